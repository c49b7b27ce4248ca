"""Where ``stepgen simulate --command FILE --latency uniform:10us -o OUT.vcd`` spends its CPU
(issue 29), in one process: each stage of the run on its own, CPU best of ``--repeat``; and the
part no change to the numpy stages can remove, pass 1 of the fast engine (one update-freq and
the closed form of its servo period, in Python, each depending on the accumulator the one before
left). ``bench/run.py`` times the whole command as a process against ``import numpy``.

    .venv/bin/python bench/stepgen_cli.py FILE.csv [--seconds 20] [--repeat 5]
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path
from unittest import mock

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from stepgen import fast  # noqa: E402
from stepgen.lateness import parse_latency  # noqa: E402
from stepgen.motion import Motion, parse_command_csv  # noqa: E402
from stepgen.reference import StepgenConfig, update_schedule  # noqa: E402
from stepgen.simulate import trace_from_run  # noqa: E402
from stepgen.vcdout import write_vcd  # noqa: E402

#: The options that go with the CSV (bench/run.py's command line; the configuration below)
OPTIONS = ["--position-scale", "1000", "--maxvel", "15", "--maxaccel", "100",
           "--latency", "uniform:10us", "--seed", "1"]  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("csv")
    ap.add_argument("--seconds", type=float, default=20.0)
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    cfg = StepgenConfig(base_period_ns=25_000, servo_period_ns=1_000_000, position_scale=1000,
                        maxvel=15, maxaccel=100, thread_order="pulses-first")  # fmt: skip
    n = round(args.seconds * 40_000)
    cpu: dict[str, list[float]] = {}

    def timed(stage: str, f, *a, **kw):  # type: ignore[no-untyped-def]
        c0 = time.process_time()
        out = f(*a, **kw)
        cpu.setdefault(stage, []).append(time.process_time() - c0)
        return out

    stub = ({}, fast.np.zeros(0, fast.np.int64), fast.np.zeros(0, fast.np.int64))
    with tempfile.TemporaryDirectory() as d:
        for _ in range(args.repeat):
            t, v = timed("read the CSV", parse_command_csv, args.csv)
            motion = Motion("csv", csv_times=t, csv_values=v)
            cmds = timed("commands", motion.commands, len(update_schedule(cfg, n)),
                         cfg.servo_ns, cfg.mode)  # fmt: skip
            with mock.patch.object(fast, "_pass2", lambda *a: stub):
                timed("pass 1 (floor)", fast.run_fast, cfg, cmds, n)
            run = timed("pass 1 + pass 2", fast.run_fast, cfg, cmds, n)
            trace = timed("latency, edge times", trace_from_run, run, parse_latency("uniform:10us"),
                          seed=1, active_edge="rising", catchup_ns=1000)  # fmt: skip
            changes = timed("write the VCD", write_vcd, trace, Path(d) / "o.vcd")
    best = {k: min(v) for k, v in cpu.items()}
    print(json.dumps({"seconds": args.seconds, "periods": n, "steps": trace.steps,
                      "changes": changes, "cpu_s": best}))  # fmt: skip


if __name__ == "__main__":
    main()
