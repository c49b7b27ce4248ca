"""Measure a capture without a drive: what a scope user reads off, per axis.

For every axis: the steps (count, directions, final position, reversals), and for every interval
kind of the rule table (:mod:`wavecheck.rules`) that applies to the axis's step type — high, low,
period, DIR setup, DIR hold, dir delay, state hold, enable setup — the count, min, max, exact mean
and percentiles, and where the extremes start; plus the instantaneous step-rate range (from the
step periods). It is the engine's run with no drive (:mod:`wavecheck.engine`): the intervals are
the ones ``check`` judges, handed to an :class:`IntervalCounts` sink per axis, which keeps each
distinct length's count (so every percentile is exact, in memory that follows the distinct
lengths, not the capture), and the steps go to a step trace (reversals, the motion panel).

Every figure is in exact ticks of the capture's :class:`~wavecheck.timebase.Timebase`; the true
interval lies within ± the resolution T (one sample period of a sampled capture; 0 for a
simulator VCD, or ``--resolution``), which :attr:`Measurement.resolution_ns` states.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from fractions import Fraction

import numpy as np

from wavecheck.capture.blocks import BlockSource, MemorySource
from wavecheck.capture.edges import Capture, EdgeArray
from wavecheck.drives.datasheet import ActiveEdge
from wavecheck.engine import CheckOptions, StepSink, start
from wavecheck.engine.parts import StepCounts, StepTrace
from wavecheck.engine.planning import AxisPlan
from wavecheck.record import field, record
from wavecheck.rules import Rule
from wavecheck.steps.interface import StepInterface
from wavecheck.steps.primitives import Intervals
from wavecheck.steptypes import StepType
from wavecheck.timebase import Timebase

__all__ = [
    "PERCENTILES",
    "AxisMeasurement",
    "IntervalCounts",
    "IntervalStats",
    "Measurement",
    "measure",
]

#: Percentiles given for every interval kind (inverted CDF: each is a measured interval).
PERCENTILES: tuple[int, ...] = (1, 5, 50, 95, 99)
#: Reversal ticks kept per axis (the first ones; the count is exact).
REVERSALS_KEPT = 1000
_GIGA = Fraction(10**9)


@record(frozen=True)
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


class _Kind:
    """One interval kind's running figures."""

    def __init__(self, rule: Rule) -> None:
        self.rule = rule
        self.lengths: list[EdgeArray] = []  # distinct lengths, one array per merge
        self.counts: list[EdgeArray] = []
        self.pending = 0
        self.n = 0
        self.total = 0
        self.lo: tuple[int, int] | None = None  # (length, start) of the first shortest
        self.hi: tuple[int, int] | None = None  # (length, start) of the first longest

    def add(self, iv: Intervals) -> None:
        w = iv.measured
        if not len(w):
            return
        i, j = int(np.argmin(w)), int(np.argmax(w))
        if self.lo is None or int(w[i]) < self.lo[0]:
            self.lo = (int(w[i]), int(iv.start[i]))
        if self.hi is None or int(w[j]) > self.hi[0]:
            self.hi = (int(w[j]), int(iv.start[j]))
        self.n += len(w)
        self.total += _exact_sum(w)
        v, c = np.unique(w, return_counts=True)
        self.lengths.append(v)
        self.counts.append(c.astype(np.int64))
        self.pending += len(v)
        if self.pending > 1 << 16:
            self._merge()

    def _merge(self) -> None:
        if len(self.lengths) > 1:
            v = np.concatenate(self.lengths)
            c = np.concatenate(self.counts)
            u, inv = np.unique(v, return_inverse=True)
            self.lengths, self.counts = [u], [np.bincount(inv, weights=c).astype(np.int64)]
        self.pending = len(self.lengths[0]) if self.lengths else 0

    def distribution(self) -> tuple[EdgeArray, EdgeArray]:
        """(distinct lengths in ticks, increasing; how many of each)."""
        self._merge()
        if not self.lengths:
            z = np.zeros(0, dtype=np.int64)
            return z, z
        return self.lengths[0], self.counts[0]

    def stats(self, timebase: Timebase) -> IntervalStats:
        if not self.n or self.lo is None or self.hi is None:
            return IntervalStats(
                self.rule.id, self.rule.what, 0, None, None, None, None, 0, {}, timebase
            )
        v, c = self.distribution()
        cum = np.cumsum(c)
        ranks = {p: max(math.ceil(p * self.n / 100) - 1, 0) for p in PERCENTILES}
        pct = {p: int(v[int(np.searchsorted(cum, k, side="right"))]) for p, k in ranks.items()}
        return IntervalStats(
            rule=self.rule.id,
            what=self.rule.what,
            count=self.n,
            min_ticks=self.lo[0],
            min_at=self.lo[1],
            max_ticks=self.hi[0],
            max_at=self.hi[1],
            sum_ticks=self.total,
            percentiles=pct,
            timebase=timebase,
        )


class IntervalCounts:
    """An axis's interval sink (:class:`wavecheck.engine.sinks.IntervalSink`): per rule, each
    distinct length's count and the extremes, merged window by window (exact)."""

    def __init__(self, rules: Sequence[Rule]) -> None:
        self.kinds = {r.id: _Kind(r) for r in rules}

    def add_intervals(self, rule: Rule, intervals: Intervals) -> None:
        self.kinds[rule.id].add(intervals)


def _exact_sum(values: EdgeArray) -> int:
    """The exact sum of an int64 array (no overflow: high and low 32 bits summed apart)."""
    if len(values) == 0:
        return 0
    high = int(np.sum(values >> 32, dtype=np.int64))
    low = int(np.sum(values & 0xFFFFFFFF, dtype=np.int64))
    return (high << 32) + low


@record
class AxisMeasurement:
    """One axis measured.

    Attributes:
        name: the axis name (None: the single unnamed axis).
        step_type: the LinuxCNC step type decoded.
        active_edge: the STEP edge that counts a step.
        forward_level: the DIR level meaning forward.
        interface: the mapped roles (channel, inversion).
        steps: the step counts.
        stats: the figures of each interval kind, in the rule table's order.
        distributions: rule id → (distinct lengths in ticks, their counts), for histograms.
        trace: position and step rate over time (thinned when long), the reversals.
        sequence_errors: phase types: moves to a state that is not a neighbour.
    """

    name: str | None
    step_type: StepType
    active_edge: ActiveEdge
    forward_level: int
    interface: StepInterface
    steps: StepCounts
    stats: list[IntervalStats]
    distributions: dict[str, tuple[EdgeArray, EdgeArray]]
    trace: StepTrace
    sequence_errors: int = 0

    @property
    def mapping(self) -> dict[str, str]:
        """Role → channel name as mapped."""
        return {role: sig.channel for role, sig in self.interface.signals.items()}

    @property
    def inverted(self) -> tuple[str, ...]:
        """Roles that were inverted."""
        return tuple(r for r, s in self.interface.signals.items() if s.inverted)

    @property
    def reversals(self) -> int:
        """Reversals (a known direction unlike the last known one)."""
        return self.trace.reversals

    @property
    def reversal_ticks(self) -> EdgeArray:
        """The tick of the first step after each of the first :data:`REVERSALS_KEPT` reversals."""
        return self.trace.reversal_ticks

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


@record
class Measurement:
    """Every axis of one capture, measured in one pass over one read of it.

    Attributes:
        capture: the capture (its skeleton).
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


def measure(
    source: BlockSource | Capture,
    options: CheckOptions,
    *,
    step_sinks: Callable[[AxisPlan], Sequence[StepSink]] | None = None,
    settled: Callable[[int], None] | None = None,
) -> Measurement:
    """Measure every axis of ``source`` (read once) with ``options`` (no drive: its ``drive``
    is ignored); ``step_sinks`` also get each axis's steps (``--steps-csv``), ``settled`` is told
    after each block the tick before which every step was handed over.

    Raises:
        WavecheckError: an unusable mapping or option, roles that cannot be told.
    """
    from wavecheck.record import replace

    src = MemorySource(source) if isinstance(source, Capture) else source
    options = replace(options, drive={})
    counts: list[IntervalCounts] = []
    traces: list[StepTrace] = []

    def interval_sink(plan: AxisPlan) -> IntervalCounts:
        counts.append(IntervalCounts(plan.rules))
        return counts[-1]

    def sinks(plan: AxisPlan) -> list[StepSink]:
        traces.append(StepTrace(reversals_kept=REVERSALS_KEPT))
        return [traces[-1], *(step_sinks(plan) if step_sinks is not None else ())]

    machine, blocks = start(src, options, step_sinks=sinks, interval_sinks=interval_sink)
    for block in blocks:
        machine.feed(block)
        if settled is not None:
            settled(machine.settled(block.end))
    machine.close()
    capture = src.capture()
    axes = []
    notes = list(capture.notes)
    resolution_ns = capture.resolution_ns
    for a, c, trace in zip(machine.axes, counts, traces, strict=True):
        plan = a.plan
        resolution_ns = plan.resolution_ns
        tb = capture.timebase
        axes.append(
            AxisMeasurement(
                name=plan.name,
                step_type=plan.step_type,
                active_edge=plan.active_edge,
                forward_level=plan.forward_level,
                interface=plan.interface,
                steps=a.steps,
                stats=[k.stats(tb) for k in c.kinds.values()],
                distributions={r: k.distribution() for r, k in c.kinds.items()},
                trace=trace,
                sequence_errors=a.sequence_errors,
            )
        )
    plans = [a.plan for a in machine.axes]
    if plans and plans[0].found:
        notes[:0] = plans[0].found
    if plans and plans[0].resolution_note:
        notes.append(plans[0].resolution_note)
    for m in axes:
        label = "" if m.name is None else f"axis {m.name}: "
        if m.step_type.kind == "step-dir" and m.interface.get("dir") is None:
            notes.append(f"{label}no DIR channel mapped: directions unknown, no DIR setup/hold")
        if m.steps.ambiguous_count:
            notes.append(
                f"{label}{m.steps.ambiguous_count} step(s) of ambiguous direction (DIR changed "
                "at the same sample as the active edge)"
            )
    return Measurement(capture, resolution_ns, axes, notes)
