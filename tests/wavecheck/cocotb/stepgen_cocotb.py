"""cocotb tests of ``stepgen_dut.v`` with wavecheck's live monitor: the example of README's
"Inside cocotb tests", run under Icarus Verilog by ``test_cocotb_monitor.py`` (which sets the
DUT's parameters, e.g. ``DIR_HOLD_NS`` below the DRV8825's 650 ns).

Run by hand: ``python tests/wavecheck/cocotb/test_cocotb_monitor.py`` (see there).
"""

from __future__ import annotations

import json
import os

import cocotb

from wavecheck.cocotb import StepMonitor


@cocotb.test()
async def steps_meet_the_drv8825(dut: object) -> None:
    """The DUT's STEP/DIR against a DRV8825: the test fails at the first violation."""
    mon = StepMonitor("drv8825", step=dut.step, dir=dut.dir, batch_time="10us").start()  # type: ignore[attr-defined]
    await dut.done.rising_edge  # type: ignore[attr-defined]
    report = await mon.finish()
    dut._log.info("wavecheck: %s, %d steps", report.verdict, report.steps.count)  # type: ignore[attr-defined]


@cocotb.test()
async def report_of_the_run(dut: object) -> None:
    """The monitor's report without failing (for the comparison with the simulator's dump):
    each rule's figures written as JSON to $WAVECHECK_SUMMARY."""
    batch = int(os.environ.get("WAVECHECK_BATCH", "8192"))
    mon = StepMonitor(
        "drv8825",
        step=dut.step,  # type: ignore[attr-defined]
        dir=dut.dir,  # type: ignore[attr-defined]
        fail_on_violation=False,
        batch=batch,
    ).start()
    await dut.done.rising_edge  # type: ignore[attr-defined]
    report = await mon.finish()
    rows = {
        r.rule: {
            "verdict": r.verdict,
            "checked": r.checked,
            "violations": r.violations,
            "unknown": r.unknown,
            "min_margin_ns": None if r.min_margin_ns is None else str(r.min_margin_ns),
            "at_s": None if r.min_margin_at_s is None else str(r.min_margin_at_s),
            "unknown_at": [int(t) for t in r.unknown_ticks],
            "worst": [str(v.time_s) for v in r.worst_violations(5)],
        }
        for r in report.rules
    }
    out = {
        "tick_s": str(report.capture.timebase.tick_s),
        "steps": [report.steps.count, report.steps.forward, report.steps.reverse],
        "rules": rows,
    }
    with open(os.environ["WAVECHECK_SUMMARY"], "w", encoding="utf-8") as f:
        json.dump(out, f)
