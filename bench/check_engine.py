"""Time every rule of the engine (``wavecheck.check``) over a synthetic 10 M-edge STEP capture (issue 7 target: < 1 s).

Run: ``.venv/bin/python bench/check_engine.py [PULSES]`` (default 5 000 000 pulses = 10 M edges).
"""

from __future__ import annotations

import sys
import time
from fractions import Fraction
from pathlib import Path

import numpy as np

from wavecheck.api import check
from wavecheck.capture.edges import Capture, Channel
from wavecheck.drives.datasheet import Drive, Figure
from wavecheck.timebase import Timebase


def main() -> None:
    n = int(sys.argv[1]) if len(sys.argv) > 1 else 5_000_000
    rng = np.random.default_rng(1)
    starts = np.cumsum(25_000 + rng.integers(-11_000, 11_000, n)).astype(np.int64)
    step = np.empty(2 * n, np.int64)
    step[0::2] = starts
    step[1::2] = starts + 5000 + rng.integers(-1000, 1000, n)
    dir_edges = np.sort(rng.choice(starts[:-1] + 12_000, max(n // 100, 1), replace=False))
    cap = Capture(
        "bench",
        "vcd",
        Timebase(Fraction(1, 10**9)),
        1,
        None,
        0,
        int(step[-1]) + 1,
        [Channel("step", 0, 0, step), Channel("dir", 1, 0, dir_edges.astype(np.int64))],
    )
    fig = lambda v: Figure(Fraction(v), "bench", "datasheet")  # noqa: E731
    drive = Drive(
        "g202",
        "Gecko G202",
        Path("g202.toml"),
        "drive",
        "step-dir",
        "falling",
        {
            "step_high": fig(4500),
            "step_low": fig(500),
            "dir_setup": fig(1000),
            "dir_hold": fig(20000),
        },
        fig(200_000),
    )
    best = float("inf")
    for _ in range(3):
        t = time.perf_counter()
        report = check(cap, drive)
        report.violations(1000)
        best = min(best, time.perf_counter() - t)
    edges = len(step) + len(dir_edges)
    print(
        f"{edges} edges, {len(report.rules)} rules: best {best:.3f} s ({edges / best / 1e6:.1f} M edges/s)"
    )


if __name__ == "__main__":
    main()
