"""DIR lines: which changing line is whose DIR, decided only where the waveforms prove it.

**Fit** (:func:`dir_fit`): a changing line ``d`` fits as the DIR of a pulse line ``s`` when it
changes only between pulses of ``s`` (never inside one; at the tick a pulse starts is allowed: DIR
setup 0), with at least one pulse of ``s`` after each change before the next, and pulses of ``s``
at both of its levels.

**Consistent** (:attr:`DirFit.consistent`): every change of ``d`` sits where a DIR change of ``s``
can be: at a reversal of ``s``'s rate (the period across the change is 1.25× the periods beside it:
slow-down, gap, speed-up), or before ``s``'s first / after its last pulse. A change in the middle
of ``s``'s steady running proves ``d`` is not ``s``'s DIR; that is the only thing a change can
prove. Where several pulse lines all pause, one change fits each of them equally: its distance
to their pulses is no proof (a DIR may change anywhere in the pause), so it decides nothing.

**Assignment** (:func:`assign`): a STEP has one DIR, and a changing line with a consistent fit is
taken to be the DIR of one of the lines it fits. So the DIRs are a matching of changing lines to
distinct pulse lines. ``d`` is given to ``s`` only when *every* matching that gives each changing
line a pulse line of its own gives it ``s`` (``d1`` fits only ``s1`` and ``d2`` fits ``s1`` and
``s2``: ``d2`` is ``s2``'s). Where no such matching exists (two lines fit only one STEP), the lines
involved are refused. Elsewhere, a line with two possible STEPs is refused and its STEPs listed.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

import numpy as np

from wavecheck.capture.edges import Channel
from wavecheck.record import field, record
from wavecheck.roles.features import Pulses

if TYPE_CHECKING:
    import numpy.typing as npt

__all__ = ["Assignment", "DirFit", "assign", "at_pauses", "dir_fit", "plural"]

_REVERSAL_GAP = 1.25  # a reversal's period is this much longer than the periods beside it


def plural(n: int, word: str) -> str:
    """``"1 time"``, ``"2 times"``: ``n`` with thousands separators and ``word`` in number."""
    return f"{n:,} {word}{'' if n == 1 else 's'}"


@record(frozen=True)
class DirFit:
    """How a changing channel ``d`` fits as the DIR of pulse channel ``s``."""

    d: Channel
    s: Channel
    toggles: int
    at_reversal: int  # changes where the period of s across them is longer than those beside
    outside: int  # changes before the first or after the last pulse of s
    per_level: tuple[int, int]  # pulses of s while d is low, high

    @property
    def consistent(self) -> bool:
        """Every change sits at a reversal of ``s``'s rate or outside its motion."""
        return self.at_reversal + self.outside == self.toggles

    def evidence(self) -> str:
        """What was seen, in words."""
        where = f"{self.at_reversal:,} of {self.toggles:,} at reversals of its rate"
        if self.outside:
            where += f", {self.outside:,} before its first or after its last pulse"
        lo, hi = self.per_level
        return (
            f"toggles {plural(self.toggles, 'time')}, only between pulses of {self.s.name!r} "
            f"(never inside one, and with a pulse after each change), {where}; its pulses "
            f"happen at both levels ({lo:,} low, {hi:,} high)"
        )


def at_pauses(t: npt.NDArray[np.int64], starts: npt.NDArray[np.int64]) -> tuple[int, int, int]:
    """Where the changes at ticks ``t`` sit in a train of events at ``starts`` (pulse starts,
    phase changes): (at a pause: the interval across the change is 1.25× the intervals beside
    it; before the first or after the last event; in full running: neither, with the interval
    across within twice the train's 10th percentile interval)."""
    count = len(starts)
    a = np.searchsorted(starts, t, side="left")  # the change is between events a-1 and a
    outside = int(np.count_nonzero((a == 0) | (a == count)))
    inner = a[(a > 0) & (a < count)]
    st = starts
    period = (st[inner] - st[inner - 1]).astype(np.float64)
    before = np.where(inner >= 2, st[inner - 1] - st[np.maximum(inner - 2, 0)], 0)
    after = np.where(inner + 1 < count, st[np.minimum(inner + 1, count - 1)] - st[inner], 0)
    beside = np.maximum(before, after).astype(np.float64)
    pause = period >= _REVERSAL_GAP * beside
    fast = 2 * float(np.percentile(np.diff(st), 10)) if count > 1 else 0.0
    running = int(np.count_nonzero(~pause & (period <= fast)))
    return int(np.count_nonzero(pause)), outside, running


def dir_fit(d: Channel, s: Channel, p: Pulses) -> DirFit | None:
    """The fit of ``d`` as DIR of ``s`` (pulses ``p``), or None when a hard rule fails: an edge of
    ``d`` inside a pulse of ``s``, two changes of ``d`` with no pulse between them, pulses of
    ``s`` at only one level of ``d``, or most changes (3 or more) where ``s`` runs at full rate
    without slowing down (a motor stops to reverse)."""
    t = d.edges
    n = len(t)
    if n == 0 or p.count == 0:
        return None
    i = np.searchsorted(s.edges, t, side="left")
    j = np.searchsorted(s.edges, t, side="right")
    if np.any((i == j) & ((s.initial ^ (i & 1)) == p.level)):
        return None  # a change inside a pulse
    # pulses per level interval of d (0 = before its first change); a pulse starting at the
    # tick of a change belongs after it (DIR setup 0)
    k = np.searchsorted(t, p.starts, side="right")
    counts = np.bincount(k, minlength=n + 1)
    if n >= 2 and np.any(counts[1:n] == 0):
        return None  # changed twice with no step between: not a direction
    levels = d.initial ^ (np.arange(n + 1) & 1)
    lo, hi = int(counts[levels == 0].sum()), int(counts[levels == 1].sum())
    if lo == 0 or hi == 0:
        return None
    at_rev, outside, running = at_pauses(t, p.starts)
    if running >= 3 and running > n / 2:
        return None  # it changes while s runs at full rate: no motor reverses so
    return DirFit(d, s, n, at_rev, outside, (lo, hi))


@record
class Assignment:
    """The outcome of :func:`assign`.

    Attributes:
        chosen: STEP channel index → the fit of its DIR.
        undecided: DIR channel index → the fits still possible (each is in some matching).
        crowded: groups of DIR channel indices that cannot all have a STEP of their own.
    """

    chosen: dict[int, DirFit] = field(default_factory=dict)
    undecided: dict[int, list[DirFit]] = field(default_factory=dict)
    crowded: list[tuple[int, ...]] = field(default_factory=list)


def _matching(
    graph: Mapping[int, Sequence[int]], lines: Sequence[int], fixed: tuple[int, int] | None = None
) -> dict[int, int]:
    """A maximum matching of ``lines`` to their neighbours in ``graph`` (augmenting paths), line →
    STEP, with the edge ``fixed`` in it when given."""
    owner: dict[int, int] = {}  # STEP -> line
    if fixed is not None:
        owner[fixed[1]] = fixed[0]

    def augment(d: int, seen: set[int]) -> bool:
        for s in graph[d]:
            if s in seen or (fixed is not None and s == fixed[1]):
                continue
            seen.add(s)
            if s not in owner or augment(owner[s], seen):
                owner[s] = d
                return True
        return False

    for d in lines:
        if fixed is None or d != fixed[0]:
            augment(d, set())
    return {d: s for s, d in owner.items()}


def _components(graph: Mapping[int, Sequence[int]]) -> list[list[int]]:
    """The changing lines grouped by shared STEP candidates (connected components)."""
    parent = {d: d for d in graph}

    def root(x: int) -> int:
        while parent[x] != x:
            parent[x] = parent[parent[x]]
            x = parent[x]
        return x

    first: dict[int, int] = {}
    for d, steps in graph.items():
        for s in steps:
            if s in first:
                parent[root(d)] = root(first[s])
            else:
                first[s] = d
    groups: dict[int, list[int]] = {}
    for d in graph:
        groups.setdefault(root(d), []).append(d)
    return list(groups.values())


def assign(cands: Mapping[int, Sequence[DirFit]]) -> Assignment:
    """Give DIRs to STEPs where every matching agrees (see the module docstring).

    ``cands``: DIR channel index → its consistent fits (at least one each).
    """
    graph = {d: [f.s.index for f in fits] for d, fits in cands.items()}
    fit_of = {(d, f.s.index): f for d, fits in cands.items() for f in fits}
    out = Assignment()
    for lines in _components(graph):
        full = _matching(graph, lines)
        if len(full) < len(lines):
            out.crowded.append(tuple(sorted(lines)))
            continue
        for d in lines:
            possible = [
                s for s in graph[d] if len(_matching(graph, lines, fixed=(d, s))) == len(lines)
            ]
            if len(possible) == 1:
                out.chosen[possible[0]] = fit_of[(d, possible[0])]
            else:
                out.undecided[d] = [fit_of[(d, s)] for s in possible]
    return out
