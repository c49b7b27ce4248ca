"""Phase outputs: a group of channels whose combined state walks one of LinuxCNC's state tables.

A group of 2..5 channels is a phase group for step type *N* when, with some order of the channels
as phase-A..E,

- every state the group is in is a state of table *N* (:data:`STATE_TABLES`), and every change
  (edges at one tick count as one change) moves to a neighbouring state of the cycle;
- it keeps going one way: at most a fifth of the changes reverse the previous one (two STEP lines
  fail here, since each pulse is a change and its undoing: for quadrature, whose neighbours are all
  one-bit changes, this is the test that matters), and it goes a cycle and a half between
  reversals on average (a state machine's nets that happen to walk a table turn back within a
  cycle: a gate-level PWM controller's did, 47 changes with 9 reversals in an 8-state table);
- the time spent in consecutive states is alike (median ratio below 3), as for a motor turning,
  unlike a pulse train's short pulses and long gaps; and so is the time spent in the states of
  one cycle (longest over shortest below 2.5 on median), unlike a handshake's (an EPP strobe
  and its nWait answer walk quadrature, their states 5.5x apart); and it runs a cycle and a half
  between pauses on average (a GPIB DAV/NDAC handshake walks one cycle a byte, then waits; the
  Y lines of sigrok-dumps' mouse sensor, 0.9 cycles a run, are not taken either).

Larger groups are tried first, among channels that pairwise change in turns (each output
changes twice a cycle, so between two changes of one the others change at most twice); a group
found is not reused. Which channel is phase-A among the
orders that fit is told by the names when they say, else the lowest channel fits first (an order
that fits reversed only flips the direction).

A walk is evidence of a motor only when it changes its rate (speeds up, slows down): a walk at
one rate is what a free-running divider's or counter's nets do (a Johnson counter's two
outputs are quadrature; so are the top bits of a Gray counter), and in bursts what a handshake
does (a strobe and its acknowledge, EPP's nDataStr and nWait, walk quadrature). Three lines walking
a three-wire table (types 3, 4) are also a brushless motor's Hall sensors. Both are kept apart
(:class:`PhaseSearch`): a phase axis only when named so.

The search is bounded by work counted: a group grows one line at a time, a partial group only
while its first changes may still walk a table, and at most :data:`BUDGET` groups are looked at
(among at most :data:`MAX_LINES` lines); a search cut short says so. 55 lines of bus data once
took 40 s (every clique of five lines tried); 100 such lines now take a fraction of a second.
"""

from __future__ import annotations

import functools
import itertools
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from wavecheck.capture.edges import Channel
from wavecheck.record import field, record
from wavecheck.roles.names import name_hint
from wavecheck.roles.periodic import timing
from wavecheck.steptypes import PHASE_NAMES, STATE_TABLES, step_type

if TYPE_CHECKING:
    import numpy.typing as npt

__all__ = ["BUDGET", "PhaseGroup", "PhaseSearch", "find_phase_groups"]

_MAX_REVERSALS = 0.2
_RUN_CYCLES = 1.5  # a motor's walk goes this many cycles between reversals, on average
_CYCLE_SPREAD = 2.5  # the longest state of a cycle over its shortest, on median, stays below
_MAX_DWELL_RATIO = 3.0
_PREFIX = 512  # changes checked first, for every order and table, before the full check


@record(frozen=True)
class PhaseGroup:
    """Channels found to be one axis's phase outputs.

    Attributes:
        step_type: LinuxCNC step type number (2..14) whose table the states walk.
        channels: the channels in phase order (``channels[0]`` is phase-A).
        changes: number of state changes.
        reversals: changes that undo the previous one.
        times: tick of each change (for "is there motion while ENABLE is off").
        named: True when the names gave the phase order.
    """

    step_type: int
    channels: tuple[Channel, ...]
    changes: int
    reversals: int
    times: npt.NDArray[np.int64]
    named: bool

    @property
    def roles(self) -> tuple[str, ...]:
        """``phase-A`` … in channel order."""
        return PHASE_NAMES[: len(self.channels)]

    def evidence(self) -> str:
        """Why these channels are phase outputs, in words."""
        st = step_type(self.step_type)
        return (
            f"{len(self.channels)} channels whose every change moves the combined state to a "
            f"neighbour in LinuxCNC's {st.name} table (step type {self.step_type}, states "
            f"{','.join(map(str, st.states))}): {self.changes:,} changes, "
            f"{self.reversals:,} reversals"
        )


def _states(chans: Sequence[Channel]) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.int64], int]:
    """(change ticks, state after each change, initial state); bit i is ``chans[i]``."""
    times = np.concatenate([c.edges for c in chans])
    bits = np.concatenate(
        [np.full(len(c.edges), 1 << i, dtype=np.int64) for i, c in enumerate(chans)]
    )
    order = np.argsort(times, kind="stable")
    times, bits = times[order], bits[order]
    first = np.flatnonzero(np.r_[True, times[1:] != times[:-1]])
    flips = np.bitwise_xor.reduceat(bits, first) if len(bits) else bits
    initial = sum(c.initial << i for i, c in enumerate(chans))
    states = initial ^ np.bitwise_xor.accumulate(flips)
    return times[first], states, initial


def _walk(pos: npt.NDArray[np.int64], cycle: int) -> tuple[bool, int]:
    """(every step moves to a neighbour, number of reversals) for cycle positions ``pos``."""
    if (pos < 0).any():
        return False, 0
    step = np.diff(pos) % cycle
    if not bool(np.all((step == 1) | (step == cycle - 1))):
        return False, 0
    direction = step == 1
    return True, int(np.count_nonzero(direction[1:] != direction[:-1]))


@functools.lru_cache(maxsize=32)
def _luts(number: int, m: int) -> tuple[tuple[tuple[int, ...], ...], npt.NDArray[np.int64]]:
    """Every order of ``m`` channels as phase bits, and for each a table: group state → position
    in the cycle of table ``number`` (-1 for a state not in it)."""
    table = STATE_TABLES[number][1]
    orders = tuple(itertools.permutations(range(m)))
    luts = np.full((len(orders), 1 << m), -1, dtype=np.int64)
    for i, order in enumerate(orders):
        for value in range(1 << m):
            table_value = sum(((value >> k) & 1) << order[k] for k in range(m))
            if table_value in table:
                luts[i, value] = table.index(table_value)
    return orders, luts


def _fit(
    chans: Sequence[Channel], number: int, seq: npt.NDArray[np.int64], min_cycles: int = 2
) -> tuple[tuple[int, ...], int] | None:
    """(order, reversals) of the preferred channel order in which the group states ``seq``
    (initial state first) walk table ``number``, or None. ``order[k]`` is the phase bit that
    ``chans[k]`` drives; fewer than ``min_cycles`` cycles of changes are no evidence."""
    cycle = len(STATE_TABLES[number][1])
    changes = len(seq) - 1
    if changes < min_cycles * cycle:
        return None
    orders, luts = _luts(number, len(chans))
    head = luts[:, seq[:_PREFIX]]
    steps = np.diff(head, axis=1) % cycle
    alive = np.flatnonzero(
        (head >= 0).all(axis=1) & ((steps == 1) | (steps == cycle - 1)).all(axis=1)
    )
    fits: list[tuple[int, int, tuple[int, ...], int]] = []
    for i in alive:
        ok, rev = _walk(luts[i][seq], cycle)
        if not ok or rev > _MAX_REVERSALS * changes:
            continue
        order = orders[i]
        named = sum(
            1 for k, c in enumerate(chans) if PHASE_NAMES[order[k]] in name_hint(c.name).roles
        )
        fits.append((-named, int(i), order, rev))
    if not fits:
        return None
    fits.sort()
    return fits[0][2], fits[0][3]


def _steady(times: npt.NDArray[np.int64]) -> bool:
    """Consecutive dwell times alike (median ratio below the limit)."""
    dwell = np.diff(times).astype(np.float64)
    if len(dwell) < 2:
        return True
    a, b = dwell[:-1], dwell[1:]
    ratio = np.maximum(a, b) / np.maximum(np.minimum(a, b), 1.0)
    return float(np.median(ratio)) <= _MAX_DWELL_RATIO


_WINDOW = 1024  # changes of the pool's lines (together) in which partial groups are judged
_POPCOUNT = np.array([bin(v).count("1") for v in range(32)], dtype=np.int64)


class _Window:
    """The levels of every line of a pool after each of the pool's first :data:`_WINDOW`
    change times, so that a group's states there are a few vector operations."""

    def __init__(self, pool: Sequence[Channel]) -> None:
        times = np.unique(np.concatenate([c.edges[:_WINDOW] for c in pool]))[:_WINDOW]
        self.times = times
        self.row = {c.index: k for k, c in enumerate(pool)}
        n = np.stack([np.searchsorted(c.edges, times, side="right") for c in pool])
        self.level = (np.array([[c.initial] for c in pool]) ^ (n & 1)).astype(np.uint8)
        before = np.concatenate([np.zeros((len(pool), 1), np.int64), n[:, :-1]], axis=1)
        self.moved = n != before  # the line changes at that time
        self.initial = np.array([c.initial for c in pool], dtype=np.int64)

    def walk(self, group: Sequence[Channel]) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.int64]]:
        """(change times, states: initial state first) of ``group`` in the window."""
        rows = [self.row[c.index] for c in group]
        weights = np.left_shift(1, np.arange(len(rows), dtype=np.uint8)).astype(np.uint8)
        state = weights @ self.level[rows] if len(rows) else np.zeros(len(self.times), np.uint8)
        moved = self.moved[rows].any(axis=0)
        initial = int(weights.astype(np.int64) @ self.initial[rows])
        return self.times[moved], np.r_[initial, state[moved].astype(np.int64)]


def _may_walk(seq: npt.NDArray[np.int64], longest: int) -> bool:
    """Whether group states ``seq`` may be (part of) a walk of a table of at most ``longest``
    states: no change flips three lines or more, and no more states than that are seen. Both
    hold for any subset of a group's outputs in any stretch of time, so a partial group failing
    here is never grown."""
    if len(seq) > 1 and int(_POPCOUNT[np.bitwise_xor(seq[1:], seq[:-1])].max()) > 2:
        return False
    return int(np.count_nonzero(np.bincount(seq, minlength=32))) <= longest


@record
class PhaseSearch:
    """What :func:`find_phase_groups` found, and what it cost.

    Attributes:
        groups: phase groups with evidence of a motor (they reverse, pause or change rate).
        steady: groups that walk a table at one rate, never speeding up or slowing down (in
            bursts or not): a free-running divider or counter (a Johnson counter's
            outputs are quadrature) or a handshake (strobe and acknowledge walk quadrature) as
            much as a motor at one constant speed; the waveform cannot tell.
        commutation: three-line groups walking a three-wire table (types 3 and 4): a brushless
            motor's Hall sensors or commutation lines walk the same states.
        named_other: groups with a line named after another function (``nWait``, ``ACK``: a
            handshake's lines walk quadrature).
        looked: partial and whole groups looked at (the work done; at most :data:`BUDGET`).
        cut_short: the search stopped at :data:`BUDGET`; lines not grouped may still be phases.
    """

    groups: list[PhaseGroup] = field(default_factory=list)
    steady: list[PhaseGroup] = field(default_factory=list)
    commutation: list[PhaseGroup] = field(default_factory=list)
    named_other: list[PhaseGroup] = field(default_factory=list)
    looked: int = 0
    cut_short: bool = False

    @property
    def all_groups(self) -> list[PhaseGroup]:
        """Every group whose states walk a table, established as a motor's or not."""
        return [*self.groups, *self.steady, *self.commutation, *self.named_other]


#: Most groups (partial or whole) one search looks at: each costs a few ``numpy`` passes over
#: :data:`_WINDOW` times (tens of µs), so a capture of hundreds of lines that pairwise change in
#: turns (a data bus, a gate-level dump) is searched in well under a second.
BUDGET = 2000
_THREE_WIRE = frozenset({3, 4})  # also the states of Hall sensors and BLDC commutation


class _Budget(Exception):
    pass


def _alike(times: npt.NDArray[np.int64], cycle: int) -> bool:
    """Whether the states of one cycle last alike: over every ``cycle`` consecutive dwells
    without a pause among them, the longest over the shortest is below :data:`_CYCLE_SPREAD`
    on median. A motor's steps at one speed last alike (sigrok-dumps' mouse sensor: 1.3-1.6,
    LinuxCNC's stepgen: 1.0); a handshake's strobe and answer do not (EPP: 5.5)."""
    dwell = np.diff(times).astype(np.float64)
    if len(dwell) < cycle:
        return True
    windows = np.lib.stride_tricks.sliding_window_view(dwell, cycle)
    longest, shortest = windows.max(axis=1), windows.min(axis=1)
    run = longest < 3 * float(np.median(dwell))  # no pause inside
    if not run.any():
        return True
    return float(np.median(longest[run] / np.maximum(shortest[run], 1.0))) < _CYCLE_SPREAD


def _per_run(times: npt.NDArray[np.int64]) -> float:
    """Changes per run between pauses (a change 3x later than the shorter of its neighbours),
    on average."""
    if len(times) < 3:
        return float(len(times))
    t = timing(times, np.zeros(len(times), np.int64), 0)
    return (t.periods - t.pauses) / (t.pauses + 1)


def _one_rate(times: npt.NDArray[np.int64], cycle: int, resolution: int) -> bool:
    """Cycles at one rate that never speeds up or slows down, with or without pauses (a divider
    of a clock, a handshake's bursts): judged on the time of every ``cycle``-th change, since
    the states of a cycle need not last alike."""
    per_cycle = times[::cycle]
    if len(per_cycle) < 4:
        return False
    return timing(per_cycle, np.zeros(len(per_cycle), np.int64), resolution).one_rate


def _pairs(
    pool: Sequence[Channel], window: _Window
) -> tuple[dict[int, set[int]], set[tuple[int, int]]]:
    """(line → lines it may share a phase group with, pairs that never change at one time in
    the window). Two outputs of one group change about as often, and between two changes of one
    the other changes at most twice (each output changes twice a cycle), but where the walk
    turns back (at most a fifth of the changes); judged in the window, for all pairs at once."""
    n = np.array([len(c.edges) for c in pool], dtype=np.int64)
    alike = np.maximum.outer(n, n) <= 2 * np.minimum.outer(n, n) + 4
    moved = window.moved
    seen = np.cumsum(moved, axis=1)  # changes of each line up to each time
    turns = np.ones((len(pool), len(pool)), dtype=bool)
    for x in range(len(pool)):
        at = np.flatnonzero(moved[x])
        if len(at) < 3:
            continue
        between = np.diff(seen[:, at], axis=1)  # changes of every line between x's changes
        turns[x] &= np.count_nonzero(between > 2, axis=1) <= _MAX_REVERSALS * len(at)
    together = moved.astype(np.float32) @ moved.T.astype(np.float32)
    ok = alike & turns & turns.T
    np.fill_diagonal(ok, False)
    fits = {
        c.index: {pool[int(j)].index for j in np.flatnonzero(ok[i])} for i, c in enumerate(pool)
    }
    apart = {
        (pool[int(i)].index, pool[int(j)].index)
        for i, j in zip(*np.nonzero(ok & (together == 0)), strict=True)
    }
    return fits, apart


#: Most lines searched for phase groups (a gate-level dump may toggle thousands of nets).
MAX_LINES = 512


def find_phase_groups(
    channels: Sequence[Channel], resolution: int = 0, budget: int = BUDGET
) -> PhaseSearch:
    """Disjoint phase groups among ``channels`` (each with at least 8 edges), largest first.

    A group is grown one channel at a time among channels that pairwise change in turns, and a
    partial group is grown only while its first changes may still walk a table
    (:func:`_may_walk`); each size of group gets an equal share of ``budget`` groups looked at,
    and at most :data:`MAX_LINES` lines are searched (:attr:`PhaseSearch.cut_short` says when
    either cut the search). ``resolution`` (ticks) is the capture's, for telling one rate.
    """
    pool = [c for c in channels if len(c.edges) >= 8]
    out = PhaseSearch()
    if len(pool) > MAX_LINES:
        pool, out.cut_short = pool[:MAX_LINES], True
    if len(pool) < 2:
        return out
    window = _Window(pool)
    fits, apart = _pairs(pool, window)
    used: set[int] = set()
    by_size: dict[int, list[int]] = {}
    for number, (_, table) in STATE_TABLES.items():
        by_size.setdefault(max(table).bit_length(), []).append(number)
    longest = {m: max(len(STATE_TABLES[n][1]) for n in numbers) for m, numbers in by_size.items()}
    # lines with similar numbers of changes first: a group's outputs change alike
    pool = sorted((c for c in pool if fits[c.index]), key=lambda c: (len(c.edges), c.index))
    verdicts: dict[tuple[int, ...], bool] = {}
    share = budget // len(by_size)
    spent = {"this size": 0}

    def look() -> None:
        if spent["this size"] >= share:
            raise _Budget
        spent["this size"] += 1
        out.looked += 1

    def may_walk(group: list[Channel], m: int) -> bool:
        key = (m, *(c.index for c in group))
        if key not in verdicts:
            look()
            verdicts[key] = _may_walk(window.walk(group)[1], longest[m])
        return verdicts[key]

    def whole(group: list[Channel], m: int) -> PhaseGroup | None:
        look()
        h_times, h_seq = window.walk(group)
        if not _may_walk(h_seq, longest[m]) or not _steady(h_times[:_PREFIX]):
            return None
        h_seq = h_seq[: _PREFIX + 1]
        if not any(_fit(group, number, h_seq, 0) is not None for number in by_size[m]):
            return None
        times, states, initial = _states(group)
        seq = np.r_[initial, states]
        if not _steady(times):
            return None
        for number in by_size[m]:
            fit = _fit(group, number, seq)
            if fit is None:
                continue
            order, rev = fit
            cycle = len(STATE_TABLES[number][1])
            if len(states) < _RUN_CYCLES * cycle * (rev + 1):
                continue  # turns back before a cycle and a half on average: no motor's moves
            if not _alike(times, cycle):
                continue  # the states of a cycle last unalike: a handshake's strobe and answer
            if _per_run(times) < _RUN_CYCLES * cycle:
                continue  # a cycle or so at a time between pauses: a handshake per byte
            ordered = tuple(group[k] for k in sorted(range(m), key=lambda k: order[k]))
            named = all(PHASE_NAMES[k] in name_hint(c.name).roles for k, c in enumerate(ordered))
            return PhaseGroup(number, ordered, len(states), rev, times, named)
        return None

    def grow(group: list[Channel], start: int, m: int) -> None:
        if len(group) == m:
            g = whole(group, m)
            if g is None:
                return
            used.update(c.index for c in group)
            if any(name_hint(c.name).other for c in g.channels):
                out.named_other.append(g)
            elif _one_rate(g.times, len(STATE_TABLES[g.step_type][1]), resolution):
                out.steady.append(g)
            elif g.step_type in _THREE_WIRE:
                out.commutation.append(g)
            else:
                out.groups.append(g)
            return
        for k in range(start, len(pool)):
            c = pool[k]
            if c.index in used or any(c.index not in fits[g.index] for g in group):
                continue
            if (
                m == 2
                and group
                and (min(group[0].index, c.index), max(group[0].index, c.index)) not in apart
            ):
                continue  # quadrature changes one line at a time
            if len(group) >= 2 and not may_walk([*group, c], m):
                continue
            grow([*group, c], k + 1, m)
            if any(g.index in used for g in group):
                return  # this partial group became a whole one

    for m in sorted(by_size, reverse=True):
        spent["this size"] = 0
        try:
            grow([], 0, m)
        except _Budget:
            out.cut_short = True
    return out
