"""LinuxCNC's software ``stepgen`` — the plain, per-period reference model.

This module is a line-by-line behavioural model of ``src/hal/components/stepgen.c`` as
specified in ``shared/reference/stepgen-linuxcnc.md`` (§1–§7; section numbers below refer to
it). It is deliberately written like the C: one object per HAL component with its module-level
statics, one state object per channel, and the three HAL functions ``make_pulses``,
``update_freq`` and ``capture_position``. Integers stay integers (the 64-bit accumulator, the
nanosecond timers, ``addval``); doubles are Python floats, which are IEEE doubles like C's, and
double→long conversions truncate toward zero as C does.

The fast engine (:mod:`stepgen.fast`) must produce exactly the same edges as
:func:`run_reference`; a property test checks this.

Units: times in integer nanoseconds; ``freq`` in steps/s; ``maxvel`` in position units/s;
``maxaccel`` in position units/s²; ``accum``/``addval`` in 2^-28 step.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from decimal import Decimal
from typing import Literal

import numpy as np

from wavecheck.errors import ConfigError
from wavecheck.steptypes import StepType, step_type

__all__ = [
    "HALF_STEP",
    "ONE_STEP",
    "PICKOFF",
    "STARTUP_BASE_NS",
    "STARTUP_SERVO_NS",
    "Channel",
    "Component",
    "InvocationRun",
    "StepgenConfig",
    "final_state",
    "hal_thread_period",
    "run_from_arrays",
    "run_reference",
    "ulceil",
    "update_schedule",
]

PICKOFF = 28
ONE_STEP = 1 << PICKOFF  #: accumulator units per step
HALF_STEP = 1 << (PICKOFF - 1)  #: accum starts here (§1)
STARTUP_BASE_NS = 50_000  #: periodns assumed until make-pulses has run once (§3)
STARTUP_SERVO_NS = 1_000_000  #: update-freq's dt until its first call (§3)
U32_MAX = 0xFFFF_FFFF
_NEVER = (
    U32_MAX  # "old_*" sentinel (~0 in the C) so every timing param is rounded on the first call
)

ThreadOrder = Literal["update-first", "pulses-first"]
Mode = Literal["position", "velocity"]


def ulceil(value: int, increment: int) -> int:
    """Round ``value`` (ns) up to a multiple of ``increment`` (ns); 0 stays 0 (§3)."""
    if value == 0:
        return 0
    return increment * ((value - 1) // increment + 1)


def hal_thread_period(base_ns: int, period_ns: int) -> int:
    """A slower thread's real period: HAL rounds it half-up to n·base (§1, [HL]).

    ``hal_thread_period(30_000, 1_000_000) == 990_000``.

    Raises:
        ConfigError: the slower thread is faster than the base thread (HAL refuses it).
    """
    if period_ns < base_ns:
        raise ConfigError(
            f"servo period {period_ns} ns is shorter than the base period {base_ns} ns "
            "(HAL refuses it; use a servo period >= the base period)"
        )
    n = (period_ns + base_ns // 2) // base_ns
    return n * base_ns


def _c_long(x: float) -> int:
    """C's double → long conversion: truncation toward zero."""
    return int(x)


#: Longest thread period accepted (ns): LinuxCNC's threads run every few µs to a few ms.
MAX_THREAD_PERIOD_NS = 10**9


@dataclass(frozen=True)
class StepgenConfig:
    """One stepgen channel and its threads, as set with ``loadrt``/``setp`` and ``addf``.

    Timing params are the *requested* values in ns (LinuxCNC's u32 params; 0 and the 1 ns
    defaults are allowed); the model rounds them as update-freq does. ``servo_period_ns`` is the
    requested servo thread period; HAL rounds it to n·base (:func:`hal_thread_period`). A servo
    period equal to the base period is LinuxCNC's single-thread set-up (``tests/stepgen.0``).
    """

    step_type: int = 0
    user_step_type: tuple[int, ...] = ()
    base_period_ns: int = 25_000
    servo_period_ns: int = 1_000_000
    mode: Mode = "position"
    position_scale: float = 1.0
    maxvel: float = 0.0
    maxaccel: float = 0.0
    steplen: int = 1
    stepspace: int = 1
    dirsetup: int = 1
    dirhold: int = 1
    dirdelay: int = 1
    thread_order: ThreadOrder = "update-first"
    enable: bool = True

    def validate(self) -> None:
        """Refuse settings LinuxCNC would refuse or silently repair (one-line ConfigError)."""
        self.kind()  # checks the type and user table
        if self.base_period_ns <= 0:
            raise ConfigError(
                f"base period {self.base_period_ns} ns must be > 0 (e.g. --base-period 25us)"
            )
        if self.servo_period_ns <= 0:
            raise ConfigError(
                f"servo period {self.servo_period_ns} ns must be > 0 (e.g. --servo-period 1ms)"
            )
        for what, value in (("base", self.base_period_ns), ("servo", self.servo_period_ns)):
            if value > MAX_THREAD_PERIOD_NS:
                raise ConfigError(
                    f"{what} period {Decimal(value):.4g} ns is longer than 1 s; LinuxCNC threads run every "
                    "few µs to ms (e.g. --base-period 25us --servo-period 1ms)"
                )
        hal_thread_period(self.base_period_ns, self.servo_period_ns)  # servo >= base
        if self.mode not in ("position", "velocity"):
            raise ConfigError(f"mode {self.mode!r} is not position or velocity")
        if self.thread_order not in ("update-first", "pulses-first"):
            raise ConfigError(
                f"thread order {self.thread_order!r} is not update-first or pulses-first"
            )
        if not math.isfinite(self.position_scale) or abs(self.position_scale) < 1e-20:
            raise ConfigError(
                f"position scale {self.position_scale} is unusable (LinuxCNC would silently use 1.0; "
                "give steps per unit, e.g. --position-scale 200)"
            )
        for name in ("maxvel", "maxaccel"):
            value = getattr(self, name)
            if not math.isfinite(value) or value < 0:
                raise ConfigError(f"--{name} {value} must be >= 0 (0 means no user limit)")
        for name in ("steplen", "stepspace", "dirsetup", "dirhold", "dirdelay"):
            value = getattr(self, name)
            if not isinstance(value, int) or value < 0 or value > U32_MAX:
                raise ConfigError(f"--{name} {value!r} ns is not a u32 ns value (0..{U32_MAX})")

    @property
    def quirk_applies(self) -> bool:
        """True if update-freq runs before the first make-pulses (the start-up quirk, §3)."""
        return self.thread_order == "update-first"

    def kind(self) -> StepType:
        """The :class:`~wavecheck.steptypes.StepType` (raises ConfigError for a bad type)."""
        return step_type(self.step_type, self.user_step_type or None)

    @property
    def servo_ns(self) -> int:
        """The servo period HAL really runs (n·base, §1)."""
        return hal_thread_period(self.base_period_ns, self.servo_period_ns)

    @property
    def servo_multiple(self) -> int:
        """n = servo period / base period."""
        return self.servo_ns // self.base_period_ns


class Channel:
    """The state of one ``stepgen.N`` channel: HAL params/pins and internal variables (§1, §7).

    Attribute names follow ``stepgen.c``. Timing params (``step_len`` …) are in ns and are
    written back by :meth:`Component.update_freq` exactly as LinuxCNC writes them back.
    """

    def __init__(self, config: StepgenConfig) -> None:
        kind = config.kind()
        self.step_type = kind.number
        self.lut: tuple[int, ...] = kind.states
        self.cycle_max = max(kind.cycle - 1, 0)
        self.pos_mode = config.mode == "position"
        # pins
        self.enable = config.enable
        self.pos_cmd = 0.0
        self.vel_cmd = 0.0
        self.counts = 0
        self.pos_fb = 0.0
        self.outbits = 0  #: output pins as bits, in StepType.outputs order
        # params
        self.pos_scale = float(config.position_scale)
        self.old_scale = 0.0
        self.scale_recip = 0.0
        self.maxvel = float(config.maxvel)
        self.maxaccel = float(config.maxaccel)
        self.freq = 0.0
        self.rawcount = 0
        self.step_len = config.steplen
        # storage sharing (§1): types >= 1 keep dirdelay in dir_hold_dly, dir_setup is internal 0;
        # stepspace exists for types 0/1 only.
        self.step_space = config.stepspace if kind.kind != "phases" else 0
        if kind.kind == "step-dir":
            self.dir_hold_dly = config.dirhold
            self.dir_setup = config.dirsetup
        else:
            self.dir_hold_dly = config.dirdelay
            self.dir_setup = 0
        self.old_step_len = _NEVER
        self.old_step_space = _NEVER
        self.old_dir_hold_dly = _NEVER
        self.old_dir_setup = _NEVER
        self.printed_error = False
        # internal state
        self.timer1 = 0
        self.timer2 = 0
        self.timer3 = 0
        self.hold_dds = False
        self.addval = 0
        self.target_addval = 0
        self.deltalim = 0
        self.accum = HALF_STEP
        self.curr_dir = 0
        self.state = 0
        self.old_pos_cmd = 0.0
        self.warnings: list[str] = []


class Component:
    """The ``stepgen`` HAL component: its statics (periodns, freqscale …) and its channels."""

    def __init__(self, configs: Sequence[StepgenConfig]) -> None:
        self.channels = [Channel(c) for c in configs]
        # module statics as initialised in rtapi_app_main (§3 start-up quirk)
        self.periodns = STARTUP_BASE_NS
        self.old_periodns = STARTUP_BASE_NS
        self.periodfp = self.periodns * 0.000000001
        self.freqscale = (1 << PICKOFF) * self.periodfp
        self.accelscale = self.freqscale * self.periodfp
        self.old_dtns = STARTUP_SERVO_NS
        self.dt = self.old_dtns * 0.000000001
        self.recip_dt = 1.0 / self.dt

    # -- make-pulses (base thread, §2) ---------------------------------------------------------
    def make_pulses(self, period: int) -> None:
        """One base-thread invocation; ``period`` = the base thread's nominal period in ns."""
        self.periodns = period
        for ch in self.channels:
            make_pulses_channel(ch, period)

    # -- update-freq (servo thread, §3–§4) -----------------------------------------------------
    def update_freq(self, period: int) -> None:
        """One servo-thread invocation; ``period`` = the servo thread's nominal period in ns."""
        newperiod = False
        if self.periodns != self.old_periodns:
            self.old_periodns = self.periodns
            self.periodfp = self.periodns * 0.000000001
            self.freqscale = (1 << PICKOFF) * self.periodfp
            self.accelscale = self.freqscale * self.periodfp
            newperiod = True
        if period != self.old_dtns:
            self.old_dtns = period
            self.dt = period * 0.000000001
            self.recip_dt = 1.0 / self.dt
        for ch in self.channels:
            update_freq_channel(self, ch, newperiod)

    # -- capture-position (§5) -----------------------------------------------------------------
    def capture_position(self, period: int) -> None:
        """Copy accum to the ``counts`` and ``position-fb`` pins."""
        for ch in self.channels:
            if ch.pos_scale != ch.old_scale:
                ch.old_scale = ch.pos_scale
                if -1e-20 < ch.pos_scale < 1e-20:
                    ch.pos_scale = 1.0
                ch.scale_recip = (1.0 / (1 << PICKOFF)) / ch.pos_scale
            ch.counts = ch.accum >> PICKOFF
            ch.pos_fb = (ch.accum - HALF_STEP) * ch.scale_recip


def make_pulses_channel(ch: Channel, periodns: int) -> bool:
    """make-pulses for one channel, in the order of §2.1; returns True if a step occurred."""
    # 1. count down the timers (saturating); timer3 reaching 0 releases the hold
    if ch.timer1 > 0:
        ch.timer1 = ch.timer1 - periodns if ch.timer1 > periodns else 0
    if ch.timer2 > 0:
        ch.timer2 = ch.timer2 - periodns if ch.timer2 > periodns else 0
    if ch.timer3 > 0:
        if ch.timer3 > periodns:
            ch.timer3 -= periodns
        else:
            ch.timer3 = 0
            ch.hold_dds = False
    # 2. ramp addval toward target by deltalim; reversal check
    if not ch.hold_dds and ch.enable:
        old_addval = ch.addval
        if ch.deltalim != 0:
            if ch.target_addval > old_addval + ch.deltalim:
                new_addval = old_addval + ch.deltalim
            elif ch.target_addval < old_addval - ch.deltalim:
                new_addval = old_addval - ch.deltalim
            else:
                new_addval = ch.target_addval
        else:
            new_addval = ch.target_addval
        ch.addval = new_addval
        if (new_addval >= 0) != (old_addval >= 0) and ch.timer3 != 0:
            ch.hold_dds = True
    # 3. DDS
    step_now = False
    if not ch.hold_dds and ch.enable:
        before = ch.accum
        ch.accum = _wrap64(before + ch.addval)
        step_now = bool((before ^ ch.accum) & ONE_STEP)
        ch.rawcount = ch.accum >> PICKOFF
    # 4. direction, only once timer2 has expired
    if ch.timer2 == 0:
        if ch.addval > 0:
            ch.curr_dir = 1
        elif ch.addval < 0:
            ch.curr_dir = -1
    # 5. (re)start the timers on a step
    if step_now:
        ch.timer1 = ch.step_len
        ch.timer2 = ch.timer1 + ch.dir_hold_dly
        ch.timer3 = ch.timer2 + ch.dir_setup
        if ch.step_type >= 2:
            ch.state += ch.curr_dir
            if ch.state < 0:
                ch.state = ch.cycle_max
            elif ch.state > ch.cycle_max:
                ch.state = 0
    # 6. outputs
    if ch.step_type == 0:
        ch.outbits = (1 if ch.timer1 != 0 else 0) | (2 if ch.curr_dir < 0 else 0)
    elif ch.step_type == 1:
        if ch.timer1 != 0:
            ch.outbits = 2 if ch.curr_dir < 0 else 1
        else:
            ch.outbits = 0
    else:
        ch.outbits = ch.lut[ch.state]
    return step_now


def _wrap64(x: int) -> int:
    """Two's-complement wrap to a signed 64-bit value (C ``long long``)."""
    if -(1 << 63) <= x < (1 << 63):
        return x
    return ((x + (1 << 63)) % (1 << 64)) - (1 << 63)


def round_timing(ch: Channel, periodns: int, newperiod: bool) -> None:
    """update-freq's ns → period rounding with write-back (§3)."""
    if newperiod:
        ch.old_step_len = ch.old_step_space = ch.old_dir_hold_dly = ch.old_dir_setup = _NEVER
    if ch.step_len != ch.old_step_len:
        if ch.step_len == 0:
            ch.step_len = 1
        ch.old_step_len = ulceil(ch.step_len, periodns)
        ch.step_len = ch.old_step_len
    if ch.step_space != ch.old_step_space:
        ch.old_step_space = ulceil(ch.step_space, periodns)
        ch.step_space = ch.old_step_space
    if ch.dir_setup != ch.old_dir_setup:
        ch.old_dir_setup = ulceil(ch.dir_setup, periodns)
        ch.dir_setup = ch.old_dir_setup
    if ch.dir_hold_dly != ch.old_dir_hold_dly:
        if ch.dir_hold_dly + ch.dir_setup == 0 and ch.step_type < 2:
            ch.dir_hold_dly = 1
        ch.old_dir_hold_dly = ulceil(ch.dir_hold_dly, periodns)
        ch.dir_hold_dly = ch.old_dir_hold_dly


def update_freq_channel(comp: Component, ch: Channel, newperiod: bool) -> None:
    """update-freq for one channel, in the order of §4 (steps 2–9)."""
    if ch.pos_scale != ch.old_scale:
        ch.old_scale = ch.pos_scale
        if -1e-20 < ch.pos_scale < 1e-20:
            ch.pos_scale = 1.0
        ch.scale_recip = (1.0 / (1 << PICKOFF)) / ch.pos_scale
    if (
        newperiod
        or ch.step_len != ch.old_step_len
        or ch.step_space != ch.old_step_space
        or ch.dir_setup != ch.old_dir_setup
        or ch.dir_hold_dly != ch.old_dir_hold_dly
    ):
        round_timing(ch, comp.periodns, newperiod)
    if not ch.enable:
        if ch.pos_mode:
            ch.old_pos_cmd = ch.pos_cmd * ch.pos_scale
        ch.freq = 0.0
        ch.addval = 0
        ch.target_addval = 0
        return
    dt = comp.dt
    recip_dt = comp.recip_dt
    min_step_period = ch.step_len + ch.step_space
    max_freq = 1.0 / (min_step_period * 0.000000001)
    if ch.maxvel <= 0.0:
        ch.maxvel = 0.0
    else:
        desired_freq = ch.maxvel * abs(ch.pos_scale)
        if desired_freq > max_freq:
            if not ch.printed_error:
                ch.warnings.append(
                    f"requested maximum velocity of {desired_freq} steps/sec is too high; "
                    f"maximum possible frequency is {max_freq} steps/sec"
                )
                ch.printed_error = True
            ch.maxvel = max_freq / abs(ch.pos_scale)
        else:
            max_freq = desired_freq
    max_ac = max_freq * recip_dt
    if ch.maxaccel <= 0.0:
        ch.maxaccel = 0.0
    else:
        if ch.maxaccel * abs(ch.pos_scale) > max_ac:
            ch.maxaccel = max_ac / abs(ch.pos_scale)
        else:
            max_ac = ch.maxaccel * abs(ch.pos_scale)
    if ch.pos_mode:
        pos_cmd = ch.pos_cmd * ch.pos_scale
        new_vel = follow_position(
            pos_cmd, ch.old_pos_cmd, ch.accum, ch.freq, max_freq, max_ac, dt, recip_dt
        )
        ch.old_pos_cmd = pos_cmd
    else:
        new_vel = follow_velocity(ch.vel_cmd * ch.pos_scale, ch.freq, max_freq, max_ac, dt)
    ch.freq = new_vel
    ch.target_addval = _c_long(ch.freq * comp.freqscale)
    ch.deltalim = _c_long(max_ac * comp.accelscale)


def follow_position(
    pos_cmd: float,
    old_pos_cmd: float,
    accum: int,
    curr_vel: float,
    max_freq: float,
    max_ac: float,
    dt: float,
    recip_dt: float,
) -> float:
    """The pre-tuned trapezoidal position follower of §4.2; returns the new frequency (steps/s).

    Args:
        pos_cmd: this period's position command, in steps (``position-cmd · scale``).
        old_pos_cmd: the previous one, in steps.
        accum: the DDS accumulator (2^28 units per step, offset 2^27).
        curr_vel: the previously commanded frequency, steps/s.
        max_freq: the frequency limit, steps/s; max_ac: the acceleration limit, steps/s².
        dt: the servo period in s; recip_dt: 1/dt (the C multiplies by it).
    """
    vel_cmd = (pos_cmd - old_pos_cmd) * recip_dt
    curr_pos = (accum - HALF_STEP) * (1.0 / (1 << PICKOFF))
    match_ac = max_ac if vel_cmd > curr_vel else -max_ac
    match_time = (vel_cmd - curr_vel) / match_ac
    avg_v = (vel_cmd + curr_vel) * 0.5
    est_out = curr_pos + avg_v * match_time
    est_cmd = pos_cmd + vel_cmd * (match_time - 1.5 * dt)
    est_err = est_out - est_cmd
    if match_time < dt:
        if abs(est_err) < 0.0001:
            new_vel = vel_cmd
        else:
            new_vel = vel_cmd - 0.5 * est_err * recip_dt
            if new_vel > curr_vel + max_ac * dt:
                new_vel = curr_vel + max_ac * dt
            elif new_vel < curr_vel - max_ac * dt:
                new_vel = curr_vel - max_ac * dt
    else:
        dv = -2.0 * match_ac * dt
        dp = dv * match_time
        if abs(est_err + dp * 2.0) < abs(est_err):
            match_ac = -match_ac
        new_vel = curr_vel + match_ac * dt
    if new_vel > max_freq:
        new_vel = max_freq
    elif new_vel < -max_freq:
        new_vel = -max_freq
    return new_vel


def follow_velocity(
    vel_cmd: float, curr_vel: float, max_freq: float, max_ac: float, dt: float
) -> float:
    """Velocity mode of §4.1: the command (steps/s) clamped to ±max_freq and ramped by max_ac·dt."""
    if vel_cmd > max_freq:
        vel_cmd = max_freq
    elif vel_cmd < -max_freq:
        vel_cmd = -max_freq
    dv = max_ac * dt
    if vel_cmd > curr_vel + dv:
        return curr_vel + dv
    if vel_cmd < curr_vel - dv:
        return curr_vel - dv
    return vel_cmd


# ---------------------------------------------------------------------------------------------
# Running the threads


def update_schedule(config: StepgenConfig, n_periods: int) -> list[int]:
    """Base invocation index before which each servo update u runs (§3 thread order).

    update-first: update u runs just before make-pulses u·n (LinuxCNC's single thread with
    update-freq first; or the servo thread scheduled first at every common tick).
    pulses-first: just after make-pulses u·n, i.e. before invocation u·n + 1.
    Only updates that precede some invocation < ``n_periods`` are listed.
    """
    n = config.servo_multiple
    first = 0 if config.thread_order == "update-first" else 1
    return list(range(first, n_periods, n))


@dataclass
class InvocationRun:
    """What the base thread did, invocation by invocation (times are applied later by latency).

    ``toggles[pin]`` holds the indices k of the make-pulses invocations after which ``pin``
    differs from its value after invocation k−1 (all pins are 0 before invocation 0).
    ``counts_at``/``counts_val``: invocations where accum>>28 changed and its new value —
    the ``counts`` pin as capture-position would read it right after each make-pulses.
    """

    config: StepgenConfig
    n_periods: int
    pins: tuple[str, ...]
    toggles: dict[str, np.ndarray]
    counts_at: np.ndarray
    counts_val: np.ndarray
    steps: int
    final: dict[str, float | int] = field(default_factory=dict)
    warnings: list[str] = field(default_factory=list)
    fast_chunks: int = 0
    exact_chunks: int = 0


def final_state(comp: Component) -> dict[str, float | int]:
    """The written-back params and the state worth reporting after a run."""
    ch = comp.channels[0]
    return {
        "counts": ch.accum >> PICKOFF,
        "accum": ch.accum,
        "frequency": ch.freq,
        "steplen": ch.step_len,
        "stepspace": ch.step_space,
        "dirsetup": ch.dir_setup,
        "dirhold": ch.dir_hold_dly,
        "maxvel": ch.maxvel,
        "maxaccel": ch.maxaccel,
    }


def run_reference(
    config: StepgenConfig, commands: Sequence[float] | np.ndarray, n_periods: int
) -> InvocationRun:
    """Run the plain per-period model for ``n_periods`` base periods.

    ``commands[u]`` is the position-cmd (position mode, position units) or velocity-cmd
    (velocity mode, units/s) pin value seen by servo update u; the last value is held if the
    sequence is shorter than the number of updates.
    """
    config.validate()
    kind = config.kind()
    comp = Component([config])
    ch = comp.channels[0]
    base = config.base_period_ns
    servo = config.servo_ns
    schedule = set(update_schedule(config, n_periods))
    n_cmd = len(commands)
    u = 0
    outs = np.zeros(n_periods, dtype=np.int64)
    counts = np.zeros(n_periods, dtype=np.int64)
    steps = 0
    for k in range(n_periods):
        if k in schedule:
            value = float(commands[min(u, n_cmd - 1)]) if n_cmd else 0.0
            if ch.pos_mode:
                ch.pos_cmd = value
            else:
                ch.vel_cmd = value
            comp.update_freq(servo)
            u += 1
        comp.periodns = base
        if make_pulses_channel(ch, base):
            steps += 1
        outs[k] = ch.outbits
        counts[k] = ch.accum >> PICKOFF
    run = run_from_arrays(config, kind, outs, counts, steps)
    run.final = final_state(comp)
    run.warnings = list(ch.warnings)
    return run


def run_from_arrays(
    config: StepgenConfig, kind: StepType, outs: np.ndarray, counts: np.ndarray, steps: int
) -> InvocationRun:
    """An :class:`InvocationRun` from each invocation's output bits (``outs``, bit i = pin i of
    ``kind.outputs``) and ``counts``: the toggle and counts-change indices (``final`` and
    ``warnings`` left for the caller)."""
    toggles: dict[str, np.ndarray] = {}
    prev = np.concatenate(([0], outs[:-1])) if len(outs) else outs
    changed = outs ^ prev
    for bit, pin in enumerate(kind.outputs):
        toggles[pin] = np.flatnonzero((changed >> bit) & 1).astype(np.int64)
    cprev = np.concatenate(([0], counts[:-1])) if len(counts) else counts
    at = np.flatnonzero(counts != cprev).astype(np.int64)
    return InvocationRun(
        config=config,
        n_periods=len(outs),
        pins=kind.outputs,
        toggles=toggles,
        counts_at=at,
        counts_val=counts[at].astype(np.int64),
        steps=steps,
    )
