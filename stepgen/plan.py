"""The step timing calculator: LinuxCNC's StepTimingCalculator as exact arithmetic.

From a drive's datasheet figures and the PC's worst latency ``J`` this chooses ``BASE_PERIOD``
(``P``) and the four step/dir parameters of LinuxCNC's software stepgen (step type 0), and
states the maximum step rate and the margin every requirement keeps. See §9 of
``shared/reference/stepgen-linuxcnc.md`` and the "Stepper Tuning" chapter of LinuxCNC's
Integrator's manual (``docs/src/motion/tweaking-steppers.adoc``).

The interval arithmetic (``n = ceil((T + J) / P)``, which datasheet figure each parameter serves,
where the active edge lies on stepgen's pulse) is :mod:`wavecheck.linuxcnc.timing`; this module
chooses the parameters, states its assumptions and warnings. Outputs: :mod:`stepgen.plan_render`.

Everything is exact: times are :class:`~fractions.Fraction` ns, the base period an integer ns.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from fractions import Fraction

from wavecheck.drives.datasheet import Drive
from wavecheck.errors import ConfigError
from wavecheck.linuxcnc.timing import (
    PARAMS,
    PLAN_RULES,
    ActiveAt,
    Requirement,
    active_at,
    evaluate,
    period_limit_ns,
    periods_needed,
    require_figures,
    step_rate_hz,
)
from wavecheck.rules import width_rule
from wavecheck.units import exact_ns, format_time

__all__ = [
    "PARAMS",
    "PLAN_RULES",
    "Param",
    "Plan",
    "latency_guidance",
    "min_base_period_ns",
    "plan",
    "simple_base_period_ns",
]

#: LinuxCNC's Stepper Tuning advice: start at 25 µs and go down only while the PC stays responsive.
SHORT_PERIOD_NS = 25_000
#: StepConf never proposes a BASE_PERIOD above 100 µs (reference §9, [SC]).
LONG_PERIOD_NS = 100_000
#: Above this latency LinuxCNC is unusable on the PC at all (Stepper Tuning); no plan is made.
MAX_LATENCY_NS = 1_000_000
#: stepgen's timing parameters are u32 ns.
U32_MAX = 2**32 - 1


def min_base_period_ns(drive: Drive, latency_ns: Fraction | int) -> Fraction:
    """Stepper Tuning's minimum BASE_PERIOD: ``J`` + the longer step high/low requirement (ns).

    With it, steplen = stepspace = 1 period meets both pulse levels; DIR setup/hold are met by
    lengthening ``dirsetup``/``dirhold``.
    """
    require_figures(drive, ("step_high", "step_low"))
    return Fraction(latency_ns) + max(_limit(drive, "step_high"), _limit(drive, "step_low"))


def simple_base_period_ns(drive: Drive, latency_ns: Fraction | int) -> Fraction:
    """Stepper Tuning's simple BASE_PERIOD: ``J`` + the longest of the four requirements (ns).

    With it every parameter can stay at one period (LinuxCNC's default).
    """
    require_figures(drive)
    return Fraction(latency_ns) + max(_limit(drive, r) for r in PLAN_RULES)


@dataclass(frozen=True)
class Param:
    """One stepgen parameter of the plan."""

    name: str
    """``steplen``, ``stepspace``, ``dirsetup`` or ``dirhold``."""
    periods: int
    """Whole base periods."""
    ns: int
    """The value to set, ns (``periods · P``; stepgen keeps it as is)."""
    reason: str
    """Why it has this many periods (the binding requirement, or LinuxCNC's one-period minimum)."""


@dataclass(frozen=True)
class Plan:
    """A stepgen timing plan for one drive, one latency and one base period (all ns)."""

    drive: Drive
    latency_ns: Fraction
    """Worst latency ``J``."""
    latency_source: str
    """Where ``J`` came from (``"--latency 11us"``, a file and its line, ...)."""
    step_inverted: bool
    """True when the STEP output pin is inverted between stepgen and the drive."""
    active_at: ActiveAt
    """The drive's active edge is the start or the end of stepgen's pulse."""
    min_base_period_ns: Fraction
    """``J`` + longer of step high/low (exact)."""
    simple_base_period_ns: Fraction
    """``J`` + longest requirement (exact)."""
    base_period_ns: int
    """The chosen ``P``."""
    base_period_given: bool
    """False when ``P`` is the minimum rounded up to a whole µs."""
    params: Mapping[str, Param]
    requirements: tuple[Requirement, ...]
    assumptions: tuple[str, ...]
    warnings: tuple[str, ...]
    guidance: str
    """LinuxCNC's Stepper Tuning verdict on the latency figure."""

    @property
    def step_periods(self) -> int:
        """Base periods per step at the maximum rate: steplen + stepspace."""
        return self.params["steplen"].periods + self.params["stepspace"].periods

    @property
    def max_step_rate_hz(self) -> Fraction:
        """stepgen's own frequency clamp: ``1 / ((steplen + stepspace)·P)``, exact Hz."""
        return step_rate_hz(self.base_period_ns, self.step_periods)

    @property
    def min_base_period_rate_hz(self) -> Fraction:
        """Max step rate at the (whole-ns) minimum period with 1-period steplen/stepspace."""
        return step_rate_hz(math.ceil(self.min_base_period_ns), 2)

    @property
    def simple_base_period_rate_hz(self) -> Fraction:
        """Max step rate at the (whole-ns) simple period with 1-period steplen/stepspace."""
        return step_rate_hz(math.ceil(self.simple_base_period_ns), 2)

    @property
    def margins_ns(self) -> dict[str, Fraction]:
        """The smallest margin of each rule over its intervals, ns."""
        out: dict[str, Fraction] = {}
        for req in self.requirements:
            if req.rule not in out or req.margin_ns < out[req.rule]:
                out[req.rule] = req.margin_ns
        return out

    @property
    def shortest_output_ns(self) -> Fraction:
        """The shortest interval the plan guarantees on the wire (any requirement), ns."""
        return min(req.worst_ns for req in self.requirements)

    def with_params(self, **periods: int) -> dict[str, int]:
        """The plan's parameter periods with some replaced (for what-if simulations)."""
        out = {name: p.periods for name, p in self.params.items()}
        for name, n in periods.items():
            if name not in out:
                raise ConfigError(
                    f"unknown stepgen parameter {name!r} (one of {', '.join(PARAMS)})"
                )
            out[name] = n
        return out


def latency_guidance(latency_ns: Fraction | int) -> tuple[str, bool]:
    """LinuxCNC's Stepper Tuning verdict on a worst latency (ns): ``(text, is_warning)``.

    Thresholds from LinuxCNC's "Stepper Tuning" chapter: below about 15–20 µs very nice results;
    30–50 µs good results but a disappointing max step rate; 100 µs or more not a candidate for
    software stepping; over 1 ms not a candidate for LinuxCNC at all. The newer latency-test doc
    says 50–500 µs needs a hardware step generator.
    """
    j = Fraction(latency_ns)
    us = format_time(j / 10**9)
    if j <= 20_000:
        return (
            f"latency {us}: good for software stepping (LinuxCNC Stepper Tuning: below about "
            "15-20 us)",
            False,
        )
    if j < 30_000:
        return (
            f"latency {us}: between Stepper Tuning's 'very nice' (15-20 us) and 'good' (30-50 us) "
            "ranges; the max step rate will be lower",
            False,
        )
    if j <= 50_000:
        return (
            f"latency {us}: usable but the max step rate may disappoint (LinuxCNC Stepper "
            "Tuning: 30-50 us)",
            True,
        )
    if j < 100_000:
        return (
            f"latency {us}: worse than Stepper Tuning's 30-50 us 'good' range; LinuxCNC's newer "
            "latency doc says 50-500 us needs a hardware step generator",
            True,
        )
    return (
        f"latency {us}: not a candidate for software stepping (LinuxCNC Stepper Tuning: 100 us "
        "or more); "
        "use a hardware step generator",
        True,
    )


def plan(
    drive: Drive,
    latency_ns: Fraction | int,
    base_period_ns: int | Fraction | None = None,
    *,
    step_inverted: bool = False,
    latency_source: str = "",
) -> Plan:
    """Plan BASE_PERIOD and stepgen's steplen/stepspace/dirsetup/dirhold for ``drive``.

    Args:
        drive: the drive; needs step_high, step_low, dir_setup and dir_hold (ns), a single active
            edge and a step/dir interface. ``max_rate`` (Hz), when given, becomes a
            ``step_period`` requirement.
        latency_ns: worst base-thread latency ``J`` in ns (0 < J ≤ 1 ms).
        base_period_ns: the BASE_PERIOD ``P`` (whole ns, > J); default: the minimum
            (:func:`min_base_period_ns`) rounded up to a whole µs.
        step_inverted: True when the STEP pin is inverted between stepgen and the drive. The
            default False is LinuxCNC's default pin polarity and Stepper Tuning's G202 reading (a
            falling-edge drive then steps at the end of stepgen's pulse).
        latency_source: where the latency figure came from, for the report.

    Raises:
        ConfigError: incomplete drive figures, unsupported interface or edge, latency or base
            period out of range.
    """
    j = _check_latency(latency_ns)
    require_figures(drive)
    if drive.interface != "step-dir":
        raise ConfigError(
            f"drive {drive.id} has a {drive.interface} interface; stepgen plan handles "
            "step/dir drives (step type 0)"
        )
    if drive.active_edge not in ("rising", "falling"):
        raise ConfigError(
            f"drive {drive.id} steps on {drive.active_edge} edges; stepgen type 0 makes one pulse "
            "per step, so plan needs a drive that steps on one edge (rising or falling)"
        )

    min_p = min_base_period_ns(drive, j)
    simple_p = simple_base_period_ns(drive, j)
    given = base_period_ns is not None
    if base_period_ns is None:
        # the minimum rounded up to a whole µs, and longer than J (only matters if T = 0)
        period = max(math.ceil(min_p / 1000), math.floor(j / 1000) + 1) * 1000
    else:
        period = _check_period(base_period_ns, j)
    at = active_at(drive, step_inverted)
    periods, reasons = _choose_periods(drive, j, period, step_inverted)
    params: dict[str, Param] = {}
    for name in PARAMS:
        ns = periods[name] * period
        if ns > U32_MAX:
            raise ConfigError(
                f"{name} would be {ns} ns, more than stepgen's u32 parameter holds "
                "(choose a longer base period)"
            )
        params[name] = Param(name, periods[name], ns, reasons[name])
    requirements = evaluate(drive, j, period, periods, step_inverted=step_inverted)
    assert all(r.margin_ns >= 0 for r in requirements), requirements  # the plan's own invariant

    assumptions = _assumptions(drive, step_inverted, at)
    guidance, bad = latency_guidance(j)
    warnings = _warnings(drive, period, min_p, guidance if bad else None)

    return Plan(
        drive=drive,
        latency_ns=j,
        latency_source=latency_source,
        step_inverted=step_inverted,
        active_at=at,
        min_base_period_ns=min_p,
        simple_base_period_ns=simple_p,
        base_period_ns=period,
        base_period_given=given,
        params=params,
        requirements=requirements,
        assumptions=assumptions,
        warnings=tuple(warnings),
        guidance=guidance,
    )


def _choose_periods(
    drive: Drive, j: Fraction, period: int, step_inverted: bool
) -> tuple[dict[str, int], dict[str, str]]:
    """steplen, stepspace, dirsetup, dirhold in whole periods of ``period`` under latency ``j``,
    and why each has that many."""
    pulse_level = "low" if step_inverted else "high"
    active_rule = width_rule(0 if step_inverted else 1)  # stepgen's pulse at the drive
    idle_rule = width_rule(1 if step_inverted else 0)
    starts = active_at(drive, step_inverted) == "start"

    def need(rule: str) -> int:
        return periods_needed(_limit(drive, rule), j, period)

    reasons: dict[str, str] = {}

    def choose(name: str, periods: int, why: str) -> int:
        if periods <= 1:
            reasons[name] = "1 period: LinuxCNC's default; the drive needs no more"
            return 1
        reasons[name] = why
        return periods

    steplen = choose(
        "steplen",
        need(active_rule),
        f"{active_rule} (the drive's {pulse_level} time = stepgen's pulse)",
    )
    space_need = need(idle_rule)
    period_rule_ns = period_limit_ns(drive)
    period_need = periods_needed(period_rule_ns, j, period) if period_rule_ns is not None else 0
    if period_need - steplen > space_need:
        stepspace = choose(
            "stepspace",
            period_need - steplen,
            "step_period: the drive's max step rate needs (steplen + stepspace)·P − J ≥ 1/fmax",
        )
    else:
        stepspace = choose("stepspace", space_need, f"{idle_rule} (the level between pulses)")
    if starts:
        dirhold = choose(
            "dirhold",
            need("dir_hold") - steplen,
            "dir_hold, counted from the active edge = start of the pulse: (steplen + dirhold)·P − J",
        )
        dirsetup = choose(
            "dirsetup", need("dir_setup"), "dir_setup: dirsetup·P − J before the pulse"
        )
    else:
        dirhold = choose(
            "dirhold",
            need("dir_hold"),
            "dir_hold, counted from the active edge = end of the pulse: dirhold·P − J",
        )
        dirsetup = choose(
            "dirsetup",
            need("dir_setup") - steplen,
            "dir_setup, to the active edge = end of the pulse: (dirsetup + steplen)·P − J",
        )
    # Across a reversal the idle level is only dirhold + dirsetup periods (reference §2.3) and the
    # step period steplen + dirhold + dirsetup: lengthen dirsetup if either falls short.
    reversal_short = max(
        space_need - (dirhold + dirsetup), period_need - (steplen + dirhold + dirsetup)
    )
    if reversal_short > 0:
        dirsetup += reversal_short
        reasons["dirsetup"] = (
            f"{idle_rule} / step_period across a reversal: the gap there is only "
            "dirhold + dirsetup periods"
        )

    periods = {"steplen": steplen, "stepspace": stepspace, "dirsetup": dirsetup, "dirhold": dirhold}
    return periods, reasons


def _warnings(drive: Drive, period: int, min_p: Fraction, latency_warning: str | None) -> list[str]:
    """What the user should know about a plan at base period ``period`` (ns)."""
    warnings: list[str] = [] if latency_warning is None else [latency_warning]
    if period < SHORT_PERIOD_NS:
        warnings.append(
            f"BASE_PERIOD {format_time(Fraction(period, 10**9))} is below 25 us: start at 25 us or "
            "more, run LinuxCNC, and go down only while the PC stays responsive (LinuxCNC "
            "Stepper Tuning)"
        )
    if period > LONG_PERIOD_NS:
        warnings.append(
            f"BASE_PERIOD {format_time(Fraction(period, 10**9))} is above 100 us, the most StepConf "
            "proposes; the step rate will be low"
        )
    if period < min_p:
        warnings.append(
            f"BASE_PERIOD is below the minimum {exact_ns(min_p)} ns for one-period pulses: steplen or "
            "stepspace takes more than one period, lowering the max step rate"
        )
    for rule in PLAN_RULES:
        fig = drive.limits[rule]
        if fig.status not in ("datasheet",):
            warnings.append(
                f"{rule} {exact_ns(fig.value)} ns is a {fig.status} figure, not a datasheet value"
            )
    return warnings


def _assumptions(drive: Drive, step_inverted: bool, active_at: ActiveAt) -> tuple[str, ...]:
    pin = "inverted" if step_inverted else "not inverted"
    level = "low" if step_inverted else "high"
    other = "high" if step_inverted else "low"
    out = [
        f"STEP pin {pin}: stepgen's pulse (steplen) is the drive's {level} time "
        f"({width_rule(0 if step_inverted else 1)}), stepspace its {other} time.",
        f"{drive.name} steps on the {drive.active_edge} edge = the {active_at.upper()} of stepgen's "
        f"pulse, so steplen is the drive's {'t_active' if active_at == 'start' else 't_idle'}"
        + (
            " (the G202 example of LinuxCNC's Stepper Tuning chapter)."
            if active_at == "end" and not step_inverted
            else "."
        ),
    ]
    if active_at == "end":
        out.append(
            "DIR hold is measured from the active edge (datasheet); LinuxCNC's dirhold counts from "
            "the end of the pulse, which here IS the active edge: hold = dirhold·P − J; "
            "setup = (dirsetup + steplen)·P − J."
        )
    else:
        out.append(
            "DIR hold is measured from the active edge (datasheet); LinuxCNC's dirhold counts from "
            "the end of the pulse, steplen periods later: hold = (steplen + dirhold)·P − J; "
            "setup = dirsetup·P − J."
        )
    out += [
        "Every interval stepgen makes n periods long is at least n·P − J in real time "
        "(one invocation late by J, the next on time).",
        "Reversals follow LinuxCNC's hold logic (stepgen.c, make_pulses): DIR changes dirhold "
        "periods "
        "after the pulse ends, the next step comes dirsetup periods later. LinuxCNC does not "
        "always obey dirsetup (LinuxCNC issue #2332): when a reversal is requested after "
        "the hold expired, or the velocity passes through exactly 0 coming from negative (the "
        "hold freezes addval at 0), DIR can flip in the same period as the next pulse starts. No "
        "parameter prevents it; when the active edge is the END of the pulse the drive still "
        "gets steplen·P − J of setup.",
        "Values are set as whole multiples of P, so stepgen keeps them; if update-freq runs before "
        "make-pulses on the first cycle, LinuxCNC rounds them at 50 us first (stepgen.c, "
        "update_freq): "
        "they only get longer (safe) but the max step rate drops.",
    ]
    return tuple(out)


def _check_latency(latency_ns: Fraction | int) -> Fraction:
    j = Fraction(latency_ns)
    if j <= 0:
        raise ConfigError(
            f"latency {exact_ns(j)} ns must be positive (run latency-test or cyclictest and give its "
            "worst figure, e.g. --latency 11us)"
        )
    if j > MAX_LATENCY_NS:
        raise ConfigError(
            f"latency {format_time(j / 10**9)} is over 1 ms: not a candidate for LinuxCNC at all "
            "(LinuxCNC Stepper Tuning), so no stepgen plan (check the unit: a bare number of 1000 "
            "or more is ns)"
        )
    return j


def _check_period(base_period_ns: int | Fraction, j: Fraction) -> int:
    p = Fraction(base_period_ns)
    if p.denominator != 1:
        raise ConfigError(
            f"base period {float(p)} ns is not a whole number of ns (BASE_PERIOD is ns)"
        )
    if p <= 0:
        raise ConfigError(f"base period {p} ns must be positive (e.g. --base-period 25us)")
    if p <= j:
        raise ConfigError(
            f"base period {exact_ns(p)} ns is not longer than the latency {exact_ns(j)} ns: every "
            "one-period interval could vanish (choose a period above J + the longer step time)"
        )
    return int(p)


def _limit(drive: Drive, rule: str) -> Fraction:
    value = drive.limit_ns(rule)
    assert value is not None
    return value
