"""Issue 33: role inference bounded, on captures of many lines that pairwise change in turns.

``python bench/roles_infer.py [--old 2839247] [--timeout 120]`` writes (deterministically) a VCD
of 55 lines of bus data on one clock, ~8 KB as in the issue (``bench/data/bus55.vcd``), and one
of 100 such lines (``bus100.vcd``), and one of 100 square waves at two periods and random
offsets (``waves100.vcd``: any two at one period are quadrature), and one of 50 step/dir axes
that reverse (``axes100.vcd``: every pair tried as STEP and DIR). For each it runs ``wavecheck
info FILE`` with today's tree and with the tree of commit ``--old`` (main before issue 33:
``git archive`` into a temporary folder, removed after the run (an unpacked tree under the
repository would be scanned by tests/architecture), run with ``PYTHONPATH`` on it; stopped after
``--timeout`` seconds), CPU as user + sys of the process, and ``roles.propose`` alone in this
process (CPU). Goal: inference of 100 lines under 1 s (issue 33). Prints one JSON line a file.
"""

from __future__ import annotations

import argparse
import io
import json
import os
import resource
import subprocess
import sys
import tarfile
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(ROOT))

from wavecheck.capture.open import open_capture  # noqa: E402
from wavecheck.roles import propose  # noqa: E402

OLD = "2839247"
GOAL_S = 1.0


def _vcd(path: Path, lines: dict[str, list[int]]) -> Path:
    """A VCD of 1-bit wires starting low, changing at the given ns."""
    ids = {name: f"!{k}" if k < 90 else f'"{k - 90}' for k, name in enumerate(lines)}
    out = ["$timescale 1ns $end", "$scope module tb $end"]
    out += [f"$var wire 1 {ids[n]} {n} $end" for n in lines]
    out += ["$upscope $end", "$enddefinitions $end", "#0", "$dumpvars"]
    out += [f"0{ids[n]}" for n in lines] + ["$end"]
    changes: dict[int, list[str]] = {}
    for n, edges in lines.items():
        for k, t in enumerate(edges):
            changes.setdefault(t, []).append(f"{(k + 1) % 2}{ids[n]}")
    for t in sorted(changes):
        out += [f"#{t}", *changes[t]]
    path.write_text("\n".join(out) + "\n")
    return path


def make_inputs(dest: Path) -> list[Path]:
    dest.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(33)
    clock = np.arange(1, 60) * 100

    def bus(n: int) -> dict[str, list[int]]:
        out = {}
        for i in range(n):
            bits = rng.integers(0, 2, len(clock))
            out[f"d{i}"] = clock[np.flatnonzero(np.diff(np.r_[0, bits]))].tolist()
        return out

    waves = {
        f"w{i}": (np.arange(int(rng.integers(0, 4)), 120, 4 + i % 2) * 100 + i).tolist()
        for i in range(100)
    }

    def axes(n: int) -> dict[str, list[int]]:
        """``n`` step/dir axes (2n lines) that reverse every 8-19 steps, each move speeding up
        and slowing down: every pair is tried as STEP and DIR, up/down and bus."""
        out = {}
        for k in range(n):
            starts: list[int] = []
            dirs: list[int] = []
            t = k * 37_000
            for m in rng.integers(8, 20, 4):
                ramp = [(3.7, 1.55, 1.2)[min(j, m - 1 - j)] if min(j, m - 1 - j) < 3 else 1.0
                        for j in range(m)]  # fmt: skip
                starts += (t + np.cumsum(ramp) * (90 + k) * 1000).astype(int).tolist()
                t = starts[-1] + 5 * (90 + k) * 1000
                dirs.append(t + 3 * (90 + k) * 1000 - 10_000)
            out[f"s{k}"] = [e for x in starts for e in (x, x + 5000)]
            out[f"d{k}"] = dirs[:-1]
        return out

    return [
        _vcd(dest / "bus55.vcd", bus(55)),
        _vcd(dest / "bus100.vcd", bus(100)),
        _vcd(dest / "waves100.vcd", waves),
        _vcd(dest / "axes100.vcd", axes(50)),
    ]


def old_tree(commit: str, dest: Path) -> Path:
    """``wavecheck``, ``stepgen`` and ``rules`` of ``commit``, unpacked into ``dest``."""
    tar = subprocess.run(
        ["git", "archive", commit, "wavecheck", "stepgen", "rules"],
        cwd=ROOT,
        check=True,
        capture_output=True,
    ).stdout
    with tarfile.open(fileobj=io.BytesIO(tar)) as t:
        t.extractall(dest, filter="data")
    return dest


def cpu_of(cmd: list[str], tree: Path, timeout: float) -> float | None:
    """CPU seconds (user + sys) of ``cmd`` run from ``tree`` (``python -m`` imports from the
    working folder first); None when it ran out of time."""
    env = {**os.environ, "PYTHONPATH": str(tree)}
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    try:
        subprocess.run(cmd, env=env, cwd=tree, check=False, capture_output=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return None
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--old", default=OLD)
    parser.add_argument("--timeout", type=float, default=120.0)
    args = parser.parse_args()
    files = make_inputs(HERE / "data" / "roles")
    with tempfile.TemporaryDirectory(prefix=f"wavecheck-{args.old}-") as tmp:
        return run(files, old_tree(args.old, Path(tmp)), args)


def run(files: list[Path], old: Path, args: argparse.Namespace) -> int:
    """Time every file with both trees; print one JSON line each."""
    exe = [sys.executable, "-m", "wavecheck", "info"]
    ok = True
    for f in files:
        cap = open_capture(f)
        t = time.process_time()
        p = propose(cap)
        infer = time.process_time() - t
        new = cpu_of([*exe, str(f)], ROOT, args.timeout)
        was = cpu_of([*exe, str(f)], old, args.timeout)
        passed = infer < GOAL_S
        ok &= passed
        print(
            json.dumps(
                {
                    "file": f.name,
                    "bytes": f.stat().st_size,
                    "lines": len(cap.channels),
                    "propose_cpu_s": round(infer, 3),
                    "axes": len(p.axes),
                    "info_cpu_s": None if new is None else round(new, 3),
                    f"info_cpu_s_{args.old}": (
                        f">{args.timeout:g} (stopped)" if was is None else round(was, 3)
                    ),
                    "goal": f"propose < {GOAL_S:g} s",
                    "verdict": "PASS" if passed else "MISS",
                    "load": round(os.getloadavg()[0], 1),
                }
            ),
            flush=True,
        )
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
