"""Captures with a known lateness for the lattice tests: stepgen model runs (stepgen/lateness.py's
models), seen by an analyzer at a sample rate (an edge at the first sample at or after it)."""

from __future__ import annotations

from fractions import Fraction

import numpy as np

from stepgen.motion import Motion, parse_moves
from stepgen.reference import StepgenConfig
from stepgen.simulate import Trace, simulate
from wavecheck.capture.edges import Capture, Channel
from wavecheck.timebase import Timebase


def run(
    base_ns: int,
    latency: str,
    seed: int = 1,
    *,
    step_type: int = 0,
    periods: int = 6000,
    moves: str = "0.6, pause 5ms, 0.25, pause 3ms, 0.5",
    vel: float = 20.0,
    accel: float = 600.0,
    active_edge: str = "rising",
    steplen_ns: int = 1,
) -> Trace:
    """A short run with ramps, cruises at up to the maximum step rate and reversals."""
    cfg = StepgenConfig(
        base_period_ns=base_ns,
        servo_period_ns=1_000_000,
        position_scale=1000,
        maxvel=0,
        maxaccel=0,
        mode="position",
        step_type=step_type,
        steplen=steplen_ns,
        thread_order="pulses-first",  # two threads: the base thread ticks first (no 50 us quirk)
    )
    motion = Motion("moves", segments=parse_moves(moves, vel, accel))
    return simulate(cfg, motion, latency, n_periods=periods, seed=seed, active_edge=active_edge)


def capture(trace: Trace, rate_hz: int | None = None) -> Capture:
    """``trace`` as an analyzer at ``rate_hz`` sees it (None: an exact 1 ns VCD)."""
    chans = []
    for i, pin in enumerate(trace.pins):
        ns = trace.edges[pin]
        ticks = ns if rate_hz is None else np.unique(-((-ns * rate_hz) // 10**9))
        if len(ticks) != len(ns):  # two toggles in one sample cancel out
            raise AssertionError(f"{pin}: edges closer than a sample at {rate_hz} Hz")
        chans.append(Channel(pin, i, 0, ticks.astype(np.int64)))
    tb = Timebase(Fraction(1, 10**9) if rate_hz is None else Fraction(1, rate_hz))
    end = trace.end_ns if rate_hz is None else trace.end_ns * rate_hz // 10**9 + 1
    return Capture(
        path=f"{trace.latency.text}@{rate_hz or 'exact'}",
        format="vcd" if rate_hz is None else "sr",
        timebase=tb,
        resolution_ticks=0 if rate_hz is None else 1,
        samplerate_hz=None if rate_hz is None else Fraction(rate_hz),
        start=0,
        end=int(end),
        channels=chans,
    )


def roles(trace: Trace) -> dict[str, str]:
    """Every pin is the role of its name."""
    return {p: p for p in trace.pins}


def true_lateness(trace: Trace) -> int:
    """The worst lateness the capture can show (ns): t_k − k·P over the invocations that made
    an edge, from the least of them."""
    idx = np.unique(np.concatenate([trace.run.toggles[p] for p in trace.pins]))
    t = np.unique(np.concatenate([trace.edges[p] for p in trace.pins]))
    late = t - idx * trace.base_period_ns
    return int(late.max() - late.min())
