"""``stepgen simulate`` with a VCD out, end to end in one process (issue 18): simulate 20 s at a
25 µs base period, then write the VCD with the numpy writer and, on the same trace, with pyvcd
(the writer it replaced). Prints one JSON line: CPU seconds of each step (best of ``--repeat``,
interleaved) and the real-time factors; checks the two files are byte-identical.

    .venv/bin/python bench/stepgen_vcd.py [--seconds 20] [--repeat 3]
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path
from unittest import mock

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from stepgen.motion import Motion  # noqa: E402
from stepgen.reference import StepgenConfig  # noqa: E402
from stepgen.simulate import simulate  # noqa: E402
from stepgen.vcdout import write_vcd  # noqa: E402
from wavecheck.capture.vcd import writer  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=20.0)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    base = 25_000
    n = int(args.seconds * 1e9) // base
    cfg = StepgenConfig(base_period_ns=base, servo_period_ns=1_000_000, mode="position",
                        position_scale=1000, maxvel=15, maxaccel=100, thread_order="pulses-first")  # fmt: skip
    t = np.arange(n // 40 + 2) * 1e-3  # as bench_stepgen.py: a slow sine, ±10 units
    motion = Motion("csv", csv_times=t, csv_values=10 * np.sin(t))
    sim, fast, ref = [], [], []
    with tempfile.TemporaryDirectory() as d:
        for _ in range(args.repeat):
            c0 = time.process_time()
            trace = simulate(cfg, motion, "uniform:10us", n_periods=n, seed=1)
            sim.append(time.process_time() - c0)
            c0 = time.process_time()
            changes = write_vcd(trace, Path(d) / "fast.vcd")
            fast.append(time.process_time() - c0)
            with mock.patch.object(writer, "_fast_covers", lambda *a: False):
                c0 = time.process_time()
                write_vcd(trace, Path(d) / "pyvcd.vcd")
                ref.append(time.process_time() - c0)
        same = (Path(d) / "fast.vcd").read_bytes() == (Path(d) / "pyvcd.vcd").read_bytes()
        size = (Path(d) / "fast.vcd").stat().st_size
    secs = n * base * 1e-9
    out = {
        "simulated_s": secs, "periods": n, "changes": changes, "vcd_bytes": size,
        "simulate_cpu_s": min(sim), "write_cpu_s": min(fast), "pyvcd_write_cpu_s": min(ref),
        "end_to_end_realtime": secs / (min(sim) + min(fast)),
        "pyvcd_end_to_end_realtime": secs / (min(sim) + min(ref)),
        "simulate_only_realtime": secs / min(sim), "byte_identical": same,
    }  # fmt: skip
    print(json.dumps(out))
    if not same:
        sys.exit("the numpy writer and pyvcd disagree")


if __name__ == "__main__":
    main()
