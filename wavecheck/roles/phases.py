"""Phase outputs: a group of channels whose combined state walks one of LinuxCNC's state tables.

A group of 2..5 channels is a phase group for step type *N* when, with some order of the channels
as phase-A..E,

- every state the group is in is a state of table *N* (:data:`STATE_TABLES`), and every change
  (edges at one tick count as one change) moves to a neighbouring state of the cycle;
- it keeps going one way: at most a fifth of the changes reverse the previous one. Two STEP lines
  fail here, since each pulse is a change and its undoing (for quadrature, whose neighbours are all
  one-bit changes, this is the test that matters);
- the time spent in consecutive states is alike (median ratio below 3), as for a motor turning,
  unlike a pulse train's short pulses and long gaps.

Larger groups are tried first, among channels that pairwise change in turns (each output
changes twice a cycle, so between two changes of one the others change at most twice); a group
found is not reused. Which channel is phase-A among the
orders that fit is told by the names when they say, else the lowest channel fits first (an order
that fits reversed only flips the direction).
"""

from __future__ import annotations

import functools
import itertools
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from wavecheck.capture.edges import Channel
from wavecheck.roles.names import name_hint
from wavecheck.steptypes import PHASE_NAMES, STATE_TABLES, step_type

__all__ = ["PhaseGroup", "find_phase_groups"]

_MAX_REVERSALS = 0.2
_MAX_DWELL_RATIO = 3.0
_PREFIX = 512  # changes checked first, for every order and table, before the full check


@dataclass(frozen=True)
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


def _interleaved(a: Channel, b: Channel) -> bool:
    """Whether ``a`` and ``b`` can be two outputs of one phase group: in every LinuxCNC table each
    output changes twice a cycle, so between two changes of one the other changes at most twice,
    but where the walk turns back (at most a fifth of the changes)."""
    if max(len(a.edges), len(b.edges)) > 2 * min(len(a.edges), len(b.edges)) + 4:
        return False
    for x, y in ((a, b), (b, a)):
        between = np.bincount(np.searchsorted(x.edges, y.edges), minlength=len(x.edges) + 1)
        if np.count_nonzero(between[1:-1] > 2) > _MAX_REVERSALS * len(x.edges):
            return False
    return True


def _cliques(pool: Sequence[Channel], m: int, fits: dict[int, set[int]]) -> list[list[Channel]]:
    """Every group of ``m`` channels of ``pool`` (in pool order) whose pairs all fit."""
    out: list[list[Channel]] = []

    def grow(group: list[Channel], start: int) -> None:
        if len(group) == m:
            out.append(list(group))
            return
        for k in range(start, len(pool)):
            c = pool[k]
            if all(c.index in fits[g.index] for g in group):
                group.append(c)
                grow(group, k + 1)
                group.pop()

    grow([], 0)
    return out


def find_phase_groups(channels: Sequence[Channel]) -> list[PhaseGroup]:
    """Disjoint phase groups among ``channels`` (each with at least 8 edges), largest first."""
    pool = [c for c in channels if len(c.edges) >= 8]
    found: list[PhaseGroup] = []
    used: set[int] = set()
    by_size: dict[int, list[int]] = {}
    for number, (_, table) in STATE_TABLES.items():
        by_size.setdefault(max(table).bit_length(), []).append(number)
    longest = {m: max(len(STATE_TABLES[n][1]) for n in numbers) for m, numbers in by_size.items()}
    fits: dict[int, set[int]] = {c.index: set() for c in pool}
    for a, b in itertools.combinations(pool, 2):
        if _interleaved(a, b):
            fits[a.index].add(b.index)
            fits[b.index].add(a.index)
    for m in sorted(by_size, reverse=True):
        for group in _cliques(pool, m, fits):
            if any(c.index in used for c in group):
                continue
            # a look at the first _PREFIX changes first: most groups fail there, cheaply
            cut = min(int(c.edges[min(len(c.edges), _PREFIX) - 1]) for c in group)
            head = [
                Channel(
                    c.name, c.index, c.initial, c.edges[: np.searchsorted(c.edges, cut, "right")]
                )
                for c in group
            ]
            h_times, h_states, h_initial = _states(head)
            h_seq = np.r_[h_initial, h_states]
            # a walk of a table of L states visits L states at most, 2 bits changing at once
            flips = np.bitwise_xor(h_seq[1:], h_seq[:-1])
            beyond_one = flips & (flips - 1)  # flips of 2 bits or more …
            if len(np.unique(h_seq)) > longest[m] or np.any(beyond_one & (beyond_one - 1)):
                continue  # … of 3 or more
            if not _steady(h_times) or not any(
                _fit(head, number, h_seq, 0) is not None for number in by_size[m]
            ):
                continue
            times, states, initial = _states(group)
            seq = np.r_[initial, states]
            if not _steady(times):
                continue
            for number in by_size[m]:
                fit = _fit(group, number, seq)
                if fit is None:
                    continue
                order, rev = fit
                ordered = tuple(group[k] for k in sorted(range(m), key=lambda k: order[k]))
                found.append(
                    PhaseGroup(
                        number,
                        ordered,
                        len(states),
                        rev,
                        times,
                        named=all(
                            PHASE_NAMES[k] in name_hint(c.name).roles for k, c in enumerate(ordered)
                        ),
                    )
                )
                used.update(c.index for c in group)
                break
    return found
