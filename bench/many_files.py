"""Many small captures in one ``check`` call (issue 18: 1000 small VCDs ≤ 1.5 s wall on 2 cores).

``python bench/many_files.py [--files 1000] [--jobs 1 2] [--runs 3]`` writes ``--files`` small
simulator VCDs (STEP/DIR, 200 steps each with a reversal and one short DIR setup every tenth
file, by the project's VCD writer) into ``bench/data/many/`` once, then times, interleaved,
``wavecheck check 'bench/data/many/*.vcd' --drive gecko-g202 --map step=STEP,dir=DIR -j N``
for each N, with the JSON report to a file (``-o``), which is checked to hold every capture in
input order. Prints one JSON line: median wall and CPU per N, ms per file, the goal and
PASS/MISS for 2 jobs, and the load.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from wavecheck.capture.vcd.writer import VcdWire, write_vcd  # noqa: E402

GOAL_S = 1.5


def make_files(folder: Path, count: int) -> list[Path]:
    """``count`` small VCDs (made once; the folder is reused when it holds them already)."""
    folder.mkdir(parents=True, exist_ok=True)
    paths = [folder / f"run{k:05d}.vcd" for k in range(count)]
    for k, path in enumerate(paths):
        if path.exists():
            continue
        rising = 10_000 + 20_000 * np.arange(200, dtype=np.int64)
        step = np.sort(np.concatenate([rising, rising + 5_000]))
        flip = int(rising[100]) - (1_000 if k % 10 == 0 else 8_000)  # every tenth: a short setup
        write_vcd(
            path,
            [VcdWire("STEP", 0, step), VcdWire("DIR", 0, np.array([flip], dtype=np.int64))],
            timescale="1 ns",
            end=int(step[-1]) + 10_000,
            scope="top",
        )
    return paths


def run_once(pattern: str, jobs: int, out: Path) -> tuple[float, float, int]:
    """Wall and CPU seconds (children included: the workers) and the exit code."""
    argv = [sys.executable, "-m", "wavecheck", "check", pattern, "--drive", "gecko-g202",
            "--map", "step=STEP,dir=DIR", "-j", str(jobs), "--format", "json", "-o", str(out)]  # fmt: skip
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    proc = subprocess.run(argv, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, check=False)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    if proc.returncode not in (0, 1):
        raise SystemExit(f"exit {proc.returncode}: {proc.stderr.decode()[-500:]}")
    return wall, cpu, proc.returncode


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--files", type=int, default=1000)
    ap.add_argument("--jobs", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--runs", type=int, default=3)
    args = ap.parse_args()
    folder = ROOT / "bench" / "data" / f"many{args.files}"
    paths = make_files(folder, args.files)
    pattern = str(folder / "*.vcd")
    walls: dict[int, list[float]] = {j: [] for j in args.jobs}
    cpus: dict[int, list[float]] = {j: [] for j in args.jobs}
    load = os.getloadavg()[0]
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "report.json"
        for _ in range(args.runs):
            for j in args.jobs:
                wall, cpu, _ = run_once(pattern, j, out)
                walls[j].append(wall)
                cpus[j].append(cpu)
                doc = json.loads(out.read_text())
                got = [r["capture"]["path"] for r in doc["reports"]]
                assert got == [str(p) for p in paths], "reports out of input order"
    result: dict[str, object] = {"files": args.files, "load_1min": round(load, 2)}
    for j in args.jobs:
        w = statistics.median(walls[j])
        result[f"j{j}_wall_s"] = round(w, 3)
        result[f"j{j}_cpu_s"] = round(statistics.median(cpus[j]), 3)
        result[f"j{j}_ms_per_file"] = round(1000 * w / args.files, 2)
    if 2 in walls:
        w2 = statistics.median(walls[2])
        result["goal"] = f"{args.files} files ≤ {GOAL_S} s wall with -j 2"
        result["verdict"] = "PASS" if w2 <= GOAL_S else "MISS"
    print(json.dumps(result))


if __name__ == "__main__":
    main()
