"""The streamed check: the whole-capture engine run window by window, results merged exactly.

Blocks (:mod:`wavecheck.capture.blocks`) are gathered until about ``block_edges`` edges have come;
then the window ``[t0, t1)`` (t1 the blocks' end) is checked by the *existing* vectorised code
(:func:`wavecheck.engine.decode.decode`, :func:`wavecheck.engine.intervals.rule_intervals`,
:func:`wavecheck.engine.verdicts.evaluate`) on a sub-capture holding, per mapped channel, its
edges from a context tick ``c0`` on (its level at ``c0`` as the initial level) up to ``t1``. An
interval is kept only in the window where its later event lies (``max(start, end)`` in
``[t0, t1)``), so each is counted once; a step, a sequence error, a state change, a step gap and a
pulse likewise by their tick.

The context ``c0`` of the next window is the earliest tick an interval not yet complete may start
from, per rule (kept in one place: :func:`_context`):

- the last edge of each channel (``step_high``/``step_low``, ``state_hold``, the phase state; and
  so an up/down pulse not yet ended, and an ENABLE rise still active, for ``dir_delay`` and
  ``enable_setup``);
- the last step (``step_period``, the observed step rate; ``dir_hold`` and ``dir_setup``: the
  last active edge, DIR changes after it wait for the next one; ``dir_delay``: the last pulse
  on either line, whose end starts the next switch);
- every DIR change so far while no step came yet (``dir_setup``).

Each is needed: dropping one makes a case of tests/wavecheck/stream fail.

Everything before ``c0`` is dropped, so memory follows the window, not the capture. The
differential tests (tests/wavecheck/stream) check the figures against the whole-capture path at
every block size from one edge up.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from fractions import Fraction

import numpy as np

from wavecheck.axes import AxisMap
from wavecheck.capture.blocks import BlockSource, EdgeBlock
from wavecheck.capture.edges import NEVER, Capture, EdgeArray
from wavecheck.drives.model import ActiveEdge, Drive
from wavecheck.engine.decode import (
    StepEvents,
    active_edges,
    decode,
    in_stretches,
    phase_states,
    unknown_stretches,
)
from wavecheck.engine.interface import RoleSignal, StepInterface
from wavecheck.engine.intervals import (
    figure_of,
    planned_rules,
    rule_intervals,
    split_unknown,
)
from wavecheck.engine.plan import ambiguous_note, check_machine, resolve_resolution_ns
from wavecheck.engine.primitives import Intervals, widths
from wavecheck.engine.rates import pulse_level as generator_level
from wavecheck.engine.rates import rates_from
from wavecheck.engine.results import RuleSummary, StepSummary
from wavecheck.engine.trace import StepTrace
from wavecheck.engine.verdicts import evaluate
from wavecheck.engine.windows import PLACES_PER_RULE, WindowKeeper, wanted_places
from wavecheck.linuxcnc.config import LinuxCNCConfig
from wavecheck.report.machine import MachineReport, common_timer
from wavecheck.report.model import Report
from wavecheck.rules import Rule

__all__ = ["DEFAULT_BLOCK_EDGES", "AxisStream", "MachineStream", "NotStreamable", "check_stream"]


class NotStreamable(Exception):
    """The check cannot be streamed (the caller reads the capture whole instead)."""


#: Edges gathered before a window is checked: ~40 MB of working arrays at the peak.
DEFAULT_BLOCK_EDGES = 1 << 18
#: Step ticks kept per axis for the several-axes common-timer note.
TIMER_STEPS = 1 << 18
_EMPTY = np.zeros(0, dtype=np.int64)


@dataclass
class _Role:
    """One mapped channel's running state."""

    index: int
    sig: RoleSignal  # from the template: role, channel name, inversion
    edges: EdgeArray  # edges from the context on, not yet dropped
    level: int  # raw level before edges[0] (at the context)
    known_from: int | None = None
    xz_starts: list[int] | None = None
    xz_ends: list[int] | None = None
    parts: list[EdgeArray] = field(default_factory=list)  # edges come since the last window


class AxisStream:
    """One axis checked block by block: :meth:`feed` each block, then :meth:`finish`.

    ``template`` is :func:`wavecheck.engine.plan.run_check`'s report on the capture's skeleton (no
    edges): it resolves the mapping, step type, active edge and resolution exactly as the
    whole-capture path, and gives the parts that do not depend on the edges.
    """

    def __init__(
        self,
        template: Report,
        drive: Drive,
        *,
        pulse_level: int,
        resolution: str | Fraction | None,
        keep_violations: int = 1000,
        user_table: tuple[int, ...] | None = None,
    ) -> None:
        self.template = template
        self.drive = drive
        self.st = template.step_type
        self.edge: ActiveEdge = template.active_edge
        self.user_table = user_table
        self.level = generator_level(template.interface, self.st, pulse_level)
        skel = template.capture
        ids = {id(c.edges): c.index for c in skel.channels}
        if any(id(sig.edges) not in ids for sig in template.interface.signals.values()):
            raise NotStreamable("a mapped channel is a bit of a vector (read whole)")
        self.roles = {
            role: _Role(ids[id(sig.edges)], sig, _EMPTY, 0, None, [], [])
            for role, sig in template.interface.signals.items()
        }
        self.rules, _ = planned_rules(drive, self.st)
        tb = skel.timebase
        self.tb = tb
        res = template.resolution_ns
        self.summaries = [
            RuleSummary(
                r.id,
                None if r.check == "sequence" else figure_of(drive, r)[0],  # type: ignore[index]
                None if r.check == "sequence" else figure_of(drive, r)[1],  # type: ignore[index]
                tb,
                res,
                keep=keep_violations,
                order_by_end=r.check in ("hold", "switch"),
            )
            for r in self.rules
        ]
        self.steps = StepSummary()
        self.trace = StepTrace()  # position and step rate, thinned, for the plot
        self.gap: tuple[int, int] | None = None
        self.pulses: dict[int, int] = {}
        self.start = skel.start
        self.t0 = -(1 << 62)
        self.pending = 0
        self.held = 0  # edges kept from earlier windows as context (after the last trim)
        self.timer_ticks: list[EdgeArray] = []
        self.timer_kept = 0
        self._resolution = resolution
        self.windows = WindowKeeper(list(self.roles))
        self._seen: list[tuple[object, ...]] = []  # places_signature per rule at the last window

    # -- feeding -------------------------------------------------------------------------------
    def feed(self, block: EdgeBlock, block_edges: int) -> None:
        """Take one block; check a window when ``block_edges`` edges have gathered, and at least as
        many as the context held from earlier windows (DIR changes waiting for a step can pile
        up; each window goes over them again, so waiting for as many new edges keeps the total
        work N log N instead of N²)."""
        if block.start is not None:
            self.start = block.start
        for r in self.roles.values():
            if r.index in block.known:
                r.known_from, r.level = block.known[r.index]  # raw level (before inversion)
            e = block.edges.get(r.index)
            if e is not None and len(e):
                r.parts.append(e)
                self.pending += len(e)
            for name in ("xz_starts", "xz_ends"):
                got = getattr(block, name).get(r.index)
                if got is not None and len(got):
                    getattr(r, name).extend(got.tolist())
        if self.pending >= max(block_edges, self.held):
            self._window(block.end)

    # -- one window ----------------------------------------------------------------------------
    def _stretches(self, r: _Role) -> tuple[EdgeArray, EdgeArray]:
        """As :meth:`Channel.unknown_stretches`, with the ends not yet seen as NEVER."""
        assert r.xz_starts is not None and r.xz_ends is not None
        if r.known_from is None:
            return np.array([self.start], np.int64), np.array([NEVER], np.int64)
        starts = np.array(r.xz_starts, np.int64)
        ends = np.full(len(starts), NEVER, np.int64)
        ends[: len(r.xz_ends)] = r.xz_ends
        if r.known_from > self.start:
            starts = np.concatenate([[self.start], starts]).astype(np.int64)
            ends = np.concatenate([[r.known_from], ends]).astype(np.int64)
        return starts, ends

    def _iface(self) -> StepInterface:
        signals = {}
        for role, r in self.roles.items():
            signals[role] = replace(
                r.sig,
                initial=r.level ^ int(r.sig.inverted),
                edges=r.edges,
                known_from=self.start if r.known_from is None else r.known_from,
                unknown=self._stretches(r),
            )
        return StepInterface(self.template.capture, signals)

    def _window(self, t1: int) -> None:
        t0, self.t0, self.pending = self.t0, t1, 0
        for held in self.roles.values():
            if held.parts:
                held.edges = np.concatenate([held.edges, *held.parts])
                held.parts = []
        iface = self._iface()
        st = self.st
        steps = decode(
            iface,
            st.number,
            active_edge=self.edge,
            forward_level=self.template.forward_level,
            user_table=self.user_table,
        )
        new = steps.ticks >= t0
        self.steps.add(steps.direction[new], steps.ambiguous[steps.ambiguous >= t0])
        self.trace.add(steps.ticks[new], steps.direction[new])
        self._timer(steps.ticks[new])
        for r, summary in zip(self.rules, self.summaries, strict=True):
            if r.check == "sequence":
                self._sequence(iface, steps, t0, summary)
            else:
                self._rule(r, iface, steps, t0, summary)
        self._rates(iface, steps, t0)
        self._keep_windows(t0)
        self._trim(_context(iface, steps, self.edge, self.rules))

    def _keep_windows(self, t0: int) -> None:
        """Update the signal windows around the places the summaries name
        (:mod:`wavecheck.engine.windows`); the places only when a rule's worst places changed."""
        seen = [s.places_signature(PLACES_PER_RULE) for s in self.summaries]
        changed = seen != self._seen
        self._seen = seen
        places = wanted_places(list(self.summaries), self.tb.tick_ns) if changed else None
        held = {role: (r.edges, r.level) for role, r in self.roles.items()}
        self.windows.update(places, held, t0)

    def _rule(
        self, r: Rule, iface: StepInterface, steps: StepEvents, t0: int, s: RuleSummary
    ) -> None:
        iv = rule_intervals(r, iface, self.st, steps, self.edge, self.level)
        sel = np.maximum(iv.start, iv.end) >= t0
        iv = Intervals(iv.start[sel], iv.end[sel])
        starts, ends = unknown_stretches(iface, r.roles_for(self.st))
        left = _EMPTY
        if len(starts):
            keep, covered = split_unknown(iv, starts, ends)
            left = iv.start[~keep]
            s.covered.update(starts[covered].tolist())
            iv = Intervals(iv.start[keep], iv.end[keep])
        assert s.limit_ns is not None
        s.add(evaluate(r.id, iv, s.limit_ns, self.tb, s.resolution_ns, s.figure), left)

    def _sequence(self, iface: StepInterface, steps: StepEvents, t0: int, s: RuleSummary) -> None:
        ticks = phase_states(iface, self.st.outputs)[0]
        unknown = unknown_stretches(iface, self.st.outputs)
        if len(unknown[0]):
            ticks = ticks[~in_stretches(ticks, *unknown)]
        s.add_sequence(int(np.count_nonzero(ticks >= t0)))
        m = steps.sequence_errors >= t0
        err = steps.sequence_errors[m]
        details = [
            f"state {a} → {b}"
            for a, b in zip(
                steps.sequence_from[m].tolist(), steps.sequence_to[m].tolist(), strict=True
            )
        ]
        from wavecheck.engine.verdicts import sequence_result

        part = sequence_result(err, details, 0, self.tb, s.resolution_ns)
        s.add(part, _EMPTY)

    def _rates(self, iface: StepInterface, steps: StepEvents, t0: int) -> None:
        t = steps.ticks
        if len(t) > 1:
            k = max(int(np.searchsorted(t, t0, side="left")), 1)
            if k < len(t):
                d = t[k:] - t[k - 1 : -1]
                i = int(np.argmin(d))
                cand = (int(d[i]), int(t[k - 1 + i]))
                if self.gap is None or cand[0] < self.gap[0]:
                    self.gap = cand
        if self.st.kind == "phases" or self.edge == "both":
            return
        for role in self.st.pulse_roles:
            sig = iface.get(role)
            if sig is None:
                continue
            p = widths(sig.initial, sig.edges, self.level)
            w = p.measured[p.end >= t0]
            vals, counts = np.unique(w, return_counts=True)
            for v, c in zip(vals.tolist(), counts.tolist(), strict=True):
                self.pulses[v] = self.pulses.get(v, 0) + c

    def _timer(self, ticks: EdgeArray) -> None:
        room = TIMER_STEPS - self.timer_kept
        if room > 0 and len(ticks):
            self.timer_ticks.append(ticks[:room].copy())
            self.timer_kept += min(room, len(ticks))

    def _trim(self, c0: int) -> None:
        for role, r in self.roles.items():
            k = int(np.searchsorted(r.edges, c0, side="left"))
            if k:
                self.windows.trimmed(role, r.edges[:k])
                r.level ^= k & 1
                r.edges = r.edges[k:].copy()
        self.held = sum(len(r.edges) for r in self.roles.values())

    # -- the end ---------------------------------------------------------------------------------
    def finish(self, capture: Capture) -> Report:
        """Check the last window and return the report (``capture``: the finished skeleton)."""
        self._window(NEVER)
        iface = self._iface()
        for r, s in zip(self.rules, self.summaries, strict=True):
            if r.check != "sequence":
                starts, _ = unknown_stretches(iface, r.roles_for(self.st))
                s.close_stretches(starts)
        own = next(
            (s for s in self.summaries if s.rule == ("step_high" if self.level else "step_low")),
            None,
        )
        rates = rates_from(
            self.drive,
            self.st,
            self.edge,
            self.tb,
            level=self.level,
            pulse_verdict=None if own is None else own.verdict,
            gap=self.gap,
            pulse=_median(self.pulses),
        )
        t = self.template
        rates = replace(rates, configured=t.rates.configured)
        extra = t.notes[len(t.capture.notes) :]
        _, res_note = resolve_resolution_ns(t.capture, self._resolution)
        amb = ambiguous_note(self.steps.ambiguous_count, self.steps.ambiguous, self.tb)
        if amb:
            at = len(extra) - (1 if res_note else 0)
            extra = [*extra[:at], amb, *extra[at:]]
        iface = StepInterface(capture, dict(t.interface.signals))
        return replace(
            t,
            capture=capture,
            interface=iface,
            windows=self.windows.signals(iface.signals),
            steps=self.steps,
            trace=self.trace,
            rules=list(self.summaries),
            rates=rates,
            notes=[*capture.notes, *extra],
        )


def _median(counts: Mapping[int, int]) -> tuple[int, int] | None:
    """(longest, lower median) of lengths given as length → count; None when there is none."""
    if not counts:
        return None
    n = sum(counts.values())
    k = (n - 1) // 2
    seen = 0
    for v in sorted(counts):
        seen += counts[v]
        if seen > k:
            return max(counts), v
    raise AssertionError("unreachable")


def _context(
    iface: StepInterface, steps: StepEvents, edge: ActiveEdge, rules: Sequence[Rule]
) -> int:
    """The earliest tick the next window needs (see the module docstring), from this window's
    sub-capture."""
    anchors = [int(s.edges[-1]) for s in iface.signals.values() if len(s.edges)]
    if len(steps.ticks):
        anchors.append(int(steps.ticks[-1]))
    ids = {r.id for r in rules}
    step_sig = iface.get("step")
    if "dir_setup" in ids and step_sig is not None and iface.get("dir") is not None:
        act = active_edges(step_sig, edge)
        d = iface.signals["dir"].edges
        if len(act) == 0 and len(d):
            anchors.append(int(d[0]))  # no step yet: every DIR change waits for one
    return min(anchors) if anchors else NEVER


# -- several axes ------------------------------------------------------------------------------------
class MachineStream:
    """Every axis of one capture, fed the same blocks: the streamed
    :func:`wavecheck.engine.plan.check_machine`. ``template`` is ``check_machine`` on the skeleton."""

    def __init__(
        self,
        template: MachineReport,
        drives: Mapping[str | None, Drive],
        *,
        pulse_level: int = 1,
        resolution: str | Fraction | None = None,
        user_table: tuple[int, ...] | None = None,
        block_edges: int = DEFAULT_BLOCK_EDGES,
        keep_violations: int = 1000,
    ) -> None:
        self.template = template
        self.block_edges = max(1, block_edges)
        self.axes = [
            AxisStream(
                r,
                drives[r.axis],
                pulse_level=pulse_level,
                resolution=resolution,
                keep_violations=keep_violations,
                user_table=user_table,
            )
            for r in template.axes
        ]

    def feed(self, block: EdgeBlock) -> None:
        """Take one block (every axis)."""
        for a in self.axes:
            a.feed(block, self.block_edges)

    def flush(self, end: int) -> None:
        """Check now what has gathered up to ``end`` (the last block's end), however few edges:
        a live check's figures stay current. The results do not depend on where windows end."""
        for a in self.axes:
            if a.pending and a.pending >= a.held // 2:  # as feed: linear in what piles up
                a._window(end)

    def finish(self, capture: Capture) -> MachineReport:
        """The report of every axis (``capture``: the finished skeleton)."""
        reports = [a.finish(capture) for a in self.axes]
        notes = list(self.template.notes)
        if notes:  # the common-timer note, from each axis's first TIMER_STEPS steps
            probes = [
                replace(
                    r,
                    steps=StepEvents(
                        np.concatenate(a.timer_ticks) if a.timer_ticks else _EMPTY,
                        np.zeros(a.timer_kept, np.int8),
                        np.zeros(a.timer_kept, np.int64),
                    ),
                )
                for a, r in zip(self.axes, reports, strict=True)
            ]
            notes = [common_timer(probes)]
        return MachineReport(capture, reports, notes)


def check_stream(
    source: BlockSource,
    axes: Sequence[AxisMap],
    drives: Mapping[str | None, Drive],
    resolution: str | Fraction | None = None,
    *,
    block_edges: int = DEFAULT_BLOCK_EDGES,
    keep_violations: int = 1000,
    step_types: Mapping[str | None, int] | None = None,
    forward_levels: Mapping[str | None, int] | None = None,
    invert: Mapping[str | None, Iterable[str]] | None = None,
    active_edge: ActiveEdge | None = None,
    user_table: tuple[int, ...] | None = None,
    stepgen: LinuxCNCConfig | None = None,
    latency_ns: Fraction | None = None,
    pulse_level: int = 1,
) -> MachineReport:
    """:func:`wavecheck.engine.plan.check_machine` over ``source``'s blocks (same arguments), in
    memory that does not grow with the capture; ``keep_violations`` violations kept per rule."""
    template = check_machine(
        source.skeleton,
        axes,
        drives,
        resolution,
        step_types=step_types,
        forward_levels=forward_levels,
        invert=invert,
        active_edge=active_edge,
        user_table=user_table,
        stepgen=stepgen,
        latency_ns=latency_ns,
        pulse_level=pulse_level,
    )
    m = MachineStream(
        template,
        drives,
        pulse_level=pulse_level,
        resolution=resolution,
        user_table=user_table,
        block_edges=block_edges,
        keep_violations=keep_violations,
    )
    source.want({r.index for a in m.axes for r in a.roles.values()})
    for block in source.blocks():
        m.feed(block)
    return m.finish(source.capture())
