"""The simulation slow-down the live monitor adds: one long run of ``stepgen_dut.v`` (STEPS
steps, a reversal every 10) under Icarus, with and without the monitor (cocotb's own real time
of each test, from its results file, and the wall time of the simulator process).

    .venv/bin/python -m tests.wavecheck.cocotb.measure [STEPS]     # default 100000
"""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

from tests.wavecheck.cocotb.test_cocotb_monitor import DUT, MODULE, TOP


def main() -> None:
    from cocotb_tools.runner import get_runner

    steps = int(sys.argv[1]) if len(sys.argv) > 1 else 100_000
    with tempfile.TemporaryDirectory() as tmp:
        build = Path(tmp)
        runner = get_runner("icarus")
        runner.build(sources=[DUT], hdl_toplevel=TOP, build_dir=build,
                     parameters={"STEPS": steps}, timescale=("1ns", "1ps"))  # fmt: skip
        for case in (
            "without_monitor",
            "report_of_the_run",
            "without_monitor",
            "report_of_the_run",
        ):
            t = time.perf_counter()
            xml = runner.test(test_module=MODULE, hdl_toplevel=TOP, testcase=case, build_dir=build,
                              test_dir=build, results_xml=str(build / "r.xml"),
                              extra_env={"WAVECHECK_SUMMARY": str(build / "s.json")})  # fmt: skip
            wall = time.perf_counter() - t
            real = xml.read_text().split('time="', 2)[2].split('"')[0]
            print(f"{case:20s} {steps} steps: cocotb real time {float(real):.3f} s, "
                  f"simulator process {wall:.3f} s", file=sys.stderr)  # fmt: skip


if __name__ == "__main__":
    main()
