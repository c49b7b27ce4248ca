"""Benchmark: one minute of LinuxCNC stepgen at a 25 µs base period (2.4 M periods).

Target (issue 4): >= 100x real time, i.e. 2.4 M periods in <= 0.6 s. Prints periods/s and the
real-time factor for the fast engine, the reference loop (on a slice), and the VCD writer.

    .venv/bin/python bench/bench_stepgen.py [--seconds 60] [--no-vcd]
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np

from stepgen.motion import Motion
from stepgen.reference import StepgenConfig, run_reference
from stepgen.simulate import simulate
from stepgen.vcdout import write_vcd


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--seconds", type=float, default=60.0)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--no-vcd", action="store_true")
    args = ap.parse_args()
    base = 25_000
    n = int(args.seconds * 1e9) // base
    cfg = StepgenConfig(
        base_period_ns=base,
        servo_period_ns=1_000_000,
        mode="position",
        position_scale=1000,
        maxvel=15,
        maxaccel=100,
        thread_order="pulses-first",
    )
    # position mode following a slow sine: ±10 units, ~10 kHz peak, reversals every ~3 s
    t = np.arange(n // 40 + 2) * 1e-3
    motion = Motion("csv", csv_times=t, csv_values=10 * np.sin(t))
    best = float("inf")
    trace = None
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        trace = simulate(cfg, motion, "uniform:10us", n_periods=n, seed=1)
        best = min(best, time.perf_counter() - t0)
    assert trace is not None
    sim_s = n * base * 1e-9
    print(
        f"fast engine: {n} periods ({sim_s:g} s simulated) in {best:.3f} s (best of {args.repeat}): "
        f"{n / best / 1e6:.2f} M periods/s, {sim_s / best:.0f}x real time; "
        f"{trace.steps} steps, {trace.run.exact_chunks} exact / {trace.run.fast_chunks} fast servo periods"
    )
    m = 100_000
    t0 = time.perf_counter()
    run_reference(cfg, motion.commands(m // 40 + 1, 1_000_000, "position"), m)
    ref = time.perf_counter() - t0
    print(
        f"reference loop: {m / ref / 1e6:.3f} M periods/s, {m * base * 1e-9 / ref:.1f}x real time"
    )
    if not args.no_vcd:
        with tempfile.TemporaryDirectory() as d:
            t0 = time.perf_counter()
            changes = write_vcd(trace, Path(d) / "bench.vcd")
            w = time.perf_counter() - t0
            size = (Path(d) / "bench.vcd").stat().st_size
        print(
            f"VCD writer: {changes} changes in {w:.2f} s = {changes / w / 1e6:.2f} M changes/s, {size / 1e6:.0f} MB"
        )


if __name__ == "__main__":
    main()
