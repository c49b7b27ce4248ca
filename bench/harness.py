"""What every benchmark of ``bench/`` shares: commands timed as processes under ``/usr/bin/time
-v``, medians and spreads, and the figures of a run (each with its goal, PASS/MISS, the peer's
figure from the same run and the machine load when it was taken)."""

from __future__ import annotations

import os
import re
import shlex
import statistics
import subprocess
import tempfile
from pathlib import Path
from typing import Any

TIME = "/usr/bin/time"


def sh(cmd: list[str]) -> str:
    return " ".join(shlex.quote(c) for c in cmd)


def timed(cmd: list[str], stdout_path: str | None = None) -> dict[str, Any]:
    """Run ``cmd`` under ``/usr/bin/time -v``; wall seconds and max RSS from it, user/sys
    seconds from ``wait4`` (µs; ``time`` prints 10 ms steps, too coarse for start-up rows:
    they include ``time``'s own ~1 ms), exit code."""
    with tempfile.NamedTemporaryFile("w+", suffix=".time") as tf:
        out = open(stdout_path, "w") if stdout_path else subprocess.DEVNULL  # noqa: SIM115
        try:
            p = subprocess.Popen(
                [TIME, "-v", "-o", tf.name, *cmd], stdout=out, stderr=subprocess.PIPE, text=True
            )
            assert p.stderr is not None
            stderr = p.stderr.read()  # to its end (the child's exit), then reap it here
            p.stderr.close()
            _, status, use = os.wait4(p.pid, 0)
            p.returncode = os.waitstatus_to_exitcode(status)
        finally:
            if stdout_path:
                out.close()  # type: ignore[union-attr]
        text = Path(tf.name).read_text()

    def field(name: str) -> str:
        m = re.search(rf"{re.escape(name)}: (.+)", text)
        return m.group(1).strip() if m else "0"

    wall = field("Elapsed (wall clock) time (h:mm:ss or m:ss)")
    parts = [float(x) for x in wall.split(":")]
    secs = parts[-1] + 60 * parts[-2] + (3600 * parts[-3] if len(parts) > 2 else 0)
    return {
        "wall_s": secs,
        "user_s": use.ru_utime,
        "sys_s": use.ru_stime,
        "max_rss_mb": int(field("Maximum resident set size (kbytes)")) / 1024,
        "rc": p.returncode,
        "stderr": stderr[-2000:],
    }


def med(runs: list[dict[str, Any]], key: str) -> float:
    return float(statistics.median(r[key] for r in runs))


def spread(runs: list[dict[str, Any]], key: str) -> str:
    vals = [r[key] for r in runs]
    return f"{min(vals):.2f}–{max(vals):.2f}" if len(vals) > 1 else f"{vals[0]:.2f}"


def mark(ok: bool) -> str:
    return "PASS" if ok else "MISS"


def load1() -> float:
    """The 1-minute load average now."""
    return os.getloadavg()[0]


#: Every figure of the run: (figure, value, goal, ok, peer, load) — the final table.
FIGURES: list[dict[str, Any]] = []


def figure(name: str, value: str, goal: str, ok: bool, peer: str, load: float) -> bool:
    """Print one figure with its goal, PASS/MISS, the peer's figure and the load; keep it."""
    busy = load > (os.cpu_count() or 1)
    FIGURES.append({"figure": name, "value": value, "goal": goal, "ok": ok, "peer": peer,
                    "load": round(load, 2), "loaded": busy})  # fmt: skip
    print(f"  => {name}: {value}  [goal {goal}]  {mark(ok)}   peer: {peer}   "
          f"load {load:.1f}{' (loaded: re-run)' if busy else ''}")  # fmt: skip
    return ok


def table() -> str:
    """The figures as a Markdown table."""
    rows = [
        "| figure | value | goal | | peer, same run | load (1 min) |",
        "|---|---|---|---|---|---|",
    ]
    for f in FIGURES:
        load = f"{f['load']:.1f}" + (" loaded" if f["loaded"] else "")
        rows.append(f"| {f['figure']} | {f['value']} | {f['goal']} | {mark(f['ok'])} | "
                    f"{f['peer']} | {load} |")  # fmt: skip
    return "\n".join(rows)


def _cpu(t: dict[str, Any]) -> float:
    return float(t["user_s"] + t["sys_s"])
