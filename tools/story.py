"""The seeds' stepper-tuning story, executable: plan → simulate under worst-case latency → check.

A development tool, not part of the installed package. ``python -m tools.story`` (``make story``)
prints it as a short report and exits 0 when every expectation holds, 1 otherwise. The numbers
the seed states are data, in ``tools/seed_numbers.toml`` (``--numbers`` names another file);
``tests/stepgen/test_story.py`` asserts the same computed values against the same file.

Each configuration is simulated with the faithful LinuxCNC stepgen model (:mod:`stepgen.simulate`)
once per rule under ``worst:J:RULE`` — the invocations that end that rule's intervals run on time,
all others ``J`` late, so every interval is ``n·P − J`` — and every trace is checked edge by edge
against the drive by the validator (:func:`wavecheck.engine.resolve.run_check`). A rule's figure is the
shortest interval over all those runs; a configuration passes when no run fails any rule.

The motion (:func:`reversal_motion`): velocity mode, servo thread = base thread, reversals at the
configuration's full step rate in one direction and 0.9 of it in the other, with segments of
slightly different lengths so the reversal request falls at every phase of the step pattern.
0.9 keeps the velocity from passing through exactly 0 going from negative to positive: there
LinuxCNC's hold logic freezes addval at 0, so DIR cannot change during the hold and flips in the
same period as the first step (reference §2.4, LinuxCNC issue #2332) whatever dirsetup is. The
cases with ``through_zero = true`` show that separately.
"""

from __future__ import annotations

import argparse
import sys
import tomllib
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np

from stepgen.lateness import RULES as WORST_RULES
from stepgen.motion import Motion
from stepgen.plan import PARAMS, Plan, min_base_period_ns, plan
from stepgen.reference import StepgenConfig
from stepgen.simulate import Trace, simulate
from wavecheck.api import check as check_report
from wavecheck.capture.edges import Capture, Channel
from wavecheck.drives.datasheet import Drive
from wavecheck.drives.library import list_drives, load_drive
from wavecheck.engine import Report
from wavecheck.rules import applicable
from wavecheck.timebase import Timebase

__all__ = [
    "NUMBERS",
    "RULES",
    "Case",
    "CaseRun",
    "Finding",
    "Outcome",
    "SeedNumbers",
    "SweepRow",
    "command_csv",
    "config_for",
    "findings",
    "library_sweep",
    "load_numbers",
    "main",
    "report",
    "reversal_motion",
    "run_case",
    "short_period_ns",
    "trace_capture",
    "worst_case",
]

#: The seed's numbers this tool reads unless told otherwise (next to this file).
NUMBERS = Path(__file__).resolve().parent / "seed_numbers.toml"
#: The step/dir rules, each simulated under its own worst case.
RULES: tuple[str, ...] = tuple(r.id for r in applicable("step-dir") if r.id in WORST_RULES)
US = 1000
#: Every stepgen parameter one period.
ONES: Mapping[str, int] = {name: 1 for name in PARAMS}

# ------------------------------------------------------------------------------ the seed's numbers


@dataclass(frozen=True)
class Case:
    """One worked example of the seed: a configuration and what the loop must find for it."""

    id: str
    section: str
    label: str
    why: str
    source: str
    drive: str
    base_period: int | str
    """µs, or ``"simple"`` (T + J) or ``"minimum"`` (stepgen plan's default)."""
    params: str
    """``"planned"`` or ``"ones"``."""
    override: Mapping[str, int]
    step_inverted: bool
    through_zero: bool
    expect: Mapping[str, Any]
    """Stated values, keyed as in seed_numbers.toml (µs, whole steps/s, rule lists)."""


@dataclass(frozen=True)
class SeedNumbers:
    """The contents of seed_numbers.toml."""

    latency_ns: int
    sections: Mapping[str, str]
    """Section id → title, in report order."""
    cases: tuple[Case, ...]
    sweep_latencies_ns: tuple[int, ...]
    short_period_latency_ns: int | None

    def case(self, case_id: str) -> Case:
        """The case called ``case_id`` (KeyError if none)."""
        for c in self.cases:
            if c.id == case_id:
                return c
        raise KeyError(case_id)


def _case(raw: Mapping[str, Any]) -> Case:
    return Case(
        id=raw["id"],
        section=raw["section"],
        label=raw["label"],
        why=raw.get("why", ""),
        source=raw.get("source", ""),
        drive=raw["drive"],
        base_period=raw["base_period_us"],
        params=raw.get("params", "planned"),
        override=dict(raw.get("override", {})),
        step_inverted=bool(raw.get("step_inverted", False)),
        through_zero=bool(raw.get("through_zero", False)),
        expect=dict(raw.get("expect", {})),
    )


def load_numbers(path: Path = NUMBERS) -> SeedNumbers:
    """Read the seed's numbers from ``path`` (µs in the file, ns here)."""
    with path.open("rb") as f:
        raw = tomllib.load(f)
    sweep = raw.get("sweep", {})
    short = sweep.get("short_period_latency_us")
    return SeedNumbers(
        latency_ns=int(raw["latency_us"] * US),
        sections=dict(raw["sections"]),
        cases=tuple(_case(c) for c in raw["case"]),
        sweep_latencies_ns=tuple(int(j * US) for j in sweep.get("latencies_us", ())),
        short_period_latency_ns=None if short is None else int(short * US),
    )


# --------------------------------------------------------------------------- configuration, motion


def servo_multiple(periods: Mapping[str, int]) -> int:
    """Servo period in base periods for :func:`config_for`: 1, or steplen + stepspace + 1 (not a
    multiple of the step spacing, so reversals still fall at every phase of the steps)."""
    if periods["steplen"] <= 1:
        return 1
    return periods["steplen"] + periods["stepspace"] + 1


def config_for(base_period_ns: int, periods: Mapping[str, int]) -> StepgenConfig:
    """A stepgen channel with ``periods`` (steplen … in whole periods) at ``base_period_ns``.

    Velocity mode; servo period = base period (so a reversal can be requested at any base
    period), or (steplen + stepspace + 1) base periods when steplen is longer than one period
    (a servo period at least as long as a pulse, as in real set-ups); make-pulses first (no start-up
    rounding at 50 µs, reference §3); no user velocity/accel limit.
    """
    return StepgenConfig(
        base_period_ns=base_period_ns,
        servo_period_ns=base_period_ns * servo_multiple(periods),
        mode="velocity",
        position_scale=1.0,
        steplen=periods["steplen"] * base_period_ns,
        stepspace=periods["stepspace"] * base_period_ns,
        dirsetup=periods["dirsetup"] * base_period_ns,
        dirhold=periods["dirhold"] * base_period_ns,
        thread_order="pulses-first",
    )


def reversal_motion(
    base_period_ns: int,
    periods: Mapping[str, int],
    *,
    reversals: int = 12,
    through_zero: bool = False,
) -> tuple[Motion, int]:
    """Velocity commands with ``reversals`` direction changes at full step rate; returns
    ``(motion, n_periods)``.

    Forward runs at the configuration's max rate 1/((steplen + stepspace)·P) — the shortest step
    spacing — and reverse at 0.9 of it (``through_zero=False``) or also at full rate
    (``through_zero=True``: the reversal from negative passes through exactly 0, see the module
    docstring). Segment k lasts ``base + k`` periods (``base`` longer than the reversal hold), so
    successive reversals fall at different phases of the step pattern.
    """
    fmax = 1e9 / ((periods["steplen"] + periods["stepspace"]) * base_period_ns)
    hold = periods["steplen"] + periods["dirhold"] + periods["dirsetup"]
    base = max(24, 2 * hold + 8)
    lengths = [base + k for k in range(reversals)]
    starts = np.concatenate(([0], np.cumsum(lengths))).astype(float)
    times = (starts + 0.5) * base_period_ns * 1e-9  # half a period off the update grid
    times[0] = 0.0
    reverse = 1.0 if through_zero else 0.9
    values = [fmax if k % 2 == 0 else -reverse * fmax for k in range(reversals)] + [0.0]
    motion = Motion(kind="csv", csv_times=times, csv_values=np.array(values))
    return motion, int(starts[-1]) + 2 * hold + 16


def command_csv(motion: Motion) -> str:
    """``motion``'s velocity commands as the ``time_s,value`` CSV of ``stepgen simulate --command``."""
    rows = "".join(
        f"{float(t)!r},{float(v)!r}\n"
        for t, v in zip(motion.csv_times, motion.csv_values, strict=True)
    )
    return "time_s,velocity\n" + rows


def trace_capture(trace: Trace) -> Capture:
    """A simulated trace as an exact capture (1 ns tick, resolution 0), pins as channels."""
    channels = [
        Channel(name=pin, index=i, initial=0, edges=np.asarray(trace.edges[pin], dtype=np.int64))
        for i, pin in enumerate(trace.pins)
    ]
    return Capture(
        path="<stepgen simulate>",
        format="vcd",
        timebase=Timebase(Fraction(1, 10**9)),
        resolution_ticks=0,
        samplerate_hz=None,
        start=0,
        end=int(trace.end_ns),
        channels=channels,
    )


# ------------------------------------------------------------------------------- the worst cases


@dataclass(frozen=True)
class RuleOutcome:
    """One rule over all worst-case runs of a configuration."""

    rule: str
    verdict: str
    """``pass``, ``fail`` or ``unchecked`` (the drive states no limit / no such interval)."""
    min_measured_ns: Fraction | None
    limit_ns: Fraction | None
    worst_run: str
    """The ``worst:J:RULE`` run that gave the shortest interval."""


@dataclass(frozen=True)
class Outcome:
    """A configuration checked under the worst case of every rule."""

    drive: Drive
    latency_ns: int
    base_period_ns: int
    periods: Mapping[str, int]
    step_inverted: bool
    rules: Mapping[str, RuleOutcome]
    observed_rate_hz: Fraction | None
    """Highest step rate seen with no latency (1 / shortest step interval)."""
    runs: int

    @property
    def verdict(self) -> str:
        """``fail`` if any run failed any rule, else ``pass``."""
        return "fail" if self.failed else "pass"

    @property
    def failed(self) -> tuple[str, ...]:
        """Rules some worst-case run failed."""
        return tuple(r.rule for r in self.rules.values() if r.verdict == "fail")

    @property
    def shortest_ns(self) -> Fraction:
        """The shortest interval measured for any rule with a limit (ns)."""
        return min(
            r.min_measured_ns
            for r in self.rules.values()
            if r.min_measured_ns is not None and r.rule != "step_period"
        )

    @property
    def config_rate_hz(self) -> Fraction:
        """stepgen's clamp 1/((steplen + stepspace)·P), exact Hz."""
        return Fraction(
            10**9, (self.periods["steplen"] + self.periods["stepspace"]) * self.base_period_ns
        )

    def measured(self, rule: str) -> Fraction | None:
        """The shortest interval of ``rule`` over all runs (ns)."""
        out = self.rules.get(rule)
        return None if out is None else out.min_measured_ns


#: One rule's result in one run: (verdict, min measured ns, limit ns, the run's latency model).
_RuleRun = tuple[str, Fraction | None, Fraction | None, str]


def _merge_runs(runs: list[_RuleRun]) -> tuple[str, Fraction | None, Fraction | None, str]:
    """One rule over several runs: the worst verdict, the shortest interval and where it was."""
    verdicts = {v for v, _, _, _ in runs}
    verdict = next((v for v in ("fail", "indeterminate", "pass") if v in verdicts), "unchecked")
    measured = [(m, where) for _, m, _, where in runs if m is not None]
    shortest, where = min(measured, key=lambda mw: mw[0]) if measured else (None, "")
    return verdict, shortest, runs[0][2], where


def worst_case(
    drive: Drive,
    latency_ns: int,
    base_period_ns: int,
    periods: Mapping[str, int],
    *,
    step_inverted: bool = False,
    through_zero: bool = False,
) -> Outcome:
    """Simulate ``periods`` at ``base_period_ns`` under ``worst:J:RULE`` for every rule and check
    each trace against ``drive``; the STEP pin is inverted before the drive if ``step_inverted``."""
    config = config_for(base_period_ns, periods)
    motion, n = reversal_motion(base_period_ns, periods, through_zero=through_zero)
    pin_edge = drive.active_edge
    if step_inverted:
        pin_edge = "falling" if drive.active_edge == "rising" else "rising"
    invert = ("step",) if step_inverted else ()

    def check(model: str) -> Report:
        trace = simulate(config, motion, model, n_periods=n, active_edge=pin_edge)  # type: ignore[arg-type]
        return check_report(trace_capture(trace), drive, invert=invert)

    seen: dict[str, list[_RuleRun]] = {}
    for rule in RULES:
        model = f"worst:{latency_ns}ns:{rule}"
        for r in check(model).rules:
            seen.setdefault(r.rule, []).append((r.verdict, r.min_measured_ns, r.limit_ns, model))
    return Outcome(
        drive=drive,
        latency_ns=latency_ns,
        base_period_ns=base_period_ns,
        periods=dict(periods),
        step_inverted=step_inverted,
        rules={rule: RuleOutcome(rule, *_merge_runs(runs)) for rule, runs in seen.items()},
        observed_rate_hz=check("none").rates.observed,
        runs=len(RULES) + 1,
    )


# ------------------------------------------------------------------------------------- one case


def _whole(hz: Fraction | None) -> int | None:
    """A rate as whole steps/s, as the seed states them (16,129 for 16,129.03)."""
    return None if hz is None else int(hz)


@dataclass(frozen=True)
class CaseRun:
    """A case of the seed's numbers run through plan → worst cases → check."""

    case: Case
    plan: Plan
    periods: Mapping[str, int]
    """The periods simulated (the plan's, or ones, with the case's overrides)."""
    outcome: Outcome

    def value(self, key: str) -> Any:
        """The computed value of the expectation ``key`` of seed_numbers.toml (µs as Fraction,
        rates as whole steps/s, rule lists as lists); KeyError for an unknown key."""
        out, p = self.outcome, self.plan
        simple: dict[str, Any] = {
            "verdict": lambda: out.verdict,
            "failed": lambda: list(out.failed),
            "fails_include": lambda: list(out.failed),
            "shortest_us": lambda: out.shortest_ns / US,
            "base_period_us": lambda: Fraction(p.base_period_ns, US),
            "planned_periods": p.with_params,
            "rate_hz": lambda: _whole(p.max_step_rate_hz),
            "observed_rate_hz": lambda: _whole(out.observed_rate_hz),
            "min_base_period_us": lambda: p.min_base_period_ns / US,
            "min_rate_hz": lambda: _whole(p.min_base_period_rate_hz),
        }
        if key in simple:
            return simple[key]()
        rule = key.removesuffix("_us")
        if key.endswith("_us") and rule in RULES:
            m = out.measured(rule)
            return None if m is None else m / US
        raise KeyError(f"unknown expectation {key!r}")

    def agrees(self, key: str) -> bool:
        """Whether the computed value of ``key`` is what the case states."""
        stated, got = self.case.expect[key], self.value(key)
        if key == "fails_include":
            return set(stated) <= set(got)
        return bool(got == stated)


def _case_plan(case: Case, drive: Drive, latency_ns: int) -> Plan:
    """stepgen plan at the case's BASE_PERIOD."""
    inverted = case.step_inverted
    if case.base_period == "minimum":
        return plan(drive, latency_ns, step_inverted=inverted)
    if case.base_period == "simple":
        period = plan(drive, latency_ns, step_inverted=inverted).simple_base_period_ns
        return plan(drive, latency_ns, period, step_inverted=inverted)
    if isinstance(case.base_period, int):
        return plan(drive, latency_ns, case.base_period * US, step_inverted=inverted)
    raise ValueError(f"{case.id}: base_period_us must be a number, 'simple' or 'minimum'")


def run_case(case: Case, latency_ns: int) -> CaseRun:
    """Plan the case, simulate it under every worst case and check it against its drive."""
    drive = load_drive(case.drive)
    p = _case_plan(case, drive, latency_ns)
    periods = {**(p.with_params() if case.params == "planned" else ONES), **case.override}
    outcome = worst_case(
        drive,
        latency_ns,
        p.base_period_ns,
        periods,
        step_inverted=case.step_inverted,
        through_zero=case.through_zero,
    )
    return CaseRun(case, p, periods, outcome)


# ------------------------------------------------------------------------------------- findings


@dataclass(frozen=True)
class Finding:
    """One line of the story: what the seed says, what the loop found, and whether they agree."""

    title: str
    expected: str
    found: str
    ok: bool
    source: str


def _us(ns: Fraction | int | None) -> str:
    if ns is None:
        return "-"
    v = Fraction(ns) / US
    return f"{v.numerator} us" if v.denominator == 1 else f"{float(v):g} us"


def _show(value: Any) -> str:
    """A stated or computed expectation value as report text."""
    if isinstance(value, Fraction):
        return str(value.numerator) if value.denominator == 1 else f"{float(value):g}"
    if isinstance(value, list):
        return ",".join(map(str, value)) or "-"
    if isinstance(value, dict):
        return " ".join(f"{k}={v}" for k, v in value.items())
    if isinstance(value, int) and value >= 10_000:
        return f"{value:,}"
    return str(value)


def finding(run: CaseRun, latency_ns: int) -> Finding:
    """One case's computed values beside its stated ones."""
    case = run.case
    keys = list(case.expect)
    return Finding(
        title=f"{case.drive}, J {_us(latency_ns)}, P {_us(run.plan.base_period_ns)}: {case.label}",
        expected="; ".join(f"{k} {_show(case.expect[k])}" for k in keys)
        + (f" — {case.why}" if case.why else ""),
        found="; ".join(f"{k} {_show(run.value(k))}" for k in keys),
        ok=all(run.agrees(k) for k in keys),
        source=case.source,
    )


def findings(numbers: SeedNumbers, section: str | None = None) -> list[Finding]:
    """Every case of ``section`` (all cases if None) run and compared with what it states."""
    return [
        finding(run_case(c, numbers.latency_ns), numbers.latency_ns)
        for c in numbers.cases
        if section is None or c.section == section
    ]


# ---------------------------------------------------------------------------------- the library


@dataclass
class SweepRow:
    """One drive and latency of the library sweep."""

    drive: Drive
    latency_ns: int
    plan: Plan
    outcome: Outcome
    shorter: dict[str, Outcome] = field(default_factory=dict)
    """For each parameter above one period: the outcome with it one period shorter."""

    @property
    def ok(self) -> bool:
        """The plan passes, and every lengthened parameter is needed (one less fails)."""
        return self.outcome.verdict == "pass" and all(
            o.verdict == "fail" for o in self.shorter.values()
        )


def plannable(drives: Iterable[Drive]) -> list[Drive]:
    """Drives ``stepgen plan`` handles: complete figures, step/dir, one active edge."""
    return [
        d
        for d in drives
        if d.complete and d.interface == "step-dir" and d.active_edge in ("rising", "falling")
    ]


def short_period_ns(drive: Drive, latency_ns: int) -> int:
    """A BASE_PERIOD below the minimum: half of it, whole µs, but at least J + 1 µs — so the
    pulse parameters need more than one period (exercises steplen/stepspace)."""
    half = -(-min_base_period_ns(drive, latency_ns) // 2000) * 1000
    return int(max(latency_ns + US, half))


def sweep_row(drive: Drive, latency_ns: int, period_ns: int | None) -> SweepRow:
    """Plan ``drive`` (at ``period_ns``, or its minimum), check it under every worst case, and
    each parameter above one period again one period shorter."""
    p = plan(drive, latency_ns, period_ns)
    periods = p.with_params()
    row = SweepRow(drive, latency_ns, p, worst_case(drive, latency_ns, p.base_period_ns, periods))
    for name in PARAMS:
        n = periods[name]
        if n > 1:
            shorter = {**periods, name: n - 1}
            row.shorter[name] = worst_case(drive, latency_ns, p.base_period_ns, shorter)
    return row


def library_sweep(
    latencies_ns: Iterable[int] = (5 * US, 11 * US, 25 * US),
    short_period_latency_ns: int | None = 5 * US,
) -> list[SweepRow]:
    """Every plannable drive in ``rules/`` at every latency: plan → worst cases → check, and each
    parameter above one period shortened by one period → worst cases → check.

    With ``short_period_latency_ns`` each drive is also planned at :func:`short_period_ns`
    (below the minimum BASE_PERIOD) for that latency.
    """
    rows = []
    for drive in plannable(list_drives()):
        cases: list[tuple[int, int | None]] = [(j, None) for j in latencies_ns]
        if short_period_latency_ns is not None:
            j = short_period_latency_ns
            cases.append((j, short_period_ns(drive, j)))
        rows += [sweep_row(drive, j, period) for j, period in cases]
    return rows


# --------------------------------------------------------------------------------------- report


def _finding_lines(title: str, found: list[Finding]) -> list[str]:
    lines = [title]
    for f in found:
        lines.append(f"  [{'ok' if f.ok else 'MISMATCH'}] {f.title}: {f.found}")
        lines.append(f"        expected {f.expected}  ({f.source})")
    return lines + [""]


def _parameter_lines(rows: list[SweepRow]) -> list[str]:
    """Per parameter: how often the plans lengthen it, and whether one period less fails."""
    lines = []
    for name in PARAMS:
        cut = [(r, o) for r in rows for pname, o in r.shorter.items() if pname == name]
        if not cut:
            lines.append(f"  {name}: never above one period")
            continue
        own = sum(any(rule in r.plan.params[name].reason for rule in o.failed) for r, o in cut)
        failed = sum(o.verdict == "fail" for _, o in cut)
        lines.append(
            f"  {name} above one period in {len(cut)} plans; one period shorter fails "
            f"{failed}/{len(cut)} (the rule the plan names: {own})"
        )
    return lines


def _row_lines(rows: list[SweepRow], verbose: bool) -> list[str]:
    """Every shortened parameter (``verbose``) and every row that does not hold."""
    lines = []
    if verbose:
        for r in rows:
            for name, o in r.shorter.items():
                lines.append(
                    f"    {r.drive.id} J {_us(r.latency_ns)} P {_us(r.plan.base_period_ns)}: "
                    f"{name} {r.plan.params[name].periods} -> "
                    f"{r.plan.params[name].periods - 1} fails {','.join(o.failed) or 'NOTHING'}"
                )
    for r in rows:
        if not r.ok:
            lines.append(
                f"  MISMATCH {r.drive.id} J {_us(r.latency_ns)} P {_us(r.plan.base_period_ns)}: "
                f"plan {r.outcome.verdict} {','.join(r.outcome.failed)}; shorter "
                f"{ ({k: o.verdict for k, o in r.shorter.items()}) }"
            )
    return lines


def _sweep_lines(numbers: SeedNumbers, rows: list[SweepRow], verbose: bool) -> list[str]:
    runs = sum(r.outcome.runs + sum(o.runs for o in r.shorter.values()) for r in rows)
    drives = len({r.drive.id for r in rows})
    below = sum(r.plan.base_period_ns < r.plan.min_base_period_ns for r in rows)
    passed = sum(r.outcome.verdict == "pass" for r in rows)
    latencies = ", ".join(str(j // US) for j in numbers.sweep_latencies_ns)
    short = numbers.short_period_latency_ns
    below_text = "" if short is None else f", and J = {_us(short)} at a P below the minimum"
    return [
        f"Library sweep: {drives} plannable drives in rules/, J = {latencies} us at the planned "
        f"P{below_text}: {len(rows)} plans ({below} below the minimum), {runs} simulations",
        f"  planned configuration passes every worst case: {passed}/{len(rows)}",
        *_parameter_lines(rows),
        *_row_lines(rows, verbose),
    ]


def report(
    numbers: SeedNumbers | None = None, sweep: bool = True, verbose: bool = False
) -> tuple[str, bool]:
    """The story as text, and whether every expectation held (``verbose``: every shortened
    parameter of the sweep on its own line)."""
    numbers = load_numbers() if numbers is None else numbers
    lines = [
        "The seed's stepper-tuning story: plan -> stepgen simulate worst:J:RULE (every rule) "
        "-> wavecheck check",
        "",
    ]
    ok = True
    for section, title in numbers.sections.items():
        found = findings(numbers, section)
        ok &= all(f.ok for f in found)
        lines += _finding_lines(f"{title}, J = {_us(numbers.latency_ns)}", found)
    if sweep:
        rows = library_sweep(numbers.sweep_latencies_ns, numbers.short_period_latency_ns)
        ok &= all(r.ok for r in rows)
        lines += _sweep_lines(numbers, rows, verbose)
    lines += ["", "all expectations hold" if ok else "SOME EXPECTATIONS FAILED"]
    return "\n".join(lines) + "\n", ok


def main(argv: list[str] | None = None) -> int:
    """Print the story; exit 0 when every expectation holds."""
    ap = argparse.ArgumentParser(prog="python -m tools.story", description=__doc__.split("\n")[0])
    ap.add_argument(
        "--numbers", type=Path, default=NUMBERS, help=f"the seed's numbers (default {NUMBERS})"
    )
    ap.add_argument("--no-sweep", action="store_true", help="skip the library sweep")
    ap.add_argument("--verbose", action="store_true", help="every shortened parameter")
    args = ap.parse_args(argv)
    text, ok = report(load_numbers(args.numbers), sweep=not args.no_sweep, verbose=args.verbose)
    sys.stdout.write(text)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
