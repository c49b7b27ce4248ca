"""The seeds' stepper-tuning story, executable: plan → simulate under worst-case latency → check.

``python -m stepgen.story`` (``make story``) prints it as a short report and exits 0 when every
expectation holds, 1 otherwise. ``tests/stepgen/test_story.py`` asserts the same findings.

Each configuration is simulated with the faithful LinuxCNC stepgen model (:mod:`stepgen.simulate`)
once per rule under ``worst:J:RULE`` — the invocations that end that rule's intervals run on time,
all others ``J`` late, so every interval is ``n·P − J`` — and every trace is checked edge by edge
against the drive by the validator (:func:`wavecheck.engine.run_check`). A rule's figure is the
shortest interval over all those runs; a configuration passes when no run fails any rule.

The motion (:func:`reversal_motion`): velocity mode, servo thread = base thread, reversals at the
configuration's full step rate in one direction and 0.9 of it in the other, with segments of
slightly different lengths so the reversal request falls at every phase of the step pattern.
0.9 keeps the velocity from passing through exactly 0 going from negative to positive: there
LinuxCNC's hold logic freezes addval at 0, so DIR cannot change during the hold and flips in the
same period as the first step (reference §2.4, LinuxCNC issue #2332) whatever dirsetup is.
:func:`zero_crossing_story` shows that case separately.
"""

from __future__ import annotations

import sys
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from fractions import Fraction

import numpy as np

from stepgen.latency import RULES as WORST_RULES
from stepgen.model import StepgenConfig
from stepgen.motion import Motion
from stepgen.plan import PARAMS, Plan, plan
from stepgen.simulate import Trace, simulate
from wavecheck.capture.model import Capture, Channel
from wavecheck.drives.model import Drive
from wavecheck.rules import applicable
from wavecheck.timebase import Timebase

__all__ = [
    "RULES",
    "Finding",
    "Outcome",
    "SweepRow",
    "command_csv",
    "config_for",
    "library_sweep",
    "main",
    "report",
    "reversal_motion",
    "seed_story",
    "short_period_ns",
    "trace_capture",
    "worst_case",
    "zero_crossing_story",
]

#: The step/dir rules, each simulated under its own worst case.
RULES: tuple[str, ...] = tuple(r.id for r in applicable("step-dir") if r.id in WORST_RULES)
US = 1000


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
    from wavecheck.engine import run_check

    config = config_for(base_period_ns, periods)
    motion, n = reversal_motion(base_period_ns, periods, through_zero=through_zero)
    pin_edge = drive.active_edge
    if step_inverted:
        pin_edge = "falling" if drive.active_edge == "rising" else "rising"
    invert = ("step",) if step_inverted else ()
    seen: dict[str, list[tuple[str, Fraction | None, Fraction | None, str]]] = {}
    for rule in RULES:
        model = f"worst:{latency_ns}ns:{rule}"
        trace = simulate(config, motion, model, n_periods=n, active_edge=pin_edge)  # type: ignore[arg-type]
        result = run_check(trace_capture(trace), drive, invert=invert)
        for r in result.rules:
            seen.setdefault(r.rule, []).append((r.verdict, r.min_measured_ns, r.limit_ns, model))
    best: dict[str, RuleOutcome] = {}
    for rule, runs in seen.items():
        verdicts = {v for v, _, _, _ in runs}
        verdict = next((v for v in ("fail", "indeterminate", "pass") if v in verdicts), "unchecked")
        measured = [(m, where) for _, m, _, where in runs if m is not None]
        shortest, where = min(measured, key=lambda mw: mw[0]) if measured else (None, "")
        best[rule] = RuleOutcome(rule, verdict, shortest, runs[0][2], where)
    calm = simulate(config, motion, "none", n_periods=n, active_edge=pin_edge)  # type: ignore[arg-type]
    observed = run_check(trace_capture(calm), drive, invert=invert).rates.observed
    return Outcome(
        drive=drive,
        latency_ns=latency_ns,
        base_period_ns=base_period_ns,
        periods=dict(periods),
        step_inverted=step_inverted,
        rules=best,
        observed_rate_hz=observed,
        runs=len(RULES) + 1,
    )


# ----------------------------------------------------------------------------------- findings


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


def _rate(hz: Fraction | None) -> str:
    return "-" if hz is None else f"{int(hz):,}/s"


def _load(drive_id: str) -> Drive:
    from wavecheck.drives.library import load_drive

    return load_drive(drive_id)


def _periods(p: Plan, **override: int) -> dict[str, int]:
    return p.with_params(**override)


DEFAULTS = {"steplen": 1, "stepspace": 1, "dirsetup": 1, "dirhold": 1}


def seed_story() -> list[Finding]:
    """The seed's G202 and Xylotex numbers, each through plan → simulate → check."""
    g202, xylotex = _load("gecko-g202"), _load("xylotex")
    j = 11 * US
    out: list[Finding] = []

    naive = worst_case(g202, j, 20 * US, DEFAULTS)
    hold = naive.measured("dir_hold")
    out.append(
        Finding(
            "G202, J 11 us, P 20 us, default parameters",
            "fails dir_hold: 20 - 11 = 9 us < 20 us",
            f"{naive.verdict} {','.join(naive.failed) or '-'}; dir_hold {_us(hold)}",
            naive.failed == ("dir_hold",) and hold == 9 * US,
            "seed 000 'Choose your BASE_PERIOD'",
        )
    )

    simple = plan(g202, j)
    p31 = plan(g202, j, simple.simple_base_period_ns)
    o31 = worst_case(g202, j, p31.base_period_ns, _periods(p31))
    out.append(
        Finding(
            f"G202, J 11 us, simple P = {_us(simple.simple_base_period_ns)} (20 + 11)",
            "passes at 16,129 steps/s, all parameters 1 period",
            f"{o31.verdict}; {_rate(p31.max_step_rate_hz)} (observed {_rate(o31.observed_rate_hz)}); "
            f"periods {list(p31.with_params().values())}",
            o31.verdict == "pass"
            and int(p31.max_step_rate_hz) == 16_129
            and o31.observed_rate_hz == p31.max_step_rate_hz
            and all(v == 1 for v in p31.with_params().values()),
            "seed 000 'Choose your BASE_PERIOD'",
        )
    )

    p16 = plan(g202, j, 16 * US)
    o16 = worst_case(g202, j, 16 * US, _periods(p16))
    out.append(
        Finding(
            "G202, J 11 us, P 16 us, planned",
            "dirhold = 2 periods, passes at 31,250 steps/s, hold 2*16 - 11 = 21 us",
            f"dirhold {p16.params['dirhold'].periods}; {o16.verdict}; {_rate(p16.max_step_rate_hz)} "
            f"(observed {_rate(o16.observed_rate_hz)}); dir_hold {_us(o16.measured('dir_hold'))}",
            p16.params["dirhold"].periods == 2
            and o16.verdict == "pass"
            and int(p16.max_step_rate_hz) == 31_250
            and o16.observed_rate_hz == p16.max_step_rate_hz
            and o16.measured("dir_hold") == 21 * US,
            "seed 000 'Use steplen, stepspace, dirsetup, and/or dirhold'",
        )
    )

    o16h1 = worst_case(g202, j, 16 * US, _periods(p16, dirhold=1))
    out.append(
        Finding(
            "G202, J 11 us, P 16 us, dirhold 1",
            "fails dir_hold: 16 - 11 = 5 us",
            f"{o16h1.verdict} {','.join(o16h1.failed) or '-'}; dir_hold {_us(o16h1.measured('dir_hold'))}",
            o16h1.failed == ("dir_hold",) and o16h1.measured("dir_hold") == 5 * US,
            "seed 000 'Use steplen, stepspace, dirsetup, and/or dirhold'",
        )
    )

    pinv = plan(g202, j, 16 * US, step_inverted=True)
    oinv = worst_case(g202, j, 16 * US, _periods(pinv), step_inverted=True)
    out.append(
        Finding(
            "G202, J 11 us, P 16 us, STEP pin inverted",
            "hold counts from the start: (1 + dirhold)*16 - 11, dirhold 1 passes",
            f"dirhold {pinv.params['dirhold'].periods}; {oinv.verdict}; dir_hold {_us(oinv.measured('dir_hold'))}",
            pinv.params["dirhold"].periods == 1
            and oinv.verdict == "pass"
            and oinv.measured("dir_hold") == 21 * US,
            "DESIGN 'The seed's Gecko G202 story'; seed 001 (invert for falling-edge drives)",
        )
    )

    px = plan(xylotex, j)
    ox = worst_case(xylotex, j, px.base_period_ns, _periods(px))
    out.append(
        Finding(
            "Xylotex, J 11 us, minimum P",
            "13 us (11 + 2), 38,461 steps/s",
            f"{_us(px.min_base_period_ns)}; {ox.verdict}; {_rate(px.min_base_period_rate_hz)} "
            f"(observed {_rate(ox.observed_rate_hz)})",
            px.min_base_period_ns == 13 * US
            and int(px.min_base_period_rate_hz) == 38_461
            and ox.verdict == "pass"
            and ox.observed_rate_hz == px.max_step_rate_hz,
            "seed 000 'Choose your BASE_PERIOD'",
        )
    )

    px16 = plan(xylotex, j, 16 * US)
    ox16 = worst_case(xylotex, j, 16 * US, _periods(px16))
    out.append(
        Finding(
            "Xylotex, J 11 us, P 16 us",
            "passes at 31,250 steps/s, shortest output time 16 - 11 = 5 us (needs 2 us)",
            f"{ox16.verdict}; {_rate(px16.max_step_rate_hz)} (observed {_rate(ox16.observed_rate_hz)}); "
            f"shortest {_us(ox16.shortest_ns)}",
            ox16.verdict == "pass"
            and int(px16.max_step_rate_hz) == 31_250
            and ox16.observed_rate_hz == px16.max_step_rate_hz
            and ox16.shortest_ns >= 5 * US,
            "seed 000 'Choose your BASE_PERIOD'",
        )
    )
    return out


def zero_crossing_story() -> list[Finding]:
    """LinuxCNC's reversal through exactly zero velocity (reference §2.4, issue #2332): DIR flips
    in the same period as the first step. A rising-edge drive gets no DIR setup at all, whatever
    dirsetup is; the seed's G202 reading (active edge = end of the pulse) keeps steplen·P − J."""
    j = 11 * US
    out = []
    xylotex, g202 = _load("xylotex"), _load("gecko-g202")
    px = plan(xylotex, j, 16 * US)
    ox = worst_case(xylotex, j, 16 * US, _periods(px), through_zero=True)
    out.append(
        Finding(
            "Xylotex planned at 16 us, reversal through v = 0",
            "LinuxCNC defect: DIR and STEP in the same period, dir_setup 0 (plan cannot fix it)",
            f"{ox.verdict} {','.join(ox.failed) or '-'}; dir_setup {_us(ox.measured('dir_setup'))}",
            "dir_setup" in ox.failed and ox.measured("dir_setup") == 0,
            "reference §2.4 case 1; LinuxCNC issue #2332",
        )
    )
    pg = plan(g202, j, 31 * US)
    og = worst_case(g202, j, 31 * US, _periods(pg), through_zero=True)
    out.append(
        Finding(
            "G202 planned at 31 us (pin not inverted), reversal through v = 0",
            "DIR and the pulse start in the same period, but its setup runs to the falling edge: "
            "steplen*P - J = 20 us >= 1 us, passes",
            f"{og.verdict}; dir_setup {_us(og.measured('dir_setup'))}",
            og.verdict == "pass" and og.measured("dir_setup") == 20 * US,
            "reference §2.4; DESIGN 'The seed's Gecko G202 story'",
        )
    )
    return out


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
    from stepgen.plan import min_base_period_ns

    half = -(-min_base_period_ns(drive, latency_ns) // 2000) * 1000
    return int(max(latency_ns + US, half))


def library_sweep(
    latencies_ns: Iterable[int] = (5 * US, 11 * US, 25 * US),
    short_period_latency_ns: int | None = 5 * US,
) -> list[SweepRow]:
    """Every plannable drive in ``rules/`` at every latency: plan → worst cases → check, and each
    parameter above one period shortened by one period → worst cases → check.

    With ``short_period_latency_ns`` each drive is also planned at :func:`short_period_ns`
    (below the minimum BASE_PERIOD) for that latency.
    """
    from wavecheck.drives.library import list_drives

    rows = []
    for drive in plannable(list_drives()):
        cases: list[tuple[int, int | None]] = [(j, None) for j in latencies_ns]
        if short_period_latency_ns is not None:
            j = short_period_latency_ns
            cases.append((j, short_period_ns(drive, j)))
        for j, period in cases:
            p = plan(drive, j, period)
            periods = _periods(p)
            row = SweepRow(drive, j, p, worst_case(drive, j, p.base_period_ns, periods))
            for name in PARAMS:
                n = periods[name]
                if n > 1:
                    row.shorter[name] = worst_case(
                        drive, j, p.base_period_ns, {**periods, name: n - 1}
                    )
            rows.append(row)
    return rows


def report(sweep: bool = True, verbose: bool = False) -> tuple[str, bool]:
    """The story as text, and whether every expectation held (``verbose``: every shortened
    parameter of the sweep on its own line)."""
    lines = [
        "The seed's stepper-tuning story: plan -> stepgen simulate worst:J:RULE (every rule) -> wavecheck check",
        "",
    ]
    ok = True
    for title, findings in (
        ("Seed numbers (Gecko G202 and Xylotex, J = 11 us)", seed_story()),
        ("LinuxCNC's zero-velocity reversal (not fixable by parameters)", zero_crossing_story()),
    ):
        lines.append(title)
        for f in findings:
            ok &= f.ok
            lines.append(f"  [{'ok' if f.ok else 'MISMATCH'}] {f.title}: {f.found}")
            lines.append(f"        expected {f.expected}  ({f.source})")
        lines.append("")
    if sweep:
        rows = library_sweep()
        bad = [r for r in rows if not r.ok]
        ok &= not bad
        runs = sum(r.outcome.runs + sum(o.runs for o in r.shorter.values()) for r in rows)
        drives = len({r.drive.id for r in rows})
        below = sum(r.plan.base_period_ns < r.plan.min_base_period_ns for r in rows)
        lines.append(
            f"Library sweep: {drives} plannable drives in rules/, J = 5, 11, 25 us at the planned "
            f"P, and J = 5 us at a P below the minimum: {len(rows)} plans ({below} below the "
            f"minimum), {runs} simulations"
        )
        passed = sum(r.outcome.verdict == "pass" for r in rows)
        lines.append(f"  planned configuration passes every worst case: {passed}/{len(rows)}")
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
        if verbose:
            for r in rows:
                for name, o in r.shorter.items():
                    lines.append(
                        f"    {r.drive.id} J {_us(r.latency_ns)} P {_us(r.plan.base_period_ns)}: "
                        f"{name} {r.plan.params[name].periods} -> "
                        f"{r.plan.params[name].periods - 1} fails {','.join(o.failed) or 'NOTHING'}"
                    )
        for r in bad:
            lines.append(
                f"  MISMATCH {r.drive.id} J {_us(r.latency_ns)} P {_us(r.plan.base_period_ns)}: "
                f"plan {r.outcome.verdict} {','.join(r.outcome.failed)}; shorter "
                f"{ ({k: o.verdict for k, o in r.shorter.items()}) }"
            )
    lines.append("")
    lines.append("all expectations hold" if ok else "SOME EXPECTATIONS FAILED")
    return "\n".join(lines) + "\n", ok


def main(argv: list[str] | None = None) -> int:
    """Print the story; exit 0 when every expectation holds (``--no-sweep``, ``--verbose``)."""
    args = sys.argv[1:] if argv is None else argv
    text, ok = report(sweep="--no-sweep" not in args, verbose="--verbose" in args)
    sys.stdout.write(text)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
