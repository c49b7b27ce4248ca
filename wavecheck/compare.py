"""A capture compared with a golden trace (e.g. made by stepgen): the model and the algorithm of
``wavecheck compare`` (:mod:`wavecheck.cli.compare` parses the options and renders the result).

Both files are checked against the same drive; then compared are

- the step count, the final position and every step's direction;
- every step's time: step *i* of the capture against step *i* of the golden, after aligning both
  on their first step (``--align first-step``, the default: a logic analyzer starts at an
  arbitrary moment) or on their own time 0 (``--align none``); a step further than
  ``--tolerance`` (default 2 µs) from its golden time is a difference;
- the two rule tables: each rule's verdict, violations and smallest margin, and the change.

Verdict: **fail** when the steps differ (count, final position, a direction, a time beyond the
tolerance) or a rule is worse than in the golden (fails where the golden does not); else
**indeterminate** when a rule is indeterminate where the golden passes; else **pass**. A golden
that itself fails a rule (a golden of a bad configuration) is matched by a capture failing it
too. :meth:`Comparison.failures` names each line that failed. Without DIR on either side (grbl
captures often have none) the final positions are unknown on both and are not compared: count,
times and rules still are; unknown on one side only is a difference.

Several axes (:func:`compare_axes`, ``--map x.step=… --map y.step=…``): each axis of the capture
is compared with the same-named axis of the golden (both read once); a
:class:`MachineComparison` holds one :class:`Comparison` per axis and the worst verdict.

Time differences are computed in float64 ns (±0.001 ns at 10⁶ s); the largest is recomputed
exactly.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from fractions import Fraction
from typing import TYPE_CHECKING, Literal

import numpy as np

from wavecheck.capture.edges import Capture, EdgeArray
from wavecheck.drives.datasheet import Drive
from wavecheck.engine import CheckOptions, MachineReport, Report, StepSink, check_capture
from wavecheck.engine.planning import AxisPlan
from wavecheck.errors import UsageError
from wavecheck.steps.decode import StepEvents
from wavecheck.steps.mapping import AxisMap
from wavecheck.units import format_ns
from wavecheck.verdict import overall_verdict

if TYPE_CHECKING:
    import numpy.typing as npt

__all__ = [
    "Align",
    "Comparison",
    "MachineComparison",
    "RuleDiff",
    "compare",
    "compare_axes",
    "compare_reports",
]

Align = Literal["first-step", "none"]
_RANK = {"pass": 0, "unchecked": 0, "indeterminate": 1, "fail": 2}


@dataclass(frozen=True)
class RuleDiff:
    """One rule in both reports (None where a report did not evaluate it)."""

    rule: str
    golden_verdict: str | None
    capture_verdict: str | None
    golden_violations: int | None
    capture_violations: int | None
    golden_margin_ns: Fraction | None
    capture_margin_ns: Fraction | None

    @property
    def delta_margin_ns(self) -> Fraction | None:
        """capture − golden smallest margin, exact ns."""
        if self.golden_margin_ns is None or self.capture_margin_ns is None:
            return None
        return self.capture_margin_ns - self.golden_margin_ns

    @property
    def change(self) -> str:
        """``"same"``, ``"worse"`` or ``"better"`` (by verdict)."""
        g = _RANK.get(self.golden_verdict or "unchecked", 0)
        c = _RANK.get(self.capture_verdict or "unchecked", 0)
        return "same" if g == c else ("worse" if c > g else "better")


@dataclass(frozen=True)
class Comparison:
    """The result of comparing a capture with a golden trace.

    Attributes:
        capture / golden: the two reports.
        capture_steps / golden_steps: every step of each.
        align: how times were aligned.
        tolerance_ns: the allowed per-step time difference, exact ns.
        compared: steps compared (the shorter count).
        max_abs_diff_ns: the largest |Δt| over compared steps, exact ns (None: nothing compared).
        max_at_step: index of that step.
        beyond_tolerance: steps whose |Δt| exceeds the tolerance.
        mean_diff_ns: mean Δt (capture − golden), ns (float).
        direction_mismatches: steps whose known directions differ.
        rules: per-rule differences.
    """

    capture: Report
    golden: Report
    capture_steps: StepEvents
    golden_steps: StepEvents
    align: Align
    tolerance_ns: Fraction
    compared: int
    max_abs_diff_ns: Fraction | None
    max_at_step: int | None
    beyond_tolerance: int
    mean_diff_ns: float | None
    direction_mismatches: int
    rules: list[RuleDiff]

    @property
    def same_count(self) -> bool:
        """Both have the same number of steps."""
        return self.capture.steps.count == self.golden.steps.count

    @property
    def position(self) -> Literal["same", "different", "unknown"]:
        """The final positions: ``unknown`` when neither is known (no DIR on either side)."""
        c, g = self.capture.steps.final_position, self.golden.steps.final_position
        if c is None and g is None:
            return "unknown"
        return "same" if c == g else "different"

    @property
    def same_position(self) -> bool:
        """Both end at the same position, or neither position is known."""
        return self.position != "different"

    def failures(self) -> list[str]:
        """Each line of the comparison that makes it fail, in words (empty: no failure)."""
        cs, gs = self.capture.steps, self.golden.steps
        out = []
        if not self.same_count:
            out.append(f"step count {cs.count} vs {gs.count}")
        if not self.same_position:
            out.append(f"final position {_pos(cs.final_position)} vs {_pos(gs.final_position)}")
        if self.direction_mismatches:
            out.append(f"{self.direction_mismatches} step direction(s) differ")
        if self.beyond_tolerance:
            out.append(f"{self.beyond_tolerance} step time(s) beyond the tolerance")
        out += [
            f"{d.rule} fails where the golden {d.golden_verdict or 'does not evaluate it'}"
            for d in self.rules
            if d.change == "worse" and d.capture_verdict == "fail"
        ]
        return out

    def said(self) -> list[str]:
        """What was compared and found, in words, for the verdict line: the failures; else that
        the capture matches the golden trace (steps and times, no rule worse), and the rules
        both fail (a golden that fails is matched by a capture that fails as it does), and any
        rule indeterminate where the golden passes."""
        failures = self.failures()
        if failures:
            return failures
        tol = format_ns(self.tolerance_ns)
        out = [
            f"matches the golden trace: {self.capture.steps.count} steps, times within ±{tol}, "
            "no rule worse"
        ]
        both = [d.rule for d in self.rules if d.golden_verdict == d.capture_verdict == "fail"]
        if both:
            out.append(f"both fail {', '.join(both)}: the capture fails as its golden does")
        out += [
            f"{d.rule} {d.capture_verdict} where the golden {d.golden_verdict or 'does not evaluate it'}"
            for d in self.rules
            if d.change == "worse"
        ]
        return out

    @property
    def verdict(self) -> str:
        """pass / fail / indeterminate (see the module docstring)."""
        if self.failures():
            return "fail"
        if any(d.change == "worse" for d in self.rules):
            return "indeterminate"
        return "pass"


def _pos(v: int | None) -> str:
    return "unknown" if v is None else f"{v:+d}"


def _times_ns(steps: StepEvents, tick_ns: Fraction, align: Align) -> np.ndarray:
    ticks = steps.ticks
    origin = int(ticks[0]) if align == "first-step" and len(ticks) else 0
    return (ticks - origin).astype(np.float64) * float(tick_ns)


def _exact_ns(steps: StepEvents, report: Report, i: int, align: Align) -> Fraction:
    ticks = steps.ticks
    origin = int(ticks[0]) if align == "first-step" and len(ticks) else 0
    return report.capture.timebase.ns(int(ticks[i]) - origin)


@dataclass(frozen=True)
class _StepTimes:
    compared: int
    max_abs_diff_ns: Fraction | None
    max_at_step: int | None
    beyond_tolerance: int
    mean_diff_ns: float | None


def _step_times(
    capture: tuple[Report, StepEvents],
    golden: tuple[Report, StepEvents],
    tolerance_ns: Fraction,
    align: Align,
) -> _StepTimes:
    """Step *i* of ``capture`` against step *i* of ``golden`` over the shorter count."""
    (cr, cs), (gr, gs) = capture, golden
    n = min(cs.count, gs.count)
    if not n:
        return _StepTimes(0, None, None, 0, None)
    d = (
        _times_ns(cs, cr.capture.timebase.tick_ns, align)[:n]
        - _times_ns(gs, gr.capture.timebase.tick_ns, align)[:n]
    )
    i = int(np.argmax(np.abs(d)))
    return _StepTimes(
        compared=n,
        max_abs_diff_ns=abs(_exact_ns(cs, cr, i, align) - _exact_ns(gs, gr, i, align)),
        max_at_step=i,
        beyond_tolerance=int(np.count_nonzero(np.abs(d) > float(tolerance_ns) + 1e-3)),
        mean_diff_ns=float(d.mean()),
    )


def _direction_mismatches(capture: StepEvents, golden: StepEvents, n: int) -> int:
    """Steps among the first ``n`` whose directions are both known and differ."""
    dc, dg = capture.direction[:n], golden.direction[:n]
    return int(np.count_nonzero((dc != 0) & (dg != 0) & (dc != dg)))


def _rule_diffs(capture: Report, golden: Report) -> list[RuleDiff]:
    """Every rule of either report, the golden's order first."""
    ids = [r.rule for r in golden.rules] + [
        r.rule for r in capture.rules if golden.rule(r.rule) is None
    ]
    diffs = []
    for rule in ids:
        g, c = golden.rule(rule), capture.rule(rule)
        diffs.append(
            RuleDiff(
                rule,
                g.verdict if g else None,
                c.verdict if c else None,
                g.violations if g else None,
                c.violations if c else None,
                g.min_margin_ns if g else None,
                c.min_margin_ns if c else None,
            )
        )
    return diffs


def compare_reports(
    capture: tuple[Report, StepEvents],
    golden: tuple[Report, StepEvents],
    tolerance_ns: Fraction,
    align: Align = "first-step",
) -> Comparison:
    """Compare two checked reports, each with its every step (see the module docstring)."""
    t = _step_times(capture, golden, tolerance_ns, align)
    return Comparison(
        capture=capture[0],
        golden=golden[0],
        capture_steps=capture[1],
        golden_steps=golden[1],
        align=align,
        tolerance_ns=tolerance_ns,
        compared=t.compared,
        max_abs_diff_ns=t.max_abs_diff_ns,
        max_at_step=t.max_at_step,
        beyond_tolerance=t.beyond_tolerance,
        mean_diff_ns=t.mean_diff_ns,
        direction_mismatches=_direction_mismatches(capture[1], golden[1], t.compared),
        rules=_rule_diffs(capture[0], golden[0]),
    )


@dataclass(frozen=True)
class MachineComparison:
    """Every axis of a capture compared with the same-named axis of a golden."""

    axes: list[Comparison]

    @property
    def several(self) -> bool:
        """Named axes (``--map x.step=…``), not the one unnamed axis of a plain comparison."""
        return len(self.axes) != 1 or self.axes[0].capture.axis is not None

    @property
    def verdict(self) -> str:
        """The worst verdict of the axes."""
        return overall_verdict(c.verdict for c in self.axes)

    def said(self) -> list[str]:
        """:meth:`Comparison.said` of each axis, prefixed ``axis NAME:`` when there are named
        axes (their failures only, when any axis fails)."""
        if not self.several:
            return self.axes[0].said()
        if self.failures():
            return self.failures()
        return ["each axis matches its golden trace"] + [
            f"axis {c.capture.axis}: {s}" for c in self.axes for s in c.said()[1:]
        ]

    def failures(self) -> list[str]:
        """Each failing line, prefixed ``axis NAME:`` when there are named axes."""
        if not self.several:
            return self.axes[0].failures()
        return [f"axis {c.capture.axis}: {f}" for c in self.axes for f in c.failures()]

    def axis(self, name: str) -> Comparison:
        """The comparison of axis ``name`` (KeyError when there is none)."""
        for c in self.axes:
            if c.capture.axis == name:
                return c
        raise KeyError(name)


def _axis_names(names: Sequence[str | None]) -> str:
    return "one unnamed axis" if list(names) == [None] else ", ".join(map(str, names))


def compare_axes(
    capture: Capture,
    golden: Capture,
    axes: Sequence[AxisMap],
    golden_axes: Sequence[AxisMap],
    drives: Mapping[str | None, Drive],
    tolerance_ns: Fraction,
    align: Align = "first-step",
    *,
    capture_invert: Mapping[str | None, Iterable[str]] | None = None,
    golden_invert: Mapping[str | None, Iterable[str]] | None = None,
    step_type: int | None = None,
    forward_level: int = 0,
) -> MachineComparison:
    """Check every axis of ``capture`` and of ``golden`` (:func:`wavecheck.engine.run.check_capture`,
    an axis against its drive in ``drives``, the same in both files) and compare each capture
    axis with the golden axis of the same name.

    Raises:
        UsageError: the two files' axes differ by name, an axis has no drive; what the engine
            raises (prefixed ``golden`` for the golden).
    """
    names = [a.name for a in axes]
    golden_names = [a.name for a in golden_axes]
    if sorted(map(str, names)) != sorted(map(str, golden_names)):
        raise UsageError(
            f"the capture's axes ({_axis_names(names)}) and the golden's "
            f"({_axis_names(golden_names)}) differ: each capture axis is compared with the golden "
            "axis of the same name (--map x.step=… for the capture, --golden-map x.step=… for "
            "the golden)"
        )
    types: dict[str | None, int] = {} if step_type is None else {None: step_type}
    checked, steps = _checked(capture, axes, drives, types, forward_level, capture_invert)
    try:
        reference, golden_steps = _checked(
            golden, golden_axes, drives, types, forward_level, golden_invert
        )
    except UsageError as err:
        raise UsageError(
            f"golden {err} (the golden's channels are mapped with --golden-map)"
        ) from None
    by_name = {r.axis: (r, s) for r, s in zip(reference.axes, golden_steps, strict=True)}
    return MachineComparison(
        [
            compare_reports((r, s), by_name[r.axis], tolerance_ns, align)
            for r, s in zip(checked.axes, steps, strict=True)
        ]
    )


class StepCollector:
    """A step sink that keeps every step (memory follows the number of steps), for the
    step-by-step comparison; the engine's tests use it as their oracle."""

    def __init__(self) -> None:
        self._ticks: list[EdgeArray] = []
        self._dirs: list[npt.NDArray[np.int8]] = []

    def add(self, ticks: EdgeArray, direction: npt.NDArray[np.int8]) -> None:
        if len(ticks):
            self._ticks.append(ticks.copy())
            self._dirs.append(direction.copy())

    def events(self) -> StepEvents:
        """The steps so far: ticks, directions and running positions."""
        ticks = np.concatenate(self._ticks) if self._ticks else np.zeros(0, dtype=np.int64)
        dirs = np.concatenate(self._dirs) if self._dirs else np.zeros(0, np.int8)
        self._ticks, self._dirs = [ticks], [dirs]
        return StepEvents(ticks, dirs, np.cumsum(dirs, dtype=np.int64))


def _checked(
    capture: Capture,
    axes: Sequence[AxisMap],
    drives: Mapping[str | None, Drive],
    types: Mapping[str | None, int],
    forward_level: int,
    invert: Mapping[str | None, Iterable[str]] | None,
) -> tuple[MachineReport, list[StepEvents]]:
    """``capture`` checked (one block) and every step of each axis."""
    collectors: list[StepCollector] = []

    def sinks(plan: AxisPlan) -> list[StepSink]:
        collectors.append(StepCollector())
        return [collectors[-1]]

    options = CheckOptions(
        drive=drives,
        axes=tuple(axes),
        invert=tuple(
            f"{axis}.{role}" if axis is not None else role
            for axis, roles in (invert or {}).items()
            for role in roles
        ),
        step_type=types,
        forward_level={None: forward_level},
    )
    machine = check_capture(capture, options, step_sinks=sinks)
    return machine, [c.events() for c in collectors]


def compare(
    capture: Capture,
    golden: Capture,
    drive: Drive,
    tolerance_ns: Fraction,
    align: Align = "first-step",
    *,
    capture_map: Mapping[str, str] | None = None,
    capture_invert: Iterable[str] = (),
    golden_map: Mapping[str, str] | None = None,
    golden_invert: Iterable[str] = (),
    step_type: int | None = None,
    forward_level: int = 0,
) -> Comparison:
    """Check ``capture`` and ``golden`` against the same ``drive`` (each with its own role mapping
    and inverted roles; the same step type and forward DIR level) and compare the two reports
    (one axis: :func:`compare_axes` for several)."""
    return compare_axes(
        capture,
        golden,
        [AxisMap(None, dict(capture_map or {}))],
        [AxisMap(None, dict(golden_map or {}))],
        {None: drive},
        tolerance_ns,
        align,
        capture_invert={None: list(capture_invert)},
        golden_invert={None: list(golden_invert)},
        step_type=step_type,
        forward_level=forward_level,
    ).axes[0]
