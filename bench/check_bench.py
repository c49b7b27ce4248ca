"""Time the check engine alone over an edge-array file; print one JSON line.

``python bench/check_bench.py FILE.npz [--repeat N] [--drive ID]``: builds a
:class:`~wavecheck.capture.edges.Capture` from the STEP/DIR arrays written by
``bench/gen.py`` (no file reading), then runs :func:`wavecheck.check` (a capture in memory: one block) — decode,
every rule, the step-rate figures — and the JSON renderer, ``N`` times. Reports the median wall
and CPU (``process_time``: work done by this one process, which runs on one core: the numpy
calls used here are single-threaded) and edges/s.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import time
from fractions import Fraction

import numpy as np

from wavecheck.api import check
from wavecheck.capture.edges import Capture, Channel
from wavecheck.drives.library import load_drive
from wavecheck.report.json import render_json
from wavecheck.timebase import Timebase


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("npz")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--drive", default="gecko-g202")
    args = ap.parse_args()
    z = np.load(args.npz)
    step, dirt, hz = z["step"], z["dir"], int(z["tick_hz"])
    cap = Capture(
        path=args.npz,
        format="sr",
        timebase=Timebase.from_samplerate(hz),
        resolution_ticks=1,
        samplerate_hz=Fraction(hz),
        start=0,
        end=int(max(step[-1], dirt[-1])) + 1,
        channels=[
            Channel(name="STEP", index=0, initial=0, edges=step),
            Channel(name="DIR", index=1, initial=0, edges=dirt),
        ],
    )
    drive = load_drive(args.drive)
    nedges = len(step) + len(dirt)
    walls: list[float] = []
    cpus: list[float] = []
    render_walls: list[float] = []
    syss: list[float] = []
    report = None
    for _ in range(args.repeat):
        t0, c0, s0 = time.perf_counter(), time.process_time(), os.times().system
        report = check(cap, drive, map={"step": "STEP", "dir": "DIR"})
        t1, c1, s1 = time.perf_counter(), time.process_time(), os.times().system
        render_json(report, 100)
        t2 = time.perf_counter()
        walls.append(t1 - t0)
        cpus.append(c1 - c0)
        syss.append(s1 - s0)
        render_walls.append(t2 - t1)
    assert report is not None
    wall, cpu = statistics.median(walls), statistics.median(cpus)
    print(
        json.dumps(
            {
                "edges": nedges,
                "steps": report.steps.count,
                "rules": [r.rule for r in report.rules],
                "violations": report.total_violations,
                "verdict": str(report.verdict),
                "wall_s": wall,
                "cpu_s": cpu,
                "walls": walls,
                "cpus": cpus,
                "sys": syss,
                "render_json_s": statistics.median(render_walls),
                "edges_per_s_cpu": nedges / cpu if cpu else None,
            }
        )
    )


if __name__ == "__main__":
    main()
