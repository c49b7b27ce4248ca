"""Measure a capture without a drive: what a scope user reads off, per axis.

For every axis: the steps (count, directions, final position, reversals), and for every interval
kind of the rule table (:mod:`wavecheck.rules`) that applies to the axis's step type — high, low,
period, DIR setup, DIR hold, dir delay, state hold, enable setup — the count, min, max, exact mean
and percentiles, and where the extremes start; plus the instantaneous step-rate range (from the
step periods). The intervals are built by the same code as ``check``'s
(:func:`wavecheck.engine.intervals.measure_intervals`), so the shortest interval here is the
shortest ``check`` judges; there is no limit and no verdict.

Every figure is in exact ticks of the capture's :class:`~wavecheck.timebase.Timebase`; the true
interval lies within ± the resolution T (one sample period of a sampled capture; 0 for a
simulator VCD, or ``--resolution``), which :attr:`Measurement.resolution_ns` states.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from fractions import Fraction

import numpy as np

from wavecheck.capture.edges import Capture, EdgeArray
from wavecheck.drives.model import ActiveEdge
from wavecheck.engine.decode import StepEvents, decode
from wavecheck.engine.interface import StepInterface, build_interface, mapped_channel_names
from wavecheck.engine.intervals import measure_intervals
from wavecheck.engine.plan import auto_map, resolve_resolution_ns
from wavecheck.engine.primitives import Intervals
from wavecheck.engine.rates import pulse_level as generator_pulse_level
from wavecheck.errors import UsageError
from wavecheck.linuxcnc.steptypes import StepType, step_type
from wavecheck.rules import Rule, applicable
from wavecheck.timebase import Timebase

__all__ = [
    "PERCENTILES",
    "AxisMeasurement",
    "AxisSpec",
    "IntervalStats",
    "Measurement",
    "default_type",
    "interval_stats",
    "measure",
    "measure_axis",
    "reversal_ticks",
]

#: Percentiles given for every interval kind (inverted CDF: each is a measured interval).
PERCENTILES: tuple[int, ...] = (1, 5, 50, 95, 99)
_GIGA = Fraction(10**9)


@dataclass(frozen=True)
class IntervalStats:
    """One interval kind of one axis, in exact ticks (``*_ns`` converts exactly).

    Attributes:
        rule: the rule id whose intervals these are (``step_high``, ``dir_setup`` …).
        what: what is measured, in words (the rule table's).
        count: how many complete, known intervals were measured.
        min_ticks, max_ticks: the shortest and longest (None when count is 0).
        min_at, max_at: the start tick of the first shortest and first longest interval.
        sum_ticks: the sum of all intervals (exact; the mean is ``sum_ticks / count``).
        percentiles: percentile → ticks (a measured interval: the inverted CDF).
        timebase: the capture's tick.
    """

    rule: str
    what: str
    count: int
    min_ticks: int | None
    min_at: int | None
    max_ticks: int | None
    max_at: int | None
    sum_ticks: int
    percentiles: dict[int, int]
    timebase: Timebase

    def ns(self, ticks: int | None) -> Fraction | None:
        """``ticks`` in exact ns (None stays None)."""
        return None if ticks is None else self.timebase.ns(ticks)

    @property
    def min_ns(self) -> Fraction | None:
        """The shortest interval, exact ns."""
        return self.ns(self.min_ticks)

    @property
    def max_ns(self) -> Fraction | None:
        """The longest interval, exact ns."""
        return self.ns(self.max_ticks)

    @property
    def mean_ns(self) -> Fraction | None:
        """The mean interval, exact ns."""
        return (
            None if not self.count else Fraction(self.sum_ticks, self.count) * self.timebase.tick_ns
        )

    def percentile_ns(self, p: int) -> Fraction | None:
        """Percentile ``p`` (one of :data:`PERCENTILES`), exact ns."""
        return self.ns(self.percentiles.get(p))


def _exact_sum(values: EdgeArray) -> int:
    """The exact sum of an int64 array (no overflow: high and low 32 bits summed apart)."""
    if len(values) == 0:
        return 0
    high = int(np.sum(values >> 32, dtype=np.int64))
    low = int(np.sum(values & 0xFFFFFFFF, dtype=np.int64))
    return (high << 32) + low


def interval_stats(rule: Rule, intervals: Intervals, timebase: Timebase) -> IntervalStats:
    """Count, extremes, exact mean and :data:`PERCENTILES` of ``intervals``."""
    w = intervals.measured
    n = len(w)
    if n == 0:
        return IntervalStats(rule.id, rule.what, 0, None, None, None, None, 0, {}, timebase)
    lo, hi = int(np.argmin(w)), int(np.argmax(w))
    ranks = {p: max(math.ceil(p * n / 100) - 1, 0) for p in PERCENTILES}
    part = np.partition(w, sorted(set(ranks.values())))
    return IntervalStats(
        rule=rule.id,
        what=rule.what,
        count=n,
        min_ticks=int(w[lo]),
        min_at=int(intervals.start[lo]),
        max_ticks=int(w[hi]),
        max_at=int(intervals.start[hi]),
        sum_ticks=_exact_sum(w),
        percentiles={p: int(part[k]) for p, k in ranks.items()},
        timebase=timebase,
    )


def reversal_ticks(steps: StepEvents) -> EdgeArray:
    """The tick of the first step after each reversal (steps of unknown direction skipped)."""
    known = steps.direction != 0
    d = steps.direction[known]
    t = steps.ticks[known]
    return t[1:][d[1:] != d[:-1]]


@dataclass
class AxisMeasurement:
    """One axis measured.

    Attributes:
        name: the axis name (None: the single unnamed axis).
        step_type: the LinuxCNC step type decoded.
        active_edge: the STEP edge that counts a step.
        forward_level: the DIR level meaning forward.
        interface: the mapped signals (levels after ``--invert``).
        steps: the decoded steps.
        intervals: rule id → every measured interval (for histograms).
        stats: the figures of each interval kind, in the rule table's order.
        reversals: tick of the first step after each reversal.
        sequence_errors: phase types: moves to a state that is not a neighbour.
    """

    name: str | None
    step_type: StepType
    active_edge: ActiveEdge
    forward_level: int
    interface: StepInterface
    steps: StepEvents
    intervals: dict[str, Intervals]
    stats: list[IntervalStats]
    reversals: EdgeArray
    sequence_errors: int = 0

    @property
    def mapping(self) -> dict[str, str]:
        """Role → channel name as mapped."""
        return {role: sig.channel for role, sig in self.interface.signals.items()}

    @property
    def inverted(self) -> tuple[str, ...]:
        """Roles that were inverted."""
        return tuple(r for r, s in self.interface.signals.items() if s.inverted)

    def stat(self, rule_id: str) -> IntervalStats:
        """The figures of interval kind ``rule_id`` (KeyError when it does not apply)."""
        for s in self.stats:
            if s.rule == rule_id:
                return s
        raise KeyError(rule_id)

    @property
    def period(self) -> IntervalStats:
        """The step periods (successive steps), from which the rates come."""
        return self.stat("step_period")

    @property
    def rate_max_hz(self) -> Fraction | None:
        """The highest instantaneous step rate (1 / the shortest step period), exact Hz."""
        p = self.period
        return None if not p.min_ticks else _GIGA / p.timebase.ns(p.min_ticks)

    @property
    def rate_min_hz(self) -> Fraction | None:
        """The lowest instantaneous step rate (1 / the longest step period), exact Hz."""
        p = self.period
        return None if not p.max_ticks else _GIGA / p.timebase.ns(p.max_ticks)

    @property
    def rate_median_hz(self) -> Fraction | None:
        """1 / the median step period, exact Hz."""
        m = self.period.percentiles.get(50)
        return None if not m else _GIGA / self.period.timebase.ns(m)


@dataclass
class Measurement:
    """Every axis of one capture, measured from the same edge arrays.

    Attributes:
        capture: the capture.
        resolution_ns: T, exact ns: every interval is within ± T of its figure (0: exact).
        axes: one measurement per axis.
        notes: how the axes were found, the resolution, anything a reader should know.
    """

    capture: Capture
    resolution_ns: Fraction
    axes: list[AxisMeasurement]
    notes: list[str] = field(default_factory=list)

    def axis(self, name: str | None) -> AxisMeasurement:
        """The measurement of axis ``name`` (KeyError when there is none)."""
        for a in self.axes:
            if a.name == name:
                return a
        raise KeyError(name)


def _leaf(name: str) -> str:
    return name.strip().rsplit(".", 1)[-1].strip().lower().replace("_", "-")


def default_type(capture: Capture, roles: Mapping[str, str]) -> int:
    """The step type of an axis without ``--type`` or a drive: 1 when it has UP/DOWN (mapped or
    a channel so named), the inferred one for phase outputs, else 0 (step/dir)."""
    named = {_leaf(c.name) for c in capture.channels}
    keys = {k.lower() for k in roles}
    if "step" in keys or ("step" in named and not keys & {"up", "down"}):
        return 0
    if keys & {"up", "down"} or "up" in named:
        return 1
    if any(k.startswith("phase-") for k in keys | named):
        from wavecheck.roles import propose

        found = [a.step_type for a in propose(capture).axes if a.step_type]
        if len(set(found)) == 1:
            return found[0]
        raise UsageError(
            f"{capture.path}: phase outputs but no step type: give --type (2 for quadrature, "
            "3-14 for the other phase tables, 15 with --user-step-type)"
        )
    return 0


def measure_axis(
    capture: Capture,
    mapping: Mapping[str, str] | None = None,
    invert: Iterable[str] = (),
    step_type_number: int | None = None,
    *,
    active_edge: ActiveEdge = "rising",
    forward_level: int = 0,
    user_table: tuple[int, ...] | None = None,
    pulse_level: int = 1,
    axis: str | None = None,
) -> AxisMeasurement:
    """Decode one axis and measure every interval kind of its step type (no drive, no limits).

    Args:
        capture: the capture (edges in ticks).
        mapping: role → channel name or index; roles missing are mapped by channel name
            (:func:`wavecheck.engine.plan.auto_map`).
        invert: roles to invert.
        step_type_number: LinuxCNC step type 0–15 (default: :func:`default_type`).
        active_edge: the STEP (UP/DOWN) edge that counts a step.
        forward_level: the DIR level (0/1) meaning forward.
        user_table: state table for step type 15.
        pulse_level: the level of the generator's pulses at its output (1 high; only
            ``dir_delay`` depends on it).
        axis: the axis name in a run of several axes.

    Raises:
        WavecheckError: an unknown channel or role, a bad step type.
    """
    explicit = dict(mapping or {})
    number = default_type(capture, explicit) if step_type_number is None else step_type_number
    st = step_type(number, user_table)
    full_map = auto_map(capture, st, mapped_channel_names(capture, explicit))
    full_map.update(explicit)
    iface = build_interface(capture, full_map, invert)
    for role in st.pulse_roles:
        iface.require(role)
    if pulse_level not in (0, 1):
        raise UsageError(f"pulse level must be 0 (low) or 1 (high), got {pulse_level!r}")
    steps = decode(
        iface,
        st.number,
        active_edge=active_edge,
        forward_level=forward_level,
        user_table=user_table,
    )
    level = generator_pulse_level(iface, st, pulse_level)
    tb = capture.timebase
    intervals: dict[str, Intervals] = {}
    stats: list[IntervalStats] = []
    for r in applicable(st.kind):
        if r.check == "sequence":
            continue
        iv = measure_intervals(r, iface, st, steps, active_edge, level)
        intervals[r.id] = iv
        stats.append(interval_stats(r, iv, tb))
    return AxisMeasurement(
        name=axis,
        step_type=st,
        active_edge=active_edge,
        forward_level=forward_level,
        interface=iface,
        steps=steps,
        intervals=intervals,
        stats=stats,
        reversals=reversal_ticks(steps),
        sequence_errors=int(len(steps.sequence_errors)),
    )


@dataclass(frozen=True)
class AxisSpec:
    """One axis to measure: name, role → channel, roles to invert, step type, DIR forward level."""

    name: str | None
    mapping: Mapping[str, str]
    invert: Sequence[str] = ()
    step_type: int | None = None
    forward_level: int = 0


def measure(
    capture: Capture,
    axes: Sequence[AxisSpec] = (AxisSpec(None, {}),),
    resolution: str | Fraction | None = None,
    *,
    active_edge: ActiveEdge = "rising",
    user_table: tuple[int, ...] | None = None,
    pulse_level: int = 1,
) -> Measurement:
    """Measure every axis of ``capture`` (see :func:`measure_axis`); ``resolution`` overrides
    the capture's T (``"500ns"`` or exact seconds)."""
    resolution_ns, note = resolve_resolution_ns(capture, resolution)
    measured = [
        measure_axis(
            capture,
            a.mapping,
            a.invert,
            a.step_type,
            active_edge=active_edge,
            forward_level=a.forward_level,
            user_table=user_table,
            pulse_level=pulse_level,
            axis=a.name,
        )
        for a in axes
    ]
    notes = list(capture.notes)
    if note:
        notes.append(note)
    for a in measured:
        label = "" if a.name is None else f"axis {a.name}: "
        if a.step_type.kind == "step-dir" and a.interface.get("dir") is None:
            notes.append(f"{label}no DIR channel mapped: directions unknown, no DIR setup/hold")
        if len(a.steps.ambiguous):
            notes.append(
                f"{label}{len(a.steps.ambiguous)} step(s) of ambiguous direction (DIR changed at "
                "the same sample as the active edge)"
            )
    return Measurement(capture, resolution_ns, measured, notes)
