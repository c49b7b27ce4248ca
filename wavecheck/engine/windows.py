"""Small windows of the mapped signals around the places a report's pictures draw.

The pictures (``--plot``, ``--gtkw``, ``--html``) read the mapped signals' edges around a few
places: each failing rule's worst violations and, when nothing fails, each rule's smallest
margin. A check that keeps pictures keeps, per axis, only those edges: a :class:`WindowKeeper`
holds a window of every mapped role around each place the summaries currently name (each rule's
:data:`PLACES_PER_RULE` worst violations and its smallest margin). A place that drops out of that
set frees its window; a window opened before its later part arrived is completed by the later
windows of the engine. Memory: at most ``(PLACES_PER_RULE + 1)`` windows per rule, each at most
``2 · SIDE_EDGES + 1`` edges per role, plus :data:`BACK_EDGES` remembered edges per role.

A window covers ``[lo, hi]`` of :func:`place_range` (the interval with twice its width, or the
limit's, each side: the plot draws 1.6 times, GTKWave's view once) plus, per role, the last edge
before ``lo`` and the first after ``hi`` (GTKWave shows a state change with its neighbouring
edges). More than :data:`SIDE_EDGES` edges on one side of the place are cut (the nearest kept),
and the window is counted as cut (:attr:`SignalWindows.cut`).

:meth:`WindowKeeper.signals` joins the windows into one edge array per role: inside a window the
edges are the capture's; between windows the level of the window before is held, and an edge is
put one tick before the next window's first edge where the levels differ (the edges in the gap are
not kept).
"""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np

from wavecheck.capture.edges import EdgeArray
from wavecheck.engine.results import RuleResult
from wavecheck.record import field, record, replace
from wavecheck.steps.interface import RoleSignal

__all__ = [
    "BACK_EDGES",
    "PLACES_PER_RULE",
    "SIDE_EDGES",
    "SignalWindows",
    "WindowKeeper",
    "place_range",
    "wanted_places",
]

#: Worst violations per rule with a window (GTKWave's 27 markers; the plot looks at 16 overall).
PLACES_PER_RULE = 27
#: Edges per role kept at most on each side of a place.
SIDE_EDGES = 256
#: Edges per role remembered from before the engine's context (a place's part before it).
BACK_EDGES = SIDE_EDGES + 2
_EMPTY = np.zeros(0, dtype=np.int64)

Place = tuple[int, int, int]
"""(start tick, end tick, the rule's limit in whole ticks, rounded up)."""


def place_range(start: int, end: int, limit_ticks: int) -> tuple[int, int]:
    """The ticks ``[lo, hi]`` kept around an interval ``[start, end]`` whose rule's limit is
    ``limit_ticks``: twice the interval's width (or the limit's, if longer) each side."""
    width = max(abs(end - start), limit_ticks, 1)
    return min(start, end) - 2 * width, max(start, end, start + limit_ticks) + 2 * width


def wanted_places(rules: list[RuleResult], tick_ns: Fraction) -> set[Place]:
    """The places whose windows the renderers may read: each rule's :data:`PLACES_PER_RULE`
    worst violations and the interval of its smallest margin."""
    out: set[Place] = set()
    for r in rules:
        lim = 0 if r.limit_ns is None else math.ceil(r.limit_ns / tick_ns)
        if r.violations:
            out.update((v.start_tick, v.end_tick, lim) for v in r.worst_violations(PLACES_PER_RULE))
        at, measured = r.min_margin_at_tick, r.min_measured_ns
        if at is not None and measured is not None:
            out.add((at, at + int(measured / tick_ns), lim))
    return out


@record
class _Side:
    """One role's part of one window."""

    pieces: list[EdgeArray]
    level: int  # raw level before pieces[0][0] (or over the window when there is no edge)
    after: int  # edges after the place still to take (SIDE_EDGES at most)
    open: bool = True  # the first edge after hi not yet seen
    cut: bool = False


@record
class _Window:
    lo: int
    hi: int
    sides: dict[str, _Side] = field(default_factory=dict)


@record
class SignalWindows:
    """The windows a report keeps, joined (module docstring).

    Attributes:
        signals: role → its signal with the windows' edges only (as
            :attr:`wavecheck.steps.interface.StepInterface.signals`; gaps hold the level).
        count: windows kept.
        cut: windows with edges cut (more than :data:`SIDE_EDGES` on one side).
    """

    signals: dict[str, RoleSignal]
    count: int
    cut: int

    @property
    def note(self) -> str:
        """One line for a file that shows the windows (the GTKWave companion VCD)."""
        cut = f", {self.cut} cut to {SIDE_EDGES} edges a side" if self.cut else ""
        return (
            f"only {self.count} window(s) around the worst places hold edges"
            f"{cut}; between them the level is held"
        )


class WindowKeeper:
    """The windows of one axis's mapped roles, fed by the engine (module docstring)."""

    def __init__(self, roles: list[str]) -> None:
        self.roles = roles
        self.back: dict[str, EdgeArray] = {r: _EMPTY for r in roles}
        self.lost: dict[str, bool] = {r: False for r in roles}  # edges fell out of ``back``
        self.windows: dict[Place, _Window] = {}

    def update(
        self, places: set[Place] | None, held: dict[str, tuple[EdgeArray, int]], t0: int
    ) -> None:
        """After one engine window: ``held`` is role → (the edges from the context on, the raw
        level before them), of which those from ``t0`` on are new; ``places`` the places wanted
        now (None: unchanged)."""
        for w in self.windows.values():
            for role, side in w.sides.items():
                if side.open:
                    e = held[role][0]
                    self._extend(w, side, e[int(np.searchsorted(e, t0, side="left")) :])
        if places is None:
            return
        for gone in set(self.windows) - places:
            del self.windows[gone]
        for p in places - set(self.windows):
            self.windows[p] = self._open(p, held)

    def trimmed(self, role: str, edges: EdgeArray) -> None:
        """The engine drops ``edges`` of ``role`` (before its context): remember the last ones."""
        if len(edges):
            every = np.concatenate([self.back[role], edges])
            self.lost[role] |= len(every) > BACK_EDGES
            self.back[role] = every[-BACK_EDGES:]

    def _open(self, p: Place, held: dict[str, tuple[EdgeArray, int]]) -> _Window:
        lo, hi = place_range(*p)
        w = _Window(lo, hi)
        for role in self.roles:
            e, level = held[role]
            back = self.back[role]
            every = np.concatenate([back, e])
            level ^= len(back) & 1  # raw level before every[0]
            a = int(np.searchsorted(every, lo, side="left"))
            s = int(np.searchsorted(every, p[0], side="left"))
            first = max(a - 1, s - SIDE_EDGES, 0)
            cut = first > max(a - 1, 0) or (a == 0 and self.lost[role])
            side = _Side([every[first:s].copy()], level ^ (first & 1), SIDE_EDGES, cut=cut)
            w.sides[role] = side
            self._extend(w, side, every[s:])
        return w

    @staticmethod
    def _extend(w: _Window, side: _Side, e: EdgeArray) -> None:
        """Add the edges ``e`` (later than those held) to ``side``, up to the first after ``hi``."""
        if not side.open or not len(e):
            return
        stop = int(np.searchsorted(e, w.hi, side="right")) + 1
        take = min(stop, len(e), side.after)
        if take:
            side.pieces.append(e[:take].copy())
            side.after -= take
        if stop <= take:
            side.open = False
        elif side.after == 0:
            side.open, side.cut = False, True

    def signals(self, template: dict[str, RoleSignal]) -> SignalWindows:
        """The windows joined per role (``template``: the report's mapped signals)."""
        order = sorted(self.windows.values(), key=lambda w: (w.lo, w.hi))
        out = {}
        for role, sig in template.items():
            edges: list[int] = []
            level: int | None = None  # raw level after the edges so far
            initial: int | None = None
            for w in order:
                side = w.sides[role]
                e = np.concatenate(side.pieces) if side.pieces else _EMPTY
                lv = side.level
                if edges:
                    k = int(np.searchsorted(e, edges[-1], side="right"))
                    if k == len(e):  # nothing after the edges so far: it adds nothing
                        continue
                    lv ^= k & 1  # the window holds edges[-1] (a window holds every edge of its
                    e = e[k:]  # span): the level after it
                if level is None:
                    initial = level = lv
                elif lv != level:  # the gap's edges are not kept: one edge just before the window
                    at = (int(e[0]) if len(e) else w.lo) - 1
                    if not edges or at > edges[-1]:
                        edges.append(at)
                        level = lv
                edges.extend(e.tolist())
                level = lv ^ (len(e) & 1)
            raw = (sig.initial ^ int(sig.inverted)) if initial is None else initial
            out[role] = replace(
                sig, initial=raw ^ int(sig.inverted), edges=np.array(edges, dtype=np.int64)
            )
        cut = sum(any(s.cut for s in w.sides.values()) for w in self.windows.values())
        return SignalWindows(out, len(self.windows), cut)
