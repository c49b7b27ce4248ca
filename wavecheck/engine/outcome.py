"""What a check gives: one :class:`Report` per axis, one :class:`MachineReport` per capture.

A :class:`Report` keeps what every renderer reads: the capture's skeleton (channels, time base),
the mapped roles, the step counts, one mergeable :class:`~wavecheck.engine.results.RuleResult`
per rule (counts, extremes, the worst violations, a histogram), the maximum step rates and the
notes; with pictures asked for, the signal windows around the worst places and a thinned step
trace. Times are exact (ticks, :class:`~fractions.Fraction` ns / s / Hz).
"""

from __future__ import annotations

import heapq
from collections.abc import Sequence
from fractions import Fraction
from typing import Protocol

from wavecheck.capture.edges import Capture
from wavecheck.drives.datasheet import ActiveEdge, Drive
from wavecheck.engine.judge import Violation
from wavecheck.engine.rates import MaxStepRates
from wavecheck.engine.results import RuleResult, StepCounts
from wavecheck.engine.trace import StepTrace
from wavecheck.engine.windows import SignalWindows
from wavecheck.record import field, record
from wavecheck.steps.interface import RoleSignal, StepInterface
from wavecheck.steptypes import StepType
from wavecheck.verdict import Verdict, exit_code, overall_verdict

__all__ = ["MachineReport", "OwnSettingsCheck", "Report", "overall_verdict"]


class OwnSettingsCheck(Protocol):
    """A capture checked against its own generator settings (``check --firmware``:
    :class:`wavecheck.firmware.capture.FirmwareCheck`): only its verdict counts here."""

    @property
    def verdict(self) -> Verdict: ...


@record
class Report:
    """One check of one capture's step interface against one drive.

    Attributes:
        capture: the capture read (path, format, timebase, channels; no edges are kept).
        drive: the drive checked against.
        step_type: the LinuxCNC step type decoded.
        interface: the mapped roles (role → channel, inversion).
        active_edge: the edge the drive steps on.
        forward_level: the DIR level taken as forward (type 0).
        resolution_ns: T used for the verdicts, exact ns (0 = exact).
        steps: the step counts.
        rules: one result per evaluated rule, in report order.
        not_stated: rules of this step type the drive gives no limit for (not evaluated).
        not_applicable: rules the drive states that this step type has no use for.
        rates: the maximum step rates.
        notes: things the user should know (assumptions, ambiguous steps, reader notes).
    """

    capture: Capture
    drive: Drive
    step_type: StepType
    interface: StepInterface
    active_edge: ActiveEdge
    forward_level: int
    resolution_ns: Fraction
    steps: StepCounts
    rules: Sequence[RuleResult]
    not_stated: tuple[str, ...]
    not_applicable: tuple[str, ...]
    rates: MaxStepRates
    notes: list[str] = field(default_factory=list)
    firmware: OwnSettingsCheck | None = None
    """``check --firmware``: the capture against its own configuration (apart from the rules)."""
    axis: str | None = None
    """The axis name in a run of several axes (``--map x.step=…``), None for a single axis."""
    windows: SignalWindows | None = None
    """With pictures: the mapped signals in small windows around the worst places
    (:mod:`wavecheck.engine.windows`)."""
    trace: StepTrace | None = None
    """With pictures: position and step rate over time, thinned to a bounded number of points
    (:mod:`wavecheck.engine.trace`)."""

    @property
    def verdict(self) -> Verdict:
        """The overall verdict (see :func:`overall_verdict`); a capture that violates its own
        firmware configuration (``firmware``) fails too."""
        own = [self.firmware.verdict] if self.firmware is not None else []
        return overall_verdict([r.verdict for r in self.rules] + own)

    @property
    def exit_code(self) -> int:
        """0 pass, 1 a rule failed, 3 only indeterminate results (or nothing could be checked)."""
        return exit_code(self.verdict)

    def rule(self, rule_id: str) -> RuleResult | None:
        """The result of ``rule_id``, or None when it was not evaluated."""
        for r in self.rules:
            if r.rule == rule_id:
                return r
        return None

    @property
    def traces(self) -> dict[str, RoleSignal]:
        """The mapped signals to draw: the windows around the worst places (empty edge arrays
        when the check kept no pictures)."""
        return self.interface.signals if self.windows is None else self.windows.signals

    @property
    def mapping(self) -> dict[str, str]:
        """Role → channel name as mapped."""
        return {role: sig.channel for role, sig in self.interface.signals.items()}

    @property
    def inverted(self) -> tuple[str, ...]:
        """Roles that were inverted."""
        return tuple(r for r, s in self.interface.signals.items() if s.inverted)

    @property
    def total_violations(self) -> int:
        """Number of violations over all rules."""
        return sum(r.violations for r in self.rules)

    def violations(self, limit: int | None = None) -> list[Violation]:
        """Violations over all rules, worst first (at most the ones each rule kept).

        ``state_sequence`` errors come first (a decode error is worse than any margin), then
        timing violations by margin (most negative first), ties in time order. ``limit`` caps
        the list (None: every one kept).
        """
        n = self.total_violations if limit is None else min(limit, self.total_violations)
        per_rule = [r.worst_violations(n) for r in self.rules if r.violations]

        def key(v: Violation) -> tuple[int, Fraction, int]:
            if v.margin_ns is None:
                return (0, Fraction(0), v.start_tick)
            return (1, v.margin_ns, v.start_tick)

        return list(heapq.merge(*per_rule, key=key))[:n]


@record
class MachineReport:
    """Every axis of one capture, checked in one pass over one read of it."""

    capture: Capture
    axes: list[Report]
    notes: list[str] = field(default_factory=list)

    @property
    def verdict(self) -> Verdict:
        """The worst verdict of the axes."""
        return overall_verdict(r.verdict for r in self.axes)

    @property
    def exit_code(self) -> int:
        """0 pass, 1 an axis failed, 3 only indeterminate or unchecked."""
        return exit_code(self.verdict)

    @property
    def total_violations(self) -> int:
        """Violations over every axis."""
        return sum(r.total_violations for r in self.axes)

    def axis(self, name: str) -> Report:
        """The report of axis ``name`` (KeyError when there is none)."""
        for r in self.axes:
            if r.axis == name:
                return r
        raise KeyError(name)
