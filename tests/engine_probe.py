"""The tests' window into the engine: a check that also keeps every step and every interval.

The engine keeps mergeable results only (:class:`wavecheck.engine.results.RuleResult`). Tests of
the measurements themselves need every interval and its verdict, and every step: :func:`run_check`
runs the one engine (:func:`wavecheck.engine.run.check_source`) with a step collector and an
interval sink attached, and returns the report wrapped so that ``report.rule(id)`` also has
``intervals``, ``outcome``, ``measured_ticks``, ``violation_ticks``, ``indeterminate_ticks`` and
``report.steps`` also has ``ticks``, ``direction``, ``position`` and ``sequence_errors``.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from fractions import Fraction
from typing import Any

import numpy as np

from wavecheck.capture.blocks import WHOLE, MemorySource
from wavecheck.capture.edges import Capture
from wavecheck.compare import StepCollector
from wavecheck.drives.datasheet import ActiveEdge, Drive
from wavecheck.drives.library import load_drive
from wavecheck.engine.judge import FAIL, INDETERMINATE, evaluate
from wavecheck.engine.options import CheckOptions
from wavecheck.engine.outcome import Report
from wavecheck.engine.resolve import AxisPlan
from wavecheck.engine.results import RuleResult
from wavecheck.engine.run import check_source
from wavecheck.engine.sinks import StepSink
from wavecheck.linuxcnc.stepgen_config import LinuxCNCConfig
from wavecheck.rules import Rule
from wavecheck.steps.decode import StepEvents
from wavecheck.steps.mapping import AxisMap
from wavecheck.steps.primitives import Intervals
from wavecheck.units import parse_time

__all__ = ["FullReport", "FullRule", "options", "run_check"]


class _Collect:
    """Every known interval of every rule, in the order the engine hands them over."""

    def __init__(self) -> None:
        self.parts: dict[str, list[Intervals]] = {}

    def add_intervals(self, rule: Rule, intervals: Intervals) -> None:
        self.parts.setdefault(rule.id, []).append(intervals)

    def of(self, rule: str) -> Intervals:
        parts = self.parts.get(rule, [])
        if not parts:
            return Intervals.empty()
        return Intervals(
            np.concatenate([p.start for p in parts]), np.concatenate([p.end for p in parts])
        )


class FullRule:
    """A rule's result (:class:`RuleResult`) with every interval and its verdict."""

    def __init__(self, result: RuleResult, intervals: Intervals) -> None:
        self.result = result
        self.intervals = intervals
        if result.limit_ns is None:
            self.outcome = np.full(len(intervals), FAIL, dtype=np.int8)
        else:
            self.outcome = evaluate(
                result.rule, intervals, result.limit_ns, result.timebase, result.resolution_ns
            ).outcome

    def __getattr__(self, name: str) -> Any:
        return getattr(self.result, name)

    @property
    def measured_ticks(self) -> Any:
        return self.intervals.measured

    @property
    def violation_ticks(self) -> Any:
        return self.intervals.start[self.outcome == FAIL]

    @property
    def indeterminate_ticks(self) -> Any:
        return self.intervals.start[self.outcome == INDETERMINATE]


class _Steps:
    """The step counts with every step."""

    def __init__(self, report: Report, every: StepEvents) -> None:
        self.counts = report.steps
        self.every = every
        seq = report.rule("state_sequence")
        errors = [v.start_tick for v in seq.worst_violations(seq.violations)] if seq else []
        self.sequence_errors = np.array(sorted(errors), dtype=np.int64)

    def __getattr__(self, name: str) -> Any:
        if name in ("ticks", "direction", "position"):
            return getattr(self.every, name)
        return getattr(self.counts, name)


class FullReport:
    """A :class:`Report` whose rules keep every interval and whose steps keep every step."""

    def __init__(self, report: Report, steps: StepEvents, intervals: _Collect) -> None:
        self.report = report
        self.steps = _Steps(report, steps)
        self._rules = {r.rule: FullRule(r, intervals.of(r.rule)) for r in report.rules}

    def __getattr__(self, name: str) -> Any:
        return getattr(self.report, name)

    def rule(self, rule_id: str) -> FullRule | None:
        return self._rules.get(rule_id)

    def events(self) -> StepEvents:
        return self.steps.every


def options(
    drive: Drive | str,
    mapping: Mapping[str, str] | None = None,
    invert: Iterable[str] = (),
    step_type_number: int | None = None,
    resolution: str | Fraction | None = None,
    *,
    forward_level: int = 0,
    active_edge: ActiveEdge | None = None,
    user_table: tuple[int, ...] | None = None,
    stepgen: LinuxCNCConfig | None = None,
    latency_ns: Fraction | None = None,
    pulse_level: int | None = None,
    pictures: bool = False,
    block_edges: int = WHOLE,
) -> CheckOptions:
    """The options object of the old ``run_check`` arguments (one unnamed axis)."""
    return CheckOptions(
        drive={None: load_drive(drive) if isinstance(drive, str) else drive},
        axes=(AxisMap(None, dict(mapping)),) if mapping else (),
        invert=tuple(invert),
        step_type={} if step_type_number is None else {None: step_type_number},
        forward_level={None: forward_level},
        user_table=user_table,
        pulse_level=pulse_level,
        active_edge=active_edge,
        resolution=parse_time(resolution) if isinstance(resolution, str) else resolution,
        stepgen=stepgen,
        latency_ns=latency_ns,
        pictures=pictures,
        block_edges=block_edges,
    )


def run_check(
    capture: Capture,
    drive: Drive | str,
    mapping: Mapping[str, str] | None = None,
    invert: Iterable[str] = (),
    step_type_number: int | None = None,
    resolution: str | Fraction | None = None,
    *,
    source_block_edges: int = WHOLE,
    **kw: Any,
) -> FullReport:
    """Check one axis of ``capture`` with the engine, keeping every step and interval
    (``source_block_edges``: the capture cut into blocks of about that many edges)."""
    steps = StepCollector()
    intervals = _Collect()

    def step_sinks(plan: AxisPlan) -> list[StepSink]:
        return [steps]

    machine = check_source(
        MemorySource(capture, source_block_edges),
        options(drive, mapping, invert, step_type_number, resolution, **kw),
        step_sinks=step_sinks,
        interval_sinks=lambda plan: intervals,
    )
    (report,) = machine.axes
    return FullReport(report, steps.events(), intervals)


def decoded(capture: Capture, report: Report | FullReport) -> StepEvents:
    """Every step of ``capture`` as the engine's one window decodes it for ``report``'s axis
    (its mapping, inversions, step type, active edge and DIR level), sequence errors with their
    states included."""
    from wavecheck.steps.decode import decode
    from wavecheck.steps.interface import build_interface

    st = report.step_type
    iface = build_interface(capture, report.mapping, report.inverted)
    return decode(
        iface,
        st.number,
        active_edge=report.active_edge,
        forward_level=report.forward_level,
        user_table=st.states if st.number == 15 else None,
    )


def every_interval(capture: Capture, **kw: Any) -> dict[str, Intervals]:
    """Every complete, known interval of every rule of the step type, no drive: the engine as
    ``wavecheck measure`` runs it (``kw``: :func:`options`' arguments but the drive)."""
    intervals = _Collect()
    opts = options("gecko-g202", **kw)
    check_source(
        MemorySource(capture),
        CheckOptions(**{**vars_of(opts), "drive": {}}),
        interval_sinks=lambda plan: intervals,
    )
    return {rule: intervals.of(rule) for rule in intervals.parts}


def vars_of(options: CheckOptions) -> dict[str, Any]:
    """The fields of an options object, by name."""
    from dataclasses import fields

    return {f.name: getattr(options, f.name) for f in fields(options)}
