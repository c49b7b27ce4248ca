"""The result of checking one step interface of one capture against one drive.

A :class:`Report` keeps everything a renderer needs: the capture (channels and edges, for timing
diagrams), the decoded steps, every rule's measured intervals and per-interval verdicts (for
histograms and GTKWave markers), the violations (materialised lazily, worst first) and the
maximum step rates. Times are exact (ticks, :class:`~fractions.Fraction` ns / s / Hz).
"""

from __future__ import annotations

import heapq
from collections.abc import Sequence
from dataclasses import dataclass, field
from fractions import Fraction
from typing import TYPE_CHECKING

from wavecheck.capture.edges import Capture
from wavecheck.drives.model import ActiveEdge, Drive
from wavecheck.engine.decode import StepEvents
from wavecheck.engine.interface import RoleSignal, StepInterface
from wavecheck.engine.rates import MaxStepRates
from wavecheck.engine.verdicts import RuleOutcome, RuleResult, Violation
from wavecheck.errors import UsageError
from wavecheck.linuxcnc.steptypes import StepType
from wavecheck.verdict import Verdict, exit_code, overall_verdict

if TYPE_CHECKING:
    from wavecheck.engine.results import StepSummary
    from wavecheck.engine.trace import StepTrace
    from wavecheck.engine.windows import SignalWindows
    from wavecheck.firmware.capture import FirmwareCheck

__all__ = ["Report", "overall_verdict"]


@dataclass
class Report:
    """One check of one capture's step interface against one drive.

    Attributes:
        capture: the capture read (path, format, timebase, channels with their edge arrays).
        drive: the drive checked against.
        step_type: the LinuxCNC step type decoded.
        interface: the mapped signals (role → channel, initial level, edges, inversion).
        active_edge: the edge the drive steps on.
        forward_level: the DIR level taken as forward (type 0).
        resolution_ns: T used for the verdicts, exact ns (0 = exact).
        steps: the decoded steps (their counts only on the streamed path:
            :class:`wavecheck.engine.results.StepSummary`).
        rules: one result per evaluated rule, in report order (every interval on the
            whole-capture path; summaries on the streamed path: :class:`RuleOutcome`).
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
    steps: StepEvents | StepSummary
    rules: Sequence[RuleOutcome]
    not_stated: tuple[str, ...]
    not_applicable: tuple[str, ...]
    rates: MaxStepRates
    notes: list[str] = field(default_factory=list)
    firmware: FirmwareCheck | None = None
    """``check --firmware``: the capture against its own configuration (apart from the rules)."""
    axis: str | None = None
    """The axis name in a run of several axes (``--map x.step=…``), None for a single axis."""
    windows: SignalWindows | None = None
    """A streamed report: the mapped signals in small windows around the worst places
    (:mod:`wavecheck.engine.windows`); None on the whole-capture path."""
    trace: StepTrace | None = None
    """A streamed report: position and step rate over time, thinned to a bounded number of
    points (:mod:`wavecheck.engine.trace`), for the plot; None on the whole-capture path."""

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

    def rule(self, rule_id: str) -> RuleOutcome | None:
        """The result of ``rule_id``, or None when it was not evaluated."""
        for r in self.rules:
            if r.rule == rule_id:
                return r
        return None

    def events(self) -> StepEvents:
        """Every decoded step (the whole-capture path); a streamed report keeps only counts.

        Raises:
            UsageError: a streamed report (read the capture whole: ``--no-stream``).
        """
        if isinstance(self.steps, StepEvents):
            return self.steps
        raise UsageError(
            f"{self.capture.path}: this output needs every step; the check was streamed "
            "(give --no-stream)"
        )

    def results(self) -> list[RuleResult]:
        """Every rule's full result with every interval (the whole-capture path).

        Raises:
            UsageError: a streamed report, whose rules are summaries (``--no-stream``).
        """
        out = [r for r in self.rules if isinstance(r, RuleResult)]
        if len(out) != len(self.rules):
            raise UsageError(
                f"{self.capture.path}: this output needs every interval; the check was "
                "streamed (give --no-stream)"
            )
        return out

    @property
    def traces(self) -> dict[str, RoleSignal]:
        """The mapped signals to draw: every edge on the whole-capture path, the windows around
        the worst places on the streamed path (role → signal)."""
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
        """Violations over all rules, worst first.

        ``state_sequence`` errors come first (a decode error is worse than any margin), then
        timing violations by margin (most negative first), ties in time order. ``limit`` caps
        the list (None: all of them — may be large).
        """
        n = self.total_violations if limit is None else min(limit, self.total_violations)
        per_rule = [r.worst_violations(n) for r in self.rules if r.violations]

        def key(v: Violation) -> tuple[int, Fraction, int]:
            if v.margin_ns is None:
                return (0, Fraction(0), v.start_tick)
            return (1, v.margin_ns, v.start_tick)

        return list(heapq.merge(*per_rule, key=key))[:n]
