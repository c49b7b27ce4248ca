"""The closed loop of a LinuxCNC servo thread: pid between a position command and a plant.

Per servo period k (pid reference §3): read the feedback f_k (capture-position / encoder),
``pid.do-pid-calcs`` with the command c_k, apply the output over the period (update-freq and the
base thread's make-pulses / the amplifier). The loop is inherently sequential: one Python
iteration per servo period, bounded by :data:`MAX_SERVO_PERIODS`.

Figures, all from the recorded arrays (numpy):

- following error as LinuxCNC's motion measures it, ``ferror_k = c_{k−1} − f_k`` (reference
  §4.4; with ``error-previous-target`` it is pid's ``error`` pin), and the check against
  ``limit_k = max(FERROR·|v_k| / MAX_VELOCITY, MIN_FERROR)`` (:func:`ferror_check`);
- a step response's rise time (10 → 90 %), overshoot, settling time into a band and
  steady-state error (:func:`step_metrics`);
- sustained oscillation: its amplitude trend and period (:func:`oscillation`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from stepgen.pid import Pid, PidGains
from stepgen.plant import Plant
from wavecheck.errors import ConfigError

__all__ = [
    "MAX_SERVO_PERIODS",
    "FerrorCheck",
    "LoopResult",
    "Oscillation",
    "StepMetrics",
    "ferror_check",
    "oscillation",
    "run_loop",
    "step_metrics",
]

#: Most servo periods one closed-loop run simulates (a per-period Python loop: ~µs each).
MAX_SERVO_PERIODS = 2_000_000
#: A response whose error exceeds this many times the step is diverging: the run stops there.
DIVERGED = 1e6


@dataclass
class LoopResult:
    """One closed-loop run, servo period by servo period (arrays of length ``n``).

    ``command[k]``, ``feedback[k]`` (read before pid), ``output[k]`` (pid's output), ``ferror[k]``
    = command[k−1] − feedback[k] (motion's following error; command[−1] = 0), ``saturated[k]``.
    ``diverged``: the run stopped early at ``n`` periods because the error grew without bound.
    """

    servo_ns: int
    command: np.ndarray
    feedback: np.ndarray
    output: np.ndarray
    ferror: np.ndarray
    saturated: np.ndarray
    diverged: bool = False

    @property
    def n(self) -> int:
        """Servo periods run."""
        return len(self.command)

    @property
    def t_s(self) -> np.ndarray:
        """Servo tick times (s)."""
        return np.arange(self.n) * (self.servo_ns * 1e-9)

    def max_ferror(self) -> tuple[float, float]:
        """(max |ferror|, the time it occurs in s) — (0, 0) for an empty run."""
        if self.n == 0:
            return 0.0, 0.0
        k = int(np.argmax(np.abs(self.ferror)))
        return float(abs(self.ferror[k])), k * self.servo_ns * 1e-9


def run_loop(
    plant: Plant,
    gains: PidGains,
    commands: Sequence[float] | np.ndarray,
    *,
    stop_if_diverged: float | None = None,
) -> LoopResult:
    """Run pid against ``plant`` for ``len(commands)`` servo periods (enabled throughout).

    Args:
        plant: the plant (its ``servo_ns`` is the servo period).
        gains: pid's pins.
        commands: the position command of each servo period (units).
        stop_if_diverged: stop when |command − feedback| exceeds this (units); None: never.
            The run also stops when the plant says it diverged (:attr:`Plant.diverged`).

    Raises:
        ConfigError: more than :data:`MAX_SERVO_PERIODS` periods.
    """
    n = len(commands)
    if n > MAX_SERVO_PERIODS:
        raise ConfigError(
            f"closed-loop run of {n} servo periods is more than the {MAX_SERVO_PERIODS} one run "
            "simulates (give a shorter --duration)"
        )
    cmd = np.asarray(commands, dtype=float)
    fb = np.zeros(n)
    out = np.zeros(n)
    sat = np.zeros(n, dtype=bool)
    pid = Pid(gains)
    servo = plant.servo_ns
    limit = math.inf if stop_if_diverged is None else stop_if_diverged
    diverged = False
    k = 0
    for k in range(n):
        f = plant.feedback()
        c = float(cmd[k])
        u = pid.calc(servo, c, f)
        fb[k] = f
        out[k] = u
        sat[k] = pid.saturated
        plant.advance(u)
        if not abs(c - f) <= limit or plant.diverged:  # also catches NaN
            diverged = True
            break
    m = k + 1 if n else 0
    prev = np.concatenate(([0.0], cmd[: m - 1])) if m else cmd[:0]
    return LoopResult(
        servo_ns=servo,
        command=cmd[:m],
        feedback=fb[:m],
        output=out[:m],
        ferror=prev - fb[:m],
        saturated=sat[:m],
        diverged=diverged,
    )


@dataclass(frozen=True)
class FerrorCheck:
    """LinuxCNC's following-error check over a run (reference §4.4).

    ``ok``: |ferror| ≤ limit in every period; ``worst_ratio``: max |ferror|/limit and its time.
    """

    ferror_limit: float
    min_ferror: float
    max_velocity: float
    ok: bool
    worst_ratio: float
    worst_t_s: float
    first_fail_t_s: float | None
    notes: tuple[str, ...] = field(default_factory=tuple)


def ferror_check(
    result: LoopResult, ferror: float, min_ferror: float | None, max_velocity: float | None
) -> FerrorCheck:
    """Check ``result`` against [JOINT_n]FERROR/MIN_FERROR as LinuxCNC's motion does.

    limit_k = max(FERROR·|v_k| / MAX_VELOCITY, MIN_FERROR), v_k the commanded velocity
    (c_k − c_{k−1})/T; MIN_FERROR defaults to FERROR (a constant limit). ``max_velocity`` is the
    joint's MAX_VELOCITY (None: the command's own peak speed, noted).
    """
    notes: list[str] = []
    if not (ferror > 0 and math.isfinite(ferror)):
        raise ConfigError(f"FERROR {ferror!r} must be > 0")
    mn = ferror if min_ferror is None else min_ferror
    if not (mn >= 0 and math.isfinite(mn)):
        raise ConfigError(f"MIN_FERROR {min_ferror!r} must be >= 0")
    t = result.servo_ns * 1e-9
    vel = np.abs(np.diff(result.command, prepend=0.0)) / t
    vmax = max_velocity
    if vmax is None or vmax <= 0:
        vmax = float(vel.max()) if len(vel) else 0.0
        notes.append(f"MAX_VELOCITY not given: the command's peak speed {vmax:g} units/s is used")
    scaled = ferror * vel / vmax if vmax > 0 else np.zeros_like(vel)
    limit = np.maximum(scaled, mn)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(limit > 0, np.abs(result.ferror) / limit, np.inf * np.abs(result.ferror))
    # 0 error within a 0 limit is fine (inf·0 = NaN there); a NaN error never is
    ratio = np.where(np.isnan(result.ferror), np.inf, np.nan_to_num(ratio, nan=0.0, posinf=np.inf))
    bad = np.flatnonzero(ratio > 1.0)
    k = int(np.argmax(ratio)) if len(ratio) else 0
    return FerrorCheck(
        ferror_limit=ferror,
        min_ferror=mn,
        max_velocity=vmax,
        ok=len(bad) == 0,
        worst_ratio=float(ratio[k]) if len(ratio) else 0.0,
        worst_t_s=k * t,
        first_fail_t_s=None if len(bad) == 0 else int(bad[0]) * t,
        notes=tuple(notes),
    )


@dataclass(frozen=True)
class StepMetrics:
    """A step response's figures (times in s from the step; overshoot as a fraction of it).

    ``settling_s`` is None when the response is still outside the band at the end.
    """

    rise_s: float | None
    overshoot: float
    settling_s: float | None
    steady_state_error: float
    band: float


def step_metrics(
    t_s: np.ndarray,
    y: np.ndarray,
    start: float,
    target: float,
    t_step: float = 0.0,
    band: float = 0.02,
) -> StepMetrics:
    """Rise time (10 → 90 %), overshoot, settling into ±band·|step|, and the steady-state error
    (target − mean of the last 10 % of the samples) of ``y`` stepping from ``start`` to ``target``.
    """
    size = target - start
    if size == 0:
        raise ConfigError("a step response needs a nonzero step")
    after = t_s >= t_step
    tt, yy = t_s[after] - t_step, (y[after] - start) / size  # normalised: 0 → 1
    if len(yy) == 0 or not np.all(np.isfinite(yy)):
        return StepMetrics(None, math.inf, None, math.inf, band)
    i10 = np.flatnonzero(yy >= 0.1)
    i90 = np.flatnonzero(yy >= 0.9)
    rise = float(tt[i90[0]] - tt[i10[0]]) if len(i10) and len(i90) else None
    overshoot = max(float(yy.max()) - 1.0, 0.0)
    outside = np.flatnonzero(np.abs(yy - 1.0) > band)
    if len(outside) == 0:
        settling: float | None = 0.0
    elif outside[-1] == len(yy) - 1:
        settling = None
    else:
        settling = float(tt[outside[-1] + 1])
    tail = yy[-max(len(yy) // 10, 1) :]
    sse = float((1.0 - tail.mean()) * size)
    return StepMetrics(rise, overshoot, settling, sse, band)


@dataclass(frozen=True)
class Oscillation:
    """The oscillation of an error signal around its final value.

    ``sustained``: the half-cycle peaks no longer decay (per-cycle ratio ≥ threshold, or the
    error diverged); ``ratio``: amplitude ratio per full cycle over the second half of the
    record; ``period_s``: the mean full-cycle period (None: fewer than 4 zero crossings).
    """

    sustained: bool
    ratio: float
    period_s: float | None
    amplitude: float
    half_cycles: int


def oscillation(
    e: np.ndarray,
    servo_ns: int,
    min_amplitude: float,
    threshold: float = 0.95,
    diverged: bool = False,
) -> Oscillation:
    """Detect sustained oscillation of ``e`` (units) sampled every servo period.

    Half-cycles are the runs between sign changes of ``e``; each has a peak |e|. Peaks below
    ``min_amplitude`` (encoder counts, friction limit cycles) are not oscillation. The ratio is
    (last peak / first peak)^(1/cycles) over the later half of the half-cycles.
    """
    t = servo_ns * 1e-9
    if diverged:
        return Oscillation(True, math.inf, None, math.inf, 0)
    s = np.sign(e)
    nz = np.flatnonzero(s != 0)
    if len(nz) < 2:
        return Oscillation(False, 0.0, None, 0.0, 0)
    sn = s[nz]
    cross = nz[np.flatnonzero(sn[1:] != sn[:-1]) + 1]  # first sample of each new half-cycle
    bounds = np.concatenate(([nz[0]], cross, [len(e)]))
    peaks = np.array([np.abs(e[a:b]).max() for a, b in zip(bounds[:-1], bounds[1:], strict=True)])
    peaks = peaks[:-1] if len(peaks) > 1 else peaks  # the last half-cycle may be cut short
    big = peaks >= min_amplitude
    half = len(peaks)
    period = float(2 * np.mean(np.diff(cross)) * t) if len(cross) >= 4 else None
    if half < 6 or not big[-1]:
        return Oscillation(False, 0.0, period, float(peaks[-1]) if half else 0.0, half)
    later = peaks[half // 2 :]
    cycles = (len(later) - 1) / 2
    ratio = float((later[-1] / later[0]) ** (1.0 / cycles)) if cycles > 0 and later[0] > 0 else 0.0
    return Oscillation(ratio >= threshold, ratio, period, float(later[-1]), half)
