"""One command run by an older tree and by this one, interleaved, in the same minutes: the fair
before/after on a machine shared with other users (``make bench`` rows each come from one run).

The older tree is ``git archive COMMIT`` unpacked once into ``$TMPDIR/wavecheck-tree-COMMIT/``
(and compiled; outside the checkout, whose tests scan every module in it); both run with this checkout's interpreter and packages, the tree's own directory
first on ``sys.path``. CPU is the child's user + sys from ``wait4`` (µs, not ``time``'s 10 ms),
best and median of ``--runs``; the load (1 min) is printed at the start and the end.

    .venv/bin/python bench/before_after.py adc30fc --runs 15 -- stepgen simulate --command …
    .venv/bin/python bench/before_after.py adc30fc --peer 'python -c "import numpy"' -- wavecheck drives

The first word after ``--`` is ``wavecheck`` or ``stepgen`` (run as ``main()`` of that tree's
CLI with ``sys.argv`` set, as the console script runs it). ``--peer`` adds a shell command run in the same loop (e.g. the row's peer).
"""

from __future__ import annotations

import argparse
import os
import shlex
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent


def tree(commit: str) -> Path:
    """The tree of ``commit``, unpacked (and compiled) once."""
    rev = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", commit],
                         capture_output=True, text=True, check=True).stdout.strip()  # fmt: skip
    dest = Path(tempfile.gettempdir()) / f"wavecheck-tree-{rev}"
    if not (dest / "wavecheck").is_dir():
        dest.mkdir(parents=True, exist_ok=True)
        archive = subprocess.run(["git", "-C", str(ROOT), "archive", rev],
                                 capture_output=True, check=True).stdout  # fmt: skip
        subprocess.run(["tar", "-x", "-C", str(dest)], input=archive, check=True)
        subprocess.run([sys.executable, "-m", "compileall", "-q", "wavecheck", "stepgen"],
                       cwd=dest, check=True)  # fmt: skip
    return dest


def cpu_of(cmd: list[str]) -> float:
    """CPU seconds (user + sys) of ``cmd`` and its children, output discarded."""
    p = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    _, status, use = os.wait4(p.pid, 0)
    if os.waitstatus_to_exitcode(status) not in (0, 1):
        raise SystemExit(f"{shlex.join(cmd)}: exit {os.waitstatus_to_exitcode(status)}")
    return use.ru_utime + use.ru_stime


def tree_command(tool: str, where: Path, args: list[str]) -> list[str]:
    """``tool ARGS`` (``wavecheck`` or ``stepgen``) run by the tree at ``where``: ``main()`` with
    no argv, as the console script calls it (the collector and allocator tuned then)."""
    code = f"import sys; sys.path.insert(0, sys.argv[1]); from {tool}.cli import main; " \
           f"sys.argv = [{tool!r}, *sys.argv[2:]]; sys.exit(main())"  # fmt: skip
    return [sys.executable, "-c", code, str(where), *args]


def interleaved(cmds: dict[str, list[str]], runs: int) -> tuple[dict[str, list[float]], float]:
    """CPU seconds of each command's ``runs`` runs, one of each in turn; the load at the start."""
    load0 = os.getloadavg()[0]
    cpu: dict[str, list[float]] = {k: [] for k in cmds}
    for _ in range(runs):
        for k, c in cmds.items():
            cpu[k].append(cpu_of(c))
    return cpu, load0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("commit", help="the older tree (e.g. the branch point)")
    ap.add_argument("--runs", type=int, default=15)
    ap.add_argument("--peer", default="", help="a shell command timed in the same loop")
    argv = sys.argv[1:]
    cut = argv.index("--") if "--" in argv else len(argv)
    args = ap.parse_args(argv[:cut])
    words = argv[cut + 1 :]
    if not words or words[0] not in ("wavecheck", "stepgen"):
        raise SystemExit("give -- wavecheck ARGS or -- stepgen ARGS")
    cmds = {
        f"before ({args.commit})": tree_command(words[0], tree(args.commit), words[1:]),
        "after (this tree)": tree_command(words[0], ROOT, words[1:]),
    }
    if args.peer:
        cmds[f"peer: {args.peer}"] = shlex.split(args.peer)
    cpu, load0 = interleaved(cmds, args.runs)
    print(f"$ {shlex.join(words)}   (best of {args.runs}, interleaved; load "
          f"{load0:.1f} -> {os.getloadavg()[0]:.1f})")  # fmt: skip
    for k, v in cpu.items():
        v.sort()
        print(f"  {v[0] * 1e3:7.1f} ms best, {v[len(v) // 2] * 1e3:7.1f} ms median  {k}")


if __name__ == "__main__":
    main()
