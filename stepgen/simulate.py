"""The Python API: run the stepgen model under a latency model and get edges in ns.

>>> from stepgen.simulate import simulate
>>> from stepgen.reference import StepgenConfig
>>> from stepgen.motion import Motion
>>> cfg = StepgenConfig(base_period_ns=100_000, servo_period_ns=100_000, position_scale=32000,
...                     maxvel=0.15, maxaccel=2)
>>> trace = simulate(cfg, Motion("position", 0.04), n_periods=3500)
>>> trace.steps, trace.final_counts
(1280, 1280)

``write_vcd(trace, path)`` / ``write_sr(trace, path)`` (:mod:`stepgen.vcdout`) write it.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from decimal import Decimal
from typing import TYPE_CHECKING

import numpy as np

from stepgen.fast import run_fast
from stepgen.lateness import (
    LatencyModel,
    catchup_for,
    invocation_clock,
    parse_latency,
)
from stepgen.motion import Motion
from stepgen.reference import InvocationRun, StepgenConfig, run_reference, update_schedule
from wavecheck.errors import ConfigError

if TYPE_CHECKING:
    from wavecheck.drives.datasheet import ActiveEdge

__all__ = ["Trace", "n_periods_for", "simulate", "trace_from_run"]


@dataclass
class Trace:
    """A simulated waveform: per pin, the times (ns) at which it toggles; all pins start at 0.

    ``edges[pin]`` is sorted int64 ns; toggle j sets the pin to 1 if j is even, 0 if odd.
    ``counts_t``/``counts_val``: the ``counts`` value (accum>>28 after each make-pulses) and
    when it changed. ``end_ns`` is the end of the simulated span (n_periods·P, or later if a
    latency pushed the last invocation past it).
    """

    config: StepgenConfig
    latency: LatencyModel
    seed: int | None
    active_edge: ActiveEdge
    n_periods: int
    pins: tuple[str, ...]
    edges: dict[str, np.ndarray]
    counts_t: np.ndarray
    counts_val: np.ndarray
    steps: int
    final_counts: int
    end_ns: int
    run: InvocationRun
    seconds: float = 0.0
    notes: list[str] = field(default_factory=list)

    @property
    def base_period_ns(self) -> int:
        """The base thread period P (ns)."""
        return self.config.base_period_ns

    @property
    def servo_period_ns(self) -> int:
        """The HAL-rounded servo period (ns)."""
        return self.config.servo_ns

    def levels_at(self, pin: str, t_ns: np.ndarray) -> np.ndarray:
        """The pin's level just after each time in ``t_ns`` (0/1)."""
        return (np.searchsorted(self.edges[pin], t_ns, side="right") & 1).astype(np.int8)


def n_periods_for(config: StepgenConfig, duration_ns: int) -> int:
    """Base periods needed to cover ``duration_ns`` (ceil)."""
    return -(-int(duration_ns) // config.base_period_ns)


def trace_from_run(
    run: InvocationRun,
    latency: LatencyModel,
    *,
    seed: int | None,
    active_edge: ActiveEdge,
    catchup_ns: int,
    n_periods: int | None = None,
) -> Trace:
    """A :class:`Trace` of ``run``'s first ``n_periods`` base periods (default all), each
    invocation timed by ``latency`` (:func:`~stepgen.lateness.invocation_clock`; catch-up time
    ``catchup_ns``): the edges and ``counts`` changes in ns, the end of the span, the run's
    warnings as notes. The one place a per-period run becomes edge times."""
    n = run.n_periods if n_periods is None else n_periods
    clock = invocation_clock(
        latency, run, seed=seed, active_edge=active_edge, catchup_ns=catchup_ns
    )
    base = run.config.base_period_ns
    at = clock.at
    on_time = clock.offsets is None and clock.times is None
    last_t = (n - 1) * base if on_time else int(at(np.array([run.n_periods - 1]))[0])
    return Trace(
        config=run.config,
        latency=latency,
        seed=seed,
        active_edge=active_edge,
        n_periods=n,
        pins=run.pins,
        edges={pin: at(run.toggles[pin]) for pin in run.pins},
        counts_t=at(run.counts_at),
        counts_val=run.counts_val,
        steps=run.steps,
        final_counts=int(run.final["counts"]),
        end_ns=int(max(n * base, last_t + 1)),
        run=run,
        notes=list(run.warnings),
    )


#: Most base periods one run simulates (per-period index/time arrays: 8 bytes each, a few of them).
MAX_PERIODS = 50_000_000


def simulate(
    config: StepgenConfig,
    motion: Motion,
    latency: LatencyModel | str = "none",
    *,
    n_periods: int,
    seed: int | None = None,
    active_edge: ActiveEdge = "rising",
    catchup_ns: int | None = None,
    engine: str = "fast",
) -> Trace:
    """Simulate ``n_periods`` base periods; returns a :class:`Trace`.

    Args:
        config: the stepgen channel and threads.
        motion: the command pin's values.
        latency: a :class:`LatencyModel` or its string form (``"worst:11us:step_high"``).
        n_periods: base-thread invocations to run (>= 1).
        seed: for the random latency models.
        active_edge: the drive's active STEP edge (worst-case dir_setup/step_period events).
        catchup_ns: run time G of an invocation (see :mod:`stepgen.lateness`); None: 1 µs,
            or P − J under ``worst:J:RULE`` when that is shorter (:func:`~stepgen.lateness.catchup_for`).
        engine: ``"fast"`` or ``"reference"`` (the plain per-period loop; same result, slower).

    Raises:
        ConfigError: bad settings, nothing simulated.
    """
    config.validate()
    if n_periods < 1:
        raise ConfigError(
            f"run length {n_periods} periods must be >= 1 (give --periods or --duration)"
        )
    if n_periods > MAX_PERIODS:
        span_s = Decimal(n_periods) * config.base_period_ns / 10**9
        raise ConfigError(
            f"run length {Decimal(n_periods):.3g} base periods ({span_s:.3g} s) is more than the "
            f"{MAX_PERIODS:.0e} periods one run simulates (per-period arrays would not fit in "
            f"memory; at P = {config.base_period_ns} ns that is "
            f"{MAX_PERIODS * config.base_period_ns / 6e10:.3g} min: give a shorter --duration)"
        )
    model = parse_latency(latency) if isinstance(latency, str) else latency
    if active_edge not in ("rising", "falling"):
        raise ConfigError(f"active edge {active_edge!r} is not rising or falling")
    n_updates = len(update_schedule(config, n_periods))
    cmds = motion.commands(max(n_updates, 1), config.servo_ns, config.mode)
    t0 = time.perf_counter()
    if engine == "fast":
        run = run_fast(config, cmds, n_periods)
    elif engine == "reference":
        run = run_reference(config, cmds, n_periods)
    else:
        raise ConfigError(f"engine {engine!r} is not fast or reference")
    catchup_ns, catchup_note = catchup_for(model, config.base_period_ns, catchup_ns)
    trace = trace_from_run(
        run, model, seed=seed, active_edge=active_edge, catchup_ns=catchup_ns, n_periods=n_periods
    )
    trace.seconds = time.perf_counter() - t0
    trace.notes += motion.notes
    if catchup_note is not None:
        trace.notes.append(catchup_note)
    return trace
