"""What ``pid`` drives in a closed loop: a velocity-mode stepgen, or a true servo motor.

Every plant has the same two-call interface, matching LinuxCNC's servo thread (pid reference
§3 thread order): :meth:`feedback` is the position fed back at the start of a servo period
(``stepgen.capture-position`` / the encoder read), and :meth:`advance` applies pid's output for
one servo period (``stepgen.update-freq`` then make-pulses in the base thread / the amplifier).

- :class:`StepgenPlant`: LinuxCNC's software stepgen (:mod:`stepgen.reference`, the reference
  per-period model) in velocity mode; pid's output is ``velocity-cmd`` (units/s), the feedback
  is ``position-fb`` (with the DDS fraction, stepgen reference §5). It records the output pins
  and ``counts`` of every base period, so the run becomes an ordinary trace (VCD, latency).
- :class:`ServoPlant`: a motor and load, ``J·a = Kt·u − B·v − Fc·sign(v) − F_load`` with ``u``
  pid's output clamped to the amplifier's limit, integrated exactly over each sub-step (the
  linear part is the exact zero-order-hold solution); the feedback is an encoder of N counts per
  unit (``floor(x·N)/N``; N = 0: unquantised). Units: position units (mm, rev …), "force" in any
  unit F consistent with ``Kt`` (F per amplifier unit), ``J`` in F·s²/unit, ``B`` in F·s/unit.
  The encoder's count at each sub-step is recorded for A/B quadrature output
  (:func:`quadrature_edges`, the ``step_type 2`` table of :mod:`wavecheck.steptypes`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from stepgen.reference import (
    Channel,
    Component,
    InvocationRun,
    StepgenConfig,
    final_state,
    make_pulses_channel,
    run_from_arrays,
)
from wavecheck.errors import ConfigError
from wavecheck.steptypes import STATE_TABLES

__all__ = [
    "MAX_ABS_COUNT",
    "MAX_COUNT_CHANGES",
    "QUADRATURE_PINS",
    "Plant",
    "ServoParams",
    "ServoPlant",
    "StepgenPlant",
    "quadrature_edges",
]

#: The encoder's A/B channels (LinuxCNC's ``encoder.N.phase-A``/``phase-B``; bit 0, bit 1).
QUADRATURE_PINS = ("phase-A", "phase-B")
#: Most encoder count changes one recorded run keeps (two Python ints each, then int64 arrays).
MAX_COUNT_CHANGES = 2_000_000
#: The encoder's count range (LinuxCNC's encoder counts are s32; beyond it the loop diverged).
MAX_ABS_COUNT = 2**31


class Plant:
    """The interface a closed loop drives (see the module doc).

    ``diverged``: the plant left the range it can represent (a servo encoder's count range,
    a non-finite position); the loop stops there.
    """

    servo_ns: int
    diverged: bool = False

    def feedback(self) -> float:
        """The position fed back now (start of a servo period), position units."""
        raise NotImplementedError

    def advance(self, u: float) -> None:
        """Apply pid's output ``u`` for one servo period."""
        raise NotImplementedError


class StepgenPlant(Plant):
    """LinuxCNC's software stepgen in velocity mode, one servo period per :meth:`advance`.

    Thread order as :func:`stepgen.reference.update_schedule`: pulses-first runs make-pulses 0
    before the first capture; every :meth:`advance` runs update-freq then n make-pulses.
    ``record``: keep each base period's output bits and counts (:meth:`invocation_run`).
    """

    def __init__(self, config: StepgenConfig, *, record: bool = False) -> None:
        if config.mode != "velocity":
            config = StepgenConfig(**{**config.__dict__, "mode": "velocity"})
        config.validate()
        self.config = config
        self.comp = Component([config])
        self.ch: Channel = self.comp.channels[0]
        self.servo_ns = config.servo_ns
        self.base_ns = config.base_period_ns
        self.n = config.servo_multiple
        self.record = record
        self._outs: list[int] = []
        self._counts: list[int] = []
        self.steps = 0
        if config.thread_order == "pulses-first":
            self._pulse(1)

    def _pulse(self, count: int) -> None:
        ch, base = self.ch, self.base_ns
        outs, counts = self._outs, self._counts
        for _ in range(count):
            self.comp.periodns = base
            if make_pulses_channel(ch, base):
                self.steps += 1
            if self.record:
                outs.append(ch.outbits)
                counts.append(ch.accum >> 28)

    def feedback(self) -> float:
        """``stepgen.capture-position``: position-fb (units, with the DDS fraction)."""
        self.comp.capture_position(self.servo_ns)
        return self.ch.pos_fb

    def advance(self, u: float) -> None:
        """velocity-cmd = u; update-freq; then the base thread's n make-pulses."""
        self.ch.vel_cmd = u
        self.comp.update_freq(self.servo_ns)
        self._pulse(self.n)

    def invocation_run(self, n_periods: int) -> InvocationRun:
        """The recorded base periods (the first ``n_periods``) as an :class:`InvocationRun`."""
        outs = np.asarray(self._outs[:n_periods], dtype=np.int64)
        counts = np.asarray(self._counts[:n_periods], dtype=np.int64)
        run = run_from_arrays(self.config, self.config.kind(), outs, counts, self.steps)
        run.final = final_state(self.comp)
        run.warnings = list(self.ch.warnings)
        return run


@dataclass(frozen=True)
class ServoParams:
    """A servo motor, its load, encoder and amplifier (units in the module doc).

    Attributes:
        inertia: J (F·s²/unit), > 0.
        viscous: B (F·s/unit), >= 0.
        torque_constant: Kt (F per amplifier-command unit), > 0.
        coulomb: Coulomb friction Fc (F), >= 0.
        load: a constant load F_load (F) opposing positive motion (gravity on a Z axis).
        counts_per_unit: encoder counts per position unit (0 = unquantised feedback).
        amp_limit: the amplifier's output limit (command units; 0 = none).
        substeps: integration sub-steps per servo period (the encoder's time resolution).
    """

    inertia: float = 1e-3
    viscous: float = 0.05
    torque_constant: float = 1.0
    coulomb: float = 0.0
    load: float = 0.0
    counts_per_unit: float = 0.0
    amp_limit: float = 0.0
    substeps: int = 8

    def validate(self) -> None:
        """One-line ConfigError for an unusable plant."""
        checks = (
            ("--inertia", self.inertia, self.inertia > 0),
            ("--viscous", self.viscous, self.viscous >= 0),
            ("--torque-constant", self.torque_constant, self.torque_constant > 0),
            ("--coulomb", self.coulomb, self.coulomb >= 0),
            ("--load", self.load, True),
            ("--encoder-counts", self.counts_per_unit, self.counts_per_unit >= 0),
            ("--amp-limit", self.amp_limit, self.amp_limit >= 0),
        )
        for name, value, ok in checks:
            if not (math.isfinite(value) and ok):
                raise ConfigError(f"{name} {value!r} is out of range (see stepgen simulate --help)")
        if not 1 <= self.substeps <= 1000:
            raise ConfigError(f"servo plant substeps {self.substeps} must be 1..1000")


class ServoPlant(Plant):
    """A :class:`ServoParams` motor and load, driven by pid's output as amplifier command."""

    def __init__(self, params: ServoParams, servo_ns: int, *, record: bool = False) -> None:
        params.validate()
        self.p = params
        self.servo_ns = servo_ns
        self.x = 0.0
        self.v = 0.0
        self.record = record
        # one sub-step of the linear part is exact whatever its length; Coulomb friction and a
        # recorded encoder need the finer grid
        self.sub = params.substeps if (params.coulomb > 0 or record) else 1
        self.h = servo_ns * 1e-9 / self.sub
        a = params.viscous / params.inertia
        self._a = a
        self._decay = math.exp(-a * self.h)
        #: (1 − e^{−a h})/a, → h as a → 0
        self._phi = (1.0 - self._decay) / a if a > 0 else self.h
        self._t_counts: list[int] = []
        self._counts: list[int] = []
        self._k = 0
        #: when the recording stopped at :data:`MAX_COUNT_CHANGES` (ns), None: complete
        self.truncated_at_ns: int | None = None
        self.last_count = self._count(0.0)

    def _count(self, x: float) -> int:
        cpu = self.p.counts_per_unit
        if cpu <= 0:
            return 0
        if not abs(x * cpu) < MAX_ABS_COUNT:  # also NaN: the loop diverged
            self.diverged = True
            return self.last_count
        return math.floor(x * cpu)

    def feedback(self) -> float:
        """The encoder position (whole counts / N), or the exact position without an encoder
        (a diverged, non-finite position is fed back as it is)."""
        cpu = self.p.counts_per_unit
        if cpu <= 0 or not math.isfinite(self.x * cpu):
            return self.x
        return math.floor(self.x * cpu) / cpu

    def advance(self, u: float) -> None:
        """Integrate one servo period with the amplifier command ``u`` (clamped)."""
        p = self.p
        lim = p.amp_limit
        if lim > 0:
            u = lim if u > lim else (-lim if u < -lim else u)
        drive = p.torque_constant * u - p.load
        j, b, fc = p.inertia, p.viscous, p.coulomb
        h, decay, phi, a = self.h, self._decay, self._phi, self._a
        x, v = self.x, self.v
        for i in range(self.sub):
            if fc > 0:
                if v == 0.0 and abs(drive) <= fc:
                    force = 0.0  # stuck: static friction holds
                else:
                    s = (1.0 if v > 0 else -1.0) if v != 0.0 else (1.0 if drive > 0 else -1.0)
                    force = drive - fc * s
            else:
                force = drive
            if a > 0:
                v_inf = force / b  # the velocity this force holds against viscous friction
                x_new = x + v_inf * h + (v - v_inf) * phi
                v_new = v_inf + (v - v_inf) * decay
            else:
                acc = force / j
                x_new = x + v * h + 0.5 * acc * h * h
                v_new = v + acc * h
            if fc > 0 and v != 0.0 and (v_new > 0) != (v > 0):
                v_new = 0.0  # friction stops the motion within the sub-step
            x, v = x_new, v_new
            if self.record and not self.diverged and self.truncated_at_ns is None:
                c = self._count(x)
                if c != self.last_count:
                    self._record_counts(c, (self._k * self.sub + i + 1))
        self.x, self.v = x, v
        self._k += 1
        if not math.isfinite(x):
            self.diverged = True

    def _record_counts(self, c: int, sub_index: int) -> None:
        """Spread the counts between the last value and ``c`` evenly over the sub-step."""
        t_end = sub_index * self.servo_ns // self.sub
        t_start = (sub_index - 1) * self.servo_ns // self.sub
        d = c - self.last_count
        n = abs(d)
        if len(self._counts) + n > MAX_COUNT_CHANGES:
            self.truncated_at_ns = t_start  # the recording stops here
            return
        step = 1 if d > 0 else -1
        for j in range(1, n + 1):
            self._t_counts.append(t_start + (t_end - t_start) * j // n)
            self._counts.append(self.last_count + step * j)
        self.last_count = c

    def count_changes(self) -> tuple[np.ndarray, np.ndarray]:
        """(time ns, count) of every encoder count change recorded (one count per entry)."""
        return np.asarray(self._t_counts, dtype=np.int64), np.asarray(self._counts, dtype=np.int64)


def quadrature_edges(
    t_ns: np.ndarray, counts: np.ndarray, initial_count: int = 0
) -> tuple[dict[str, np.ndarray], dict[str, int]]:
    """A/B quadrature of a count sequence (one count per entry), with stepgen type 2's table.

    Returns ({"phase-A": toggle times, "phase-B": toggle times}, initial levels) — the names of
    LinuxCNC's ``encoder`` inputs and of stepgen's type 2 outputs. State s = count mod 4
    gives bits (A = bit 0, B = bit 1) of ``STATE_TABLES[2]`` — what stepgen's type 2 outputs and
    what its decoder reads back.
    """
    table = np.asarray(STATE_TABLES[2][1], dtype=np.int64)
    states = table[np.mod(np.concatenate(([initial_count], counts)), len(table))]
    edges: dict[str, np.ndarray] = {}
    init: dict[str, int] = {}
    for bit, pin in enumerate(QUADRATURE_PINS):
        lv = (states >> bit) & 1
        init[pin] = int(lv[0])
        edges[pin] = t_ns[np.flatnonzero(lv[1:] != lv[:-1])]
    return edges, init
