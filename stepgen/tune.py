"""The manual PID tuning method of the integrator's chapter, automated on a model plant.

The method (Machinekit/LinuxCNC "Integrator concepts", Manual tuning; pid reference §4.1):

1. I = D = 0; raise P until the loop oscillates — here: the later half-cycle peaks of a step
   response's error decay by less than 1 % per cycle (:func:`stepgen.loop.oscillation`), found
   by doubling P and then bisecting to 1 %; the lowest such P is the ultimate gain Ku, its
   period Pu. The report says what that response's swing does over the whole window
   (:func:`swing_words`: it may still decay, as its plot shows);
2. P = Ku/2 ("about half, for a quarter amplitude decay");
3. raise I until the offset is corrected within the settling time the user gives (I grows by
   ×1.4 from 0.05·P/Pu; stops before a setting that oscillates, keeping the last stable one);
   with no offset to correct I stays 0;
4. raise D while it reduces the overshoot (from 0.01·P·Pu by ×1.5; stops when it no longer
   helps or the settling gets worse).

For a velocity-mode stepgen, :func:`feedforward_comparison` also runs LinuxCNC's configured
gains (pncconf: P = 1/servo period, FF1 = 1, I = D = 0) and the tuned ones on a constant-speed
command: without FF1 a type-1 loop lags by v/P at cruise; with FF1 = 1 the lag is 0.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np

from stepgen.loop import LoopResult, Oscillation, StepMetrics, oscillation, run_loop, step_metrics
from stepgen.pid import PidGains
from stepgen.plant import Plant
from wavecheck.errors import ConfigError

__all__ = [
    "FeedForward",
    "Stage",
    "TuneResult",
    "feedforward_comparison",
    "find_ultimate_gain",
    "hal_lines",
    "ini_lines",
    "step_response",
    "swing_words",
    "tune",
]

#: Per-cycle amplitude ratio at and above which an oscillation counts as sustained.
SUSTAINED_RATIO = 0.99
#: Oscillation smaller than this fraction of the step is noise (encoder counts, friction).
MIN_AMPLITUDE = 0.02
#: Most servo periods of one step response (the method runs dozens of them, ~µs per period).
MAX_RESPONSE_PERIODS = 200_000
#: Bisection stops when hi/lo is below this.
KU_TOLERANCE = 1.01


@dataclass
class Stage:
    """One step of the method: its gains, step response figures and what was decided."""

    name: str
    gains: PidGains
    metrics: StepMetrics
    osc: Oscillation
    note: str
    result: LoopResult = field(repr=False)


@dataclass
class TuneResult:
    """What ``stepgen tune`` found (Ku in the output's units per position unit, Pu in s)."""

    ku: float
    pu: float
    stages: list[Stage]
    final: PidGains
    tries: int
    notes: list[str] = field(default_factory=list)


def step_response(
    make_plant: Callable[[], Plant], gains: PidGains, step: float, window_s: float
) -> LoopResult:
    """The loop's response to a position step of ``step`` units at the second servo period."""
    plant = make_plant()
    n = max(int(round(window_s / (plant.servo_ns * 1e-9))), 8)
    cmd = np.full(n, step)
    cmd[0] = 0.0
    return run_loop(plant, gains, cmd, stop_if_diverged=1e3 * abs(step))


def _settling(s: Stage) -> float:
    return math.inf if s.metrics.settling_s is None else s.metrics.settling_s


def _judge(r: LoopResult, step: float, band: float) -> tuple[StepMetrics, Oscillation]:
    osc = oscillation(
        r.ferror, r.servo_ns, MIN_AMPLITUDE * abs(step), SUSTAINED_RATIO, diverged=r.diverged
    )
    return step_metrics(r.t_s, r.feedback, 0.0, step, t_step=r.servo_ns * 1e-9, band=band), osc


def swing_words(r: LoopResult, period_s: float) -> str:
    """What the response's swing does over the whole window, in words that match its plot: the
    peak-to-peak of the position over its first cycle after the step and over its last cycle,
    and the ratio per cycle between them (units of position)."""
    k = round(period_s / (r.servo_ns * 1e-9)) if math.isfinite(period_s) else 0
    if r.diverged or k < 2 or r.n < 1 + 3 * k:
        return "the loop diverges" if r.diverged else "no full cycles to compare"
    first = float(np.ptp(r.feedback[1 : 1 + k]))
    last = float(np.ptp(r.feedback[-k:]))
    cycles = (r.n - 1 - k) / k
    ratio = (last / first) ** (1 / cycles) if first > 0 else math.nan
    what = "decays" if ratio < 0.995 else "grows" if ratio > 1.005 else "keeps its size"
    return (
        f"its swing {what} from {first:.3g} to {last:.3g} units over the {r.n * r.servo_ns * 1e-9:g} s "
        f"window (×{ratio:.3f} per cycle)"
    )


def find_ultimate_gain(
    make_plant: Callable[[], Plant],
    step: float,
    window_s: float,
    p_start: float = 1.0,
    base: PidGains | None = None,
) -> tuple[float, float, int]:
    """(Ku, Pu in s, responses run): the lowest P (I = D = 0) that passes the oscillation test.

    Raises:
        ConfigError: no P up to 2^60·p_start oscillates (or even p_start/2^60 does).
    """
    g0 = replace(base or PidGains(), Pgain=p_start, Igain=0.0, Dgain=0.0)
    tries = 0

    def osc(p: float) -> Oscillation:
        nonlocal tries
        tries += 1
        r = step_response(make_plant, replace(g0, Pgain=p), step, window_s)
        return oscillation(
            r.ferror, r.servo_ns, MIN_AMPLITUDE * abs(step), SUSTAINED_RATIO, diverged=r.diverged
        )

    lo, hi = p_start, p_start
    if osc(p_start).sustained:
        for _ in range(60):
            lo /= 2
            if not osc(lo).sustained:
                break
        else:
            raise ConfigError(f"the loop oscillates even at P = {lo:g}: check the plant")
        hi = lo * 2
    else:
        for _ in range(60):
            hi *= 2
            if osc(hi).sustained:
                break
        else:
            raise ConfigError(
                f"no P up to {hi:g} makes the loop oscillate within the {window_s:g} s window "
                "(give a longer --window or check the plant)"
            )
        lo = hi / 2
    while hi / lo > KU_TOLERANCE:
        mid = math.sqrt(lo * hi)
        if osc(mid).sustained:
            hi = mid
        else:
            lo = mid
    final = osc(hi)
    pu = final.period_s if final.period_s is not None else math.nan
    return hi, pu, tries


def tune(
    make_plant: Callable[[], Plant],
    *,
    step: float,
    settle_s: float,
    window_s: float,
    band: float = 0.02,
    p_start: float = 1.0,
    base: PidGains | None = None,
) -> TuneResult:
    """Run the method (module doc) on fresh plants from ``make_plant``.

    Args:
        make_plant: a new plant at rest for each response.
        step: the step size (position units).
        settle_s: the settling time the offset must be corrected within (s).
        window_s: the length of each response (s); several oscillation periods.
        band: the settling band, a fraction of the step.
        p_start: the first P tried.
        base: other pins kept throughout (limits, deadband); gains are overwritten.
    """
    if not (step != 0 and math.isfinite(step)):
        raise ConfigError(f"--step {step!r} must be a nonzero number of position units")
    if not (0 < settle_s < window_s):
        raise ConfigError(
            f"--settle {settle_s:g} s must be > 0 and shorter than --window {window_s:g} s"
        )
    if not (0 < band < 1):
        raise ConfigError(f"--band {band!r} must be between 0 and 1 (a fraction of the step)")
    servo_s = make_plant().servo_ns * 1e-9
    if window_s / servo_s > MAX_RESPONSE_PERIODS:
        raise ConfigError(
            f"--window {window_s:g} s is {window_s / servo_s:.3g} servo periods per response, "
            f"more than {MAX_RESPONSE_PERIODS} (the method runs dozens of responses: give a "
            "shorter --window)"
        )
    g0 = replace(base or PidGains(), Igain=0.0, Dgain=0.0)
    ku, pu, tries = find_ultimate_gain(make_plant, step, window_s, p_start, g0)
    stages: list[Stage] = []

    def run(name: str, g: PidGains, note: str) -> Stage:
        nonlocal tries
        tries += 1
        r = step_response(make_plant, g, step, window_s)
        m, o = _judge(r, step, band)
        s = Stage(name, g, m, o, note, r)
        stages.append(s)
        return s

    s_ku = run("1 oscillation", replace(g0, Pgain=ku), "")
    s_ku.note = (
        f"P = Ku = {ku:.6g}, the lowest P the oscillation test (later half-cycles decaying by "
        f"less than {1 - SUSTAINED_RATIO:.0%} per cycle) passes: {swing_words(s_ku.result, pu)}; "
        f"period Pu = {pu:.6g} s"
    )
    p = ku / 2
    s_p = run("2 P = Ku/2", replace(g0, Pgain=p), "half the oscillating P")
    notes: list[str] = []
    g = s_p.gains
    settled = s_p.metrics.settling_s is not None and s_p.metrics.settling_s <= settle_s
    if settled and abs(s_p.metrics.steady_state_error) <= band * abs(step):
        notes.append("P alone leaves no offset beyond the band within --settle: I stays 0")
        s_i = s_p
    else:
        i_gain = 0.05 * p / pu
        s_i = s_p
        chosen = None
        for _ in range(40):
            trial = run("3 raise I", replace(g, Igain=i_gain), f"I = {i_gain:.6g}")
            if trial.osc.sustained or trial.result.diverged:
                trial.note += ": oscillates — stopped before instability"
                break
            if s_i is s_p or _settling(trial) < _settling(s_i):
                s_i = trial  # the best-settling stable I so far
            if trial.metrics.settling_s is not None and trial.metrics.settling_s <= settle_s:
                s_i = trial
                chosen = trial
                trial.note += f": settles in {trial.metrics.settling_s:.4g} s <= {settle_s:g} s"
                break
            i_gain *= 1.4
        if chosen is None:
            notes.append(
                f"no stable I corrects the offset within {settle_s:g} s; kept I = {s_i.gains.Igain:.6g}"
            )
        g = s_i.gains
    best = s_i
    d_gain = 0.01 * p * pu
    limit_settle = max(settle_s, s_i.metrics.settling_s or settle_s)
    for _ in range(30):
        trial = run("4 raise D", replace(g, Dgain=d_gain), f"D = {d_gain:.6g}")
        ok = (
            not trial.osc.sustained
            and not trial.result.diverged
            and trial.metrics.settling_s is not None
            and trial.metrics.settling_s <= limit_settle
        )
        if not ok or trial.metrics.overshoot >= best.metrics.overshoot - 1e-6:
            trial.note += ": does not reduce the overshoot — stopped"
            break
        trial.note += f": overshoot {trial.metrics.overshoot:.1%}"
        best = trial
        d_gain *= 1.5
    final = best.gains
    stages.append(replace(best, name="final", note="the gains kept"))
    return TuneResult(ku=ku, pu=pu, stages=stages, final=final, tries=tries, notes=notes)


@dataclass(frozen=True)
class FeedForward:
    """Following error at a constant speed (``velocity`` units/s): tuned gains vs LinuxCNC's."""

    velocity: float
    configured: PidGains
    tuned_ferror: float
    configured_ferror: float


def feedforward_comparison(
    make_plant: Callable[[], Plant],
    tuned: PidGains,
    velocity: float,
    servo_ns: int,
    run_s: float = 0.5,
) -> FeedForward:
    """Run a ramp at ``velocity`` with the tuned gains and with pncconf's (P = 1/T, FF1 = 1);
    the figures are the largest |ferror| over the last half of the run (cruise)."""
    t = servo_ns * 1e-9
    n = max(int(round(run_s / t)), 8)
    cmd = velocity * t * np.arange(n)
    configured = PidGains(Pgain=round(1.0 / t, 9), FF1=1.0)
    out = []
    for g in (tuned, configured):
        r = run_loop(make_plant(), g, cmd)
        out.append(float(np.abs(r.ferror[n // 2 :]).max()))
    return FeedForward(velocity, configured, out[0], out[1])


def ini_lines(g: PidGains, joint: int) -> list[str]:
    """The ``[JOINT_n]`` lines LinuxCNC configurations keep the gains in."""
    return [
        f"[JOINT_{joint}]",
        f"P = {g.Pgain:.6g}",
        f"I = {g.Igain:.6g}",
        f"D = {g.Dgain:.6g}",
        f"FF0 = {g.FF0:.6g}",
        f"FF1 = {g.FF1:.6g}",
        f"FF2 = {g.FF2:.6g}",
        f"BIAS = {g.bias:.6g}",
        f"DEADBAND = {g.deadband:.6g}",
        f"MAX_OUTPUT = {g.maxoutput:.6g}",
    ]


def hal_lines(joint: int, pid: int | None = None) -> list[str]:
    """The ``setp pid.N.*`` lines that read them (pncconf's form)."""
    n = joint if pid is None else pid
    pairs = (
        ("Pgain", "P"),
        ("Igain", "I"),
        ("Dgain", "D"),
        ("bias", "BIAS"),
        ("FF0", "FF0"),
        ("FF1", "FF1"),
        ("FF2", "FF2"),
        ("deadband", "DEADBAND"),
        ("maxoutput", "MAX_OUTPUT"),
    )
    return [f"setp pid.{n}.{pin} [JOINT_{joint}]{key}" for pin, key in pairs]
