"""One axis checked window by window: the engine's core, for a whole capture as for a live stream.

Blocks (:mod:`wavecheck.capture.blocks`) are gathered until about ``block_edges`` edges have come;
then the window ``[t0, t1)`` (t1 the blocks' end) is checked by the vectorised code
(:func:`wavecheck.steps.decode.decode`, :func:`wavecheck.engine.intervals.rule_intervals`,
:func:`wavecheck.engine.judge.evaluate`) on the plan's signals holding, per mapped channel, its
edges from a context tick ``c0`` on (its level at ``c0`` as the initial level) up to ``t1``. An
interval is kept only in the window where its later event lies (``max(start, end)`` in
``[t0, t1)``), so each is counted once; a step, a sequence error, a state change, a step gap and a
pulse likewise by their tick. A capture already in memory is one block: one window.

The context ``c0`` of the next window is the earliest tick an interval not yet complete may start
from; what each rule holds back is declared in the rule table (:attr:`wavecheck.rules.Rule.holds`):

- ``edges``: the last edge of each pulse line (``step_high``/``step_low``, ``state_hold``, the
  phase state; and so an up/down pulse not yet ended, for ``dir_delay``), and of any other line
  (ENABLE, DIR) while no step has followed it (``enable_setup``);
- ``step``: the last step (``step_period``, the observed step rate; ``dir_hold`` and
  ``dir_setup``: the last active edge, DIR changes after it wait for the next one; ``dir_delay``:
  the last pulse on either line, whose end starts the next switch);
- ``unstepped_dir``: every DIR change so far while no step came yet (``dir_setup``).

Each is needed: dropping one makes a case of tests/wavecheck/engine fail. Everything before ``c0``
is dropped, so memory follows the window, not the capture.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

import numpy as np

from wavecheck.capture.blocks import EdgeBlock
from wavecheck.capture.edges import NEVER, Capture, EdgeArray
from wavecheck.engine.intervals import either_level, rule_intervals, split_unknown
from wavecheck.engine.judge import FAIL, INDETERMINATE, PASS, evaluate, sequence_result
from wavecheck.engine.outcome import Report
from wavecheck.engine.rates import rates_from
from wavecheck.engine.resolve import AxisPlan, ambiguous_note
from wavecheck.engine.results import RuleResult, StepCounts
from wavecheck.engine.sinks import IntervalSink, StepSink
from wavecheck.engine.trace import StepTrace
from wavecheck.engine.windows import PLACES_PER_RULE, WindowKeeper, wanted_places
from wavecheck.record import field, record, replace
from wavecheck.rules import Rule, width_rule
from wavecheck.steps.decode import (
    StepEvents,
    active_edges,
    decode,
    in_stretches,
    phase_states,
    touches_stretches,
    unknown_stretches,
)
from wavecheck.steps.interface import RoleSignal, StepInterface
from wavecheck.steps.primitives import Intervals, widths

if TYPE_CHECKING:
    import numpy.typing as npt

__all__ = ["AxisCheck"]

_EMPTY = np.zeros(0, dtype=np.int64)


@record
class _Role:
    """One mapped channel's running state."""

    sig: RoleSignal  # from the plan: role, channel name and index, inversion
    edges: EdgeArray  # edges from the context on, not yet dropped
    level: int  # raw level before edges[0] (at the context)
    known_from: int | None = None
    xz_starts: list[int] = field(default_factory=list)
    xz_ends: list[int] = field(default_factory=list)
    parts: list[EdgeArray] = field(default_factory=list)  # edges come since the last window


class AxisCheck:
    """One axis checked block by block: :meth:`feed` each block, then :meth:`finish`.

    Args:
        plan: the axis resolved against the capture's channels.
        skeleton: the capture's skeleton (time base; its start until a block gives one).
        keep_violations: the worst violations kept per rule.
        pictures: keep the signal windows around the worst places and a thinned step trace
            (what ``--plot``, ``--html`` and ``--gtkw`` draw).
        step_sinks: fed each window's new steps.
        interval_sink: fed each window's known intervals of every measured rule.
    """

    def __init__(
        self,
        plan: AxisPlan,
        skeleton: Capture,
        *,
        keep_violations: int,
        pictures: bool = False,
        step_sinks: Sequence[StepSink] = (),
        interval_sink: IntervalSink | None = None,
    ) -> None:
        self.plan = plan
        self.st = plan.step_type
        self.roles = {role: _Role(sig, _EMPTY, 0) for role, sig in plan.interface.signals.items()}
        self.tb = skeleton.timebase
        self.results = [
            RuleResult(
                r.id,
                plan.limits[r.id][0] if r.id in plan.limits else None,
                plan.limits[r.id][1] if r.id in plan.limits else None,
                self.tb,
                plan.resolution_ns,
                keep=keep_violations,
                order_by_end=r.listed_by_end,
                binned=pictures,
            )
            for r in plan.rules
            if r.id in plan.limits or r.check == "sequence"
        ]
        self._judged = {s.rule: s for s in self.results}
        self.steps = StepCounts()
        self.first_active: int | None = None
        """The first active edge of STEP seen (step/dir)."""
        self.unstepped_dir: int | None = None
        """The last DIR change before the first active edge (or before the end, when none)."""
        self.sequence_errors = 0
        """Phase types: moves to a state that is not a neighbour (counted with or without the
        ``state_sequence`` rule)."""
        self.trace = StepTrace() if pictures else None
        self.windows = WindowKeeper(list(self.roles)) if pictures else None
        self.sinks = [*step_sinks, *([self.trace] if self.trace is not None else [])]
        self.interval_sink = interval_sink
        self.gap: tuple[int, int] | None = None
        self.pulses: dict[int, int] = {}
        self.start = skeleton.start
        self.t0 = -(1 << 62)
        self.pending = 0
        self.held = 0  # edges kept from earlier windows as context (after the last trim)
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
            i = r.sig.index
            if i in block.known:
                r.known_from, r.level = block.known[i]  # raw level (before inversion)
            e = block.edges.get(i)
            if e is not None and len(e):
                r.parts.append(e)
                self.pending += len(e)
            got = block.xz_starts.get(i)
            if got is not None and len(got):
                r.xz_starts.extend(got.tolist())
            got = block.xz_ends.get(i)
            if got is not None and len(got):
                r.xz_ends.extend(got.tolist())
        if self.pending >= max(block_edges, self.held):
            self.window(block.end)

    def flush(self, end: int) -> None:
        """Check now what has gathered up to ``end`` (the last block's end), however few edges:
        a live check's figures stay current. The results do not depend on where windows end."""
        if self.pending and self.pending >= self.held // 2:  # as feed: linear in what piles up
            self.window(end)

    # -- one window ----------------------------------------------------------------------------
    def _stretches(self, r: _Role) -> tuple[EdgeArray, EdgeArray]:
        """As :meth:`Channel.unknown_stretches`, with the ends not yet seen as NEVER."""
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
        return StepInterface(self.plan.interface.capture, signals)

    def window(self, t1: int) -> None:
        """Check the window ``[t0, t1)`` of what has gathered (module docstring)."""
        t0, self.t0, self.pending = self.t0, t1, 0
        for held in self.roles.values():
            if held.parts:
                held.edges = np.concatenate([held.edges, *held.parts])
                held.parts = []
        iface = self._iface()
        plan = self.plan
        steps = decode(
            iface,
            self.st.number,
            active_edge=plan.active_edge,
            forward_level=plan.forward_level,
            user_table=plan.user_table,
        )
        new = steps.ticks >= t0
        ticks, direction = steps.ticks[new], steps.direction[new]
        self.steps.add(direction, steps.ambiguous[steps.ambiguous >= t0])
        lost = [
            t
            for role in self.st.pulse_roles
            if role in self.roles
            for t in self.roles[role].xz_starts
        ]
        if lost:
            self.steps.lose_from(min(lost))
        self.sequence_errors += int(np.count_nonzero(steps.sequence_errors >= t0))
        for sink in self.sinks:
            sink.add(ticks, direction)
        self._first_events(iface)
        for r in plan.rules:
            if r.check == "sequence":
                self._sequence(iface, steps, t0, self._judged[r.id])
            else:
                self._rule(r, iface, steps, t0)
        self._rates(iface, steps, t0)
        if self.windows is not None:
            self._keep_windows(t0)
        self._trim(self._context(iface, steps))

    def _first_events(self, iface: StepInterface) -> None:
        """Keep :attr:`first_active` and :attr:`unstepped_dir` up to date."""
        step, dirs = iface.get("step"), iface.get("dir")
        if step is None or dirs is None or self.first_active is not None:
            return
        act = active_edges(step, self.plan.active_edge)
        if len(act):
            self.first_active = int(act[0])
        d = dirs.edges
        if self.first_active is not None:
            d = d[d < self.first_active]
        if len(d):
            self.unstepped_dir = max(int(d[-1]), self.unstepped_dir or int(d[-1]))

    def _keep_windows(self, t0: int) -> None:
        """Update the signal windows around the places the results name
        (:mod:`wavecheck.engine.windows`); the places only when a rule's worst places changed."""
        assert self.windows is not None
        seen = [s.places_signature(PLACES_PER_RULE) for s in self.results]
        changed = seen != self._seen
        self._seen = seen
        places = wanted_places(self.results, self.tb.tick_ns) if changed else None
        held = {role: (r.edges, r.level) for role, r in self.roles.items()}
        self.windows.update(places, held, t0)

    def _rule(self, r: Rule, iface: StepInterface, steps: StepEvents, t0: int) -> None:
        plan = self.plan
        iv = rule_intervals(r, iface, self.st, steps, plan.active_edge, plan.level)
        # the end of an up/down pulse depends on its level: not stated nor seen, both are read
        # (the verdict then depends on the signal at the drive's input only, issue 33)
        long = None
        if r.ends_by_level and plan.level_open:
            other = rule_intervals(r, iface, self.st, steps, plan.active_edge, 1 - plan.level)
            iv, long, both = either_level(iv, other)
        sel = np.maximum(iv.start, iv.end) >= t0
        starts, ends = unknown_stretches(iface, r.roles_for(self.st))
        left = _EMPTY
        s = self._judged.get(r.id)
        if len(starts):
            keep, covered = split_unknown(iv, starts, ends)
            if long is not None:
                keep_long, covered_long = split_unknown(long, starts, ends)
                keep, covered = keep & keep_long, covered | covered_long
            left = iv.start[~keep & sel]
            if s is not None:
                s.covered.update(starts[covered].tolist())
            sel &= keep
        if not sel.all():
            iv = Intervals(iv.start[sel], iv.end[sel])
            if long is not None:
                long, both = Intervals(long.start[sel], long.end[sel]), both[sel]
        if self.interval_sink is not None:
            self.interval_sink.add_intervals(r, iv)
        if s is not None:
            assert s.limit_ns is not None
            judged = evaluate(r.id, iv, s.limit_ns, self.tb, s.resolution_ns)
            if long is not None:
                wide = evaluate(r.id, long, s.limit_ns, self.tb, s.resolution_ns).outcome
                judged.outcome = np.where(
                    both & (judged.outcome == PASS),
                    PASS,
                    np.where(both & (wide == FAIL), FAIL, INDETERMINATE),
                ).astype(np.int8)
            s.add(judged, left)

    def _sequence(self, iface: StepInterface, steps: StepEvents, t0: int, s: RuleResult) -> None:
        ticks = phase_states(iface, self.st.outputs)[0]
        unknown = unknown_stretches(iface, self.st.outputs)
        if len(unknown[0]):
            ticks = ticks[~in_stretches(ticks, *unknown)]
        m = steps.sequence_errors >= t0
        err = steps.sequence_errors[m]
        details = [
            f"state {a} → {b}"
            for a, b in zip(
                steps.sequence_from[m].tolist(), steps.sequence_to[m].tolist(), strict=True
            )
        ]
        s.add(sequence_result(err, details, int(np.count_nonzero(ticks >= t0))), _EMPTY)

    def _rates(self, iface: StepInterface, steps: StepEvents, t0: int) -> None:
        """The shortest step interval and the pulses, none that touches an unknown stretch of a
        step line (steps inside it are not seen; the edge ending it may be no step)."""
        t = steps.ticks
        unknown = unknown_stretches(iface, self.st.pulse_roles)
        if len(t) > 1:
            k = max(int(np.searchsorted(t, t0, side="left")), 1)
            if k < len(t):
                d = t[k:] - t[k - 1 : -1]
                if len(unknown[0]):
                    d = np.where(touches_stretches(t[k - 1 : -1], t[k:], *unknown), NEVER, d)
                i = int(np.argmin(d))
                cand = (int(d[i]), int(t[k - 1 + i]))
                if cand[0] < NEVER and (self.gap is None or cand[0] < self.gap[0]):
                    self.gap = cand
        if self.st.kind == "phases" or self.plan.active_edge == "both":
            return
        for role in self.st.pulse_roles:
            sig = iface.get(role)
            if sig is None:
                continue
            p = widths(sig.initial, sig.edges, self.plan.level)
            sel = p.end >= t0
            if len(unknown[0]):
                sel &= ~touches_stretches(p.start, p.end, *unknown)
            w = p.measured[sel]
            vals, counts = np.unique(w, return_counts=True)
            for v, c in zip(vals.tolist(), counts.tolist(), strict=True):
                self.pulses[v] = self.pulses.get(v, 0) + c

    def _context(self, iface: StepInterface, steps: StepEvents) -> int:
        """The earliest tick the next window needs (module docstring), from this window."""
        holds = {h for r in self.plan.rules for h in r.holds}
        last_step = int(steps.ticks[-1]) if len(steps.ticks) else None
        pulse = set(self.st.pulse_roles)
        # the last edge of a line that is no pulse line (DIR, ENABLE) starts an interval only
        # until a step follows it: after that it is not held (an ENABLE that rose once would
        # else hold the whole capture)
        anchors = [
            int(s.edges[-1])
            for role, s in iface.signals.items()
            if len(s.edges) and (role in pulse or last_step is None or last_step < s.edges[-1])
        ]
        if last_step is not None:
            anchors.append(last_step)
        step_sig, dir_sig = iface.get("step"), iface.get("dir")
        if "unstepped_dir" in holds and step_sig is not None and dir_sig is not None:
            if len(active_edges(step_sig, self.plan.active_edge)) == 0 and len(dir_sig.edges):
                anchors.append(int(dir_sig.edges[0]))  # no step yet: every DIR change waits
        return min(anchors) if anchors else NEVER

    def _trim(self, c0: int) -> None:
        for role, r in self.roles.items():
            k = int(np.searchsorted(r.edges, c0, side="left"))
            if k:
                if self.windows is not None:
                    self.windows.trimmed(role, r.edges[:k])
                r.level ^= k & 1
                r.edges = r.edges[k:].copy()
        self.held = sum(len(r.edges) for r in self.roles.values())

    # -- the end ---------------------------------------------------------------------------------
    def close(self) -> None:
        """Check the last window and count the unknown stretches no judged interval touched
        (before :meth:`report`): each is an unknown place of a rule when an interval of that rule
        may hide in it (:meth:`_hiding`)."""
        self.window(NEVER)
        iface = self._iface()
        for r in self.plan.rules:
            s = self._judged.get(r.id)
            if s is not None and r.check != "sequence":
                starts, ends = unknown_stretches(iface, r.roles_for(self.st))
                if len(starts):
                    s.close_stretches(starts[self._hiding(r, iface, starts, ends)])

    def _hiding(
        self, r: Rule, iface: StepInterface, starts: EdgeArray, ends: EdgeArray
    ) -> npt.NDArray[np.bool_]:
        """Which unknown stretches ``[starts, ends]`` of ``r``'s roles may hide an interval of
        ``r`` that no measured interval reveals. A setup interval starts at its reference event
        (a DIR change): a stretch of the data line (STEP) alone hides none, since the DIR
        changes around it are seen and their intervals reach across it. A hold interval ends at
        its data event: a stretch of the reference line (STEP) hides one only when a data event
        (a DIR change) follows it before any reference event (active edge) is seen; the data
        line's stretches may hide one each. Any other rule: every stretch may."""
        if r.check not in ("setup", "hold"):
            return np.ones(len(starts), dtype=np.bool_)
        ref_roles = r.event_roles(r.ref, self.st)
        data_roles = r.event_roles(r.data, self.st)
        hiding_roles = ref_roles if r.check == "setup" else data_roles
        hs, he = unknown_stretches(iface, hiding_roles)
        hide = touches_stretches(starts, ends, hs, he)
        if r.check == "hold" and self.unstepped_dir is not None:
            rs, re_ = unknown_stretches(iface, ref_roles)
            early = rs < self.unstepped_dir  # a DIR change waits after it for an active edge
            hide |= touches_stretches(starts, ends, rs[early], re_[early])
        return hide

    def report(self, capture: Capture) -> Report:
        """The report of this axis (after :meth:`close`; ``capture``: the finished skeleton)."""
        plan = self.plan
        assert plan.drive is not None, "a measured-only axis has no report"
        own_id = width_rule(plan.level)
        own = next((s for s in self.results if s.rule == own_id), None)
        rates = rates_from(
            plan.drive,
            self.st,
            plan.active_edge,
            self.tb,
            level=plan.level,
            pulse_verdict=None if own is None else own.verdict,
            gap=self.gap,
            pulse=_median(self.pulses),
        )
        rates = replace(rates, configured=plan.configured)
        notes = [*plan.found, *capture.notes, *plan.notes]
        amb = ambiguous_note(self.steps.ambiguous_count, self.steps.ambiguous, self.tb)
        if amb:
            notes.append(amb)
        if plan.resolution_note:
            notes.append(plan.resolution_note)
        iface = StepInterface(capture, dict(plan.interface.signals))
        return Report(
            capture=capture,
            drive=plan.drive,
            step_type=self.st,
            interface=iface,
            active_edge=plan.active_edge,
            forward_level=plan.forward_level,
            resolution_ns=plan.resolution_ns,
            steps=self.steps,
            rules=list(self.results),
            not_stated=plan.not_stated,
            not_applicable=plan.not_applicable,
            rates=rates,
            notes=notes,
            axis=plan.name,
            windows=None if self.windows is None else self.windows.signals(iface.signals),
            trace=self.trace,
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
