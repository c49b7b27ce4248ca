"""cocotb tests of ``stepgen_dut.v`` with wavecheck's live monitor: the example of README's
"Inside cocotb tests", run under Icarus Verilog by ``test_cocotb_monitor.py`` (which sets the
DUT's parameters, e.g. ``DIR_HOLD_NS`` below the DRV8825's 650 ns).

Run by hand: ``.venv/bin/python -m tests.wavecheck.cocotb.test_cocotb_monitor [DIR_HOLD_NS]``.
"""

from __future__ import annotations

import json
import os
from typing import Any

import cocotb

from wavecheck.cocotb import StepMonitor


@cocotb.test()
async def steps_meet_the_drv8825(dut: Any) -> None:
    """The DUT's STEP/DIR against a DRV8825: the test fails at the first violation."""
    mon = StepMonitor("drv8825", step=dut.step, dir=dut.dir, batch_time="10us").start()
    await dut.done.rising_edge
    report = await mon.finish()
    dut._log.info("wavecheck: %s, %d steps", report.verdict, report.steps.count)


@cocotb.test()
async def report_of_the_run(dut: Any) -> None:
    """The monitor's report without failing (for the comparison with the simulator's dump):
    each rule's figures written as JSON to $WAVECHECK_SUMMARY."""
    batch = int(os.environ.get("WAVECHECK_BATCH", "8192"))
    mon = StepMonitor(
        "drv8825",
        step=dut.step,
        dir=dut.dir,
        fail_on_violation=False,
        batch=batch,
    ).start()
    await dut.done.rising_edge
    report = await mon.finish()
    out = summary(report)
    with open(os.environ["WAVECHECK_SUMMARY"], "w", encoding="utf-8") as f:
        json.dump(out, f)


@cocotb.test()
async def requires_enable_setup(dut: Any) -> None:
    """``require=`` as ``--require``: the DUT has no ENABLE line, so a required enable_setup is
    not checked and :meth:`StepMonitor.finish` raises (issue 26)."""
    mon = StepMonitor(
        "leadshine-dm542", step=dut.step, dir=dut.dir, fail_on_violation=False,
        require="enable_setup",
    ).start()  # fmt: skip
    await dut.done.rising_edge
    await mon.finish()


@cocotb.test()
async def without_monitor(dut: Any) -> None:
    """The same run without the monitor (the baseline of ``measure.py``)."""
    await dut.done.rising_edge


@cocotb.test()
async def two_axes(dut: Any) -> None:
    """Several axes (``axes=``): x is the DUT's STEP/DIR against a DRV8825, y takes DONE as its
    STEP against a Leadshine DM542; each axis's dir_hold margin and step count as JSON."""
    mon = StepMonitor(
        "drv8825",
        axes={
            "x": {"step": dut.step, "dir": dut.dir},
            "y": {"step": dut.done, "drive": "leadshine-dm542"},
        },
        fail_on_violation=False,
        batch=5,
    ).start()
    await dut.done.rising_edge
    machine = await mon.finish()
    out = {
        a.axis: [
            a.drive.id,
            a.steps.count,
            [(r.rule, r.verdict, str(r.min_margin_ns)) for r in a.rules],
        ]
        for a in machine.axes
    }
    with open(os.environ["WAVECHECK_SUMMARY"], "w", encoding="utf-8") as f:
        json.dump(out, f)


def summary(report: Any) -> dict[str, Any]:
    """What the comparison with the dump looks at: time base, step counts and each rule's figures
    (exact values as text, so they survive JSON)."""
    return {
        "tick_s": str(report.capture.timebase.tick_s),
        "steps": [report.steps.count, report.steps.forward, report.steps.reverse],
        "rules": {
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
        },
    }
