"""Issue 23: 1000 small VCDs, the one engine against the two engines it replaced, in one run.

``python bench/one_engine.py [--files 1000] [--runs 3] [--old 64d4756]`` checks the small VCDs of
``bench/many_files.py`` (200 steps each; every tenth with a short DIR setup) in one call,
``wavecheck check 'bench/data/many1000/*.vcd' --drive gecko-g202 --map step=STEP,dir=DIR -j 1
--format json -o REPORT``, with today's tree and with the tree of commit ``--old`` (main before
issue 23: ``git archive`` into ``$TMPDIR/wavecheck-old-COMMIT/``, run with ``PYTHONPATH`` on it), that
one both as its default (the streamed engine) and with ``--no-stream`` (its whole-capture engine).
Interleaved run by run; CPU is user + sys of the process. Every capture's verdict and step count
must agree across the three. Prints one JSON line: CPU and peak RSS per variant, ms of CPU per
file, the ratio to the old whole path's CPU (goal ≤ 1.0) and PASS/MISS.
"""

from __future__ import annotations

import argparse
import io
import json
import os
import resource
import statistics
import subprocess
import sys
import tarfile
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(ROOT))

from bench.many_files import make_files  # noqa: E402

#: Main before issue 23 (two engines).
OLD = "64d4756"
GOAL = 1.0


def old_tree(commit: str) -> Path:
    """``wavecheck``, ``stepgen`` and ``rules`` of ``commit``, unpacked once under ``$TMPDIR``
    (not in the checkout: tests/architecture scans every module under ``bench/``)."""
    dest = Path(tempfile.gettempdir()) / f"wavecheck-old-{commit}"
    if (dest / "wavecheck" / "__init__.py").exists():
        return dest
    tar = subprocess.run(
        ["git", "archive", "--format=tar", commit, "wavecheck", "stepgen", "rules"],
        cwd=ROOT,
        check=True,
        capture_output=True,
    ).stdout
    dest.mkdir(parents=True, exist_ok=True)
    with tarfile.open(fileobj=io.BytesIO(tar)) as t:
        t.extractall(dest, filter="data")
    return dest


def digest(path: Path) -> list[tuple[str, str, int]]:
    """Each capture's path, verdict and step count from a JSON report."""
    doc = json.loads(path.read_text())
    return [(r["capture"]["path"], r["verdict"], r["steps"]["count"]) for r in doc["reports"]]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--files", type=int, default=1000)
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--old", default=OLD, help=f"the commit of the two engines (default {OLD})")
    args = ap.parse_args()
    paths = make_files(HERE / "data" / f"many{args.files}", args.files)
    pattern = str(paths[0].parent / "*.vcd")
    old = old_tree(args.old)
    env_new = dict(os.environ, PYTHONPATH=str(ROOT))
    env_old = dict(os.environ, PYTHONPATH=str(old))
    base = [sys.executable, "-m", "wavecheck", "check", pattern, "--drive", "gecko-g202",
            "--map", "step=STEP,dir=DIR", "-j", "1", "--format", "json", "-o"]  # fmt: skip
    # the working directory comes first on sys.path under ``python -m``: each tree runs from its own
    variants = {
        "one_engine": ([], env_new, ROOT),
        "old_streamed": ([], env_old, old),
        "old_whole": (["--no-stream"], env_old, old),
    }
    cpu: dict[str, list[float]] = {k: [] for k in variants}
    rss: dict[str, float] = {}
    digests: dict[str, list[tuple[str, str, int]]] = {}
    trees: dict[str, str] = {}
    load = os.getloadavg()[0]
    with tempfile.TemporaryDirectory() as tmp:
        for _ in range(args.runs):
            for name, (extra, env, cwd) in variants.items():
                out = Path(tmp) / f"{name}.json"
                # peak RSS per variant: a fresh child per measurement via a wrapper process
                wrapper = [sys.executable, "-c",
                           "import resource,subprocess,sys,wavecheck;"
                           "r=subprocess.run(sys.argv[1:]).returncode;"
                           "print(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss,"
                           " wavecheck.__file__, file=sys.stderr);sys.exit(r)",
                           *base, str(out), *extra]  # fmt: skip
                before = resource.getrusage(resource.RUSAGE_CHILDREN)
                proc = subprocess.run(wrapper, env=env, cwd=cwd, stdout=subprocess.DEVNULL,
                                      stderr=subprocess.PIPE, text=True)  # fmt: skip
                after = resource.getrusage(resource.RUSAGE_CHILDREN)
                if proc.returncode not in (0, 1):
                    raise SystemExit(f"{name}: exit {proc.returncode}: {proc.stderr[-400:]}")
                cpu[name].append(
                    (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
                )
                kb, used = proc.stderr.strip().splitlines()[-1].split(" ", 1)
                rss[name] = max(rss.get(name, 0.0), int(kb) / 1024)
                digests[name] = digest(out)
                trees[name] = str(Path(used).parent.parent)
    agree = digests["one_engine"] == digests["old_streamed"] == digests["old_whole"]
    med = {k: statistics.median(v) for k, v in cpu.items()}
    ratio = med["one_engine"] / med["old_whole"]
    result = {
        "files": args.files,
        "trees": trees,
        "old_commit": args.old,
        "command": " ".join(base) + " REPORT.json [--no-stream]",
        "load_1min": round(load, 2),
        "cpu_s": {k: round(v, 3) for k, v in med.items()},
        "cpu_ms_per_file": {k: round(1000 * v / args.files, 3) for k, v in med.items()},
        "max_rss_mb": {k: round(v, 1) for k, v in rss.items()},
        "same_verdicts_and_steps": agree,
        "ratio_vs_old_whole": round(ratio, 3),
        "ratio_vs_old_streamed": round(med["one_engine"] / med["old_streamed"], 3),
        "goal": f"CPU per file ≤ {GOAL}× the old whole path's",
        "verdict": "PASS" if ratio <= GOAL and agree else "MISS",
    }
    print(json.dumps(result))


if __name__ == "__main__":
    main()
