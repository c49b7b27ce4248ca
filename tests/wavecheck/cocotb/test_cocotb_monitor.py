"""wavecheck.cocotb under a real simulator: Icarus Verilog runs ``stepgen_dut.v`` with the cocotb
tests of ``stepgen_cocotb.py`` (cocotb's Python runner, as a cocotb user runs them).

- the good configuration passes; with ``DIR_HOLD_NS`` = 400 the test fails *during* the
  simulation with the DRV8825's DIR hold margin, 400 − 650 = −250 ns;
- the monitor's report has the figures :func:`wavecheck.check` gives on the dump the simulator
  wrote of the same run (``waves=True``: Icarus's FST; and GTKWave's ``fst2vcd`` of it as VCD),
  at every batch size from one value change up, with DIR unknown (x) at the start and mid-run.

By hand: ``.venv/bin/python -m tests.wavecheck.cocotb.test_cocotb_monitor [DIR_HOLD_NS]`` runs
the example test once and leaves the dump in ``sim_build/``.
"""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
import xml.etree.ElementTree as ET
from fractions import Fraction
from pathlib import Path

import pytest

from tests.wavecheck.cocotb.stepgen_cocotb import summary as figures_of

HERE = Path(__file__).parent
DUT = HERE / "stepgen_dut.v"
MODULE = "tests.wavecheck.cocotb.stepgen_cocotb"
TOP = "stepgen_dut"
DRV8825_DIR_HOLD_NS = 650
#: The DUT's defaults (stepgen_dut.v): 40 steps of 2 us high / 2 us low from 1 us, done 4 us later.
END_NS = 1000 + 40 * 4000 + 4000

pytestmark = [
    pytest.mark.skipif(
        shutil.which("iverilog") is None or shutil.which("vvp") is None,
        reason="needs Debian's iverilog (make system-deps)",
    ),
    pytest.mark.slow,
]


def run(
    build: Path, testcase: str, params: dict[str, int], env: dict[str, str] | None = None
) -> ET.Element:
    """Build the DUT with ``params`` into ``build`` and run one cocotb test with its FST dump
    (``build/stepgen_dut.fst``); the test's element of cocotb's results file."""
    from cocotb_tools.runner import get_runner

    runner = get_runner("icarus")
    runner.build(
        sources=[DUT],
        hdl_toplevel=TOP,
        build_dir=build,
        parameters=params,
        timescale=("1ns", "1ps"),
        waves=True,
        always=True,
    )
    results = build / "results.xml"
    try:
        runner.test(
            test_module=MODULE,
            hdl_toplevel=TOP,
            testcase=testcase,
            build_dir=build,
            test_dir=build,
            results_xml=str(results),
            extra_env=env or {},
            waves=True,
        )
    except SystemExit:  # the runner's way to report a failed test under pytest
        pass
    case = ET.parse(results).getroot().find(".//testcase")
    assert case is not None, f"no test ran: {results.read_text()}"
    return case


def _sim_stop_ns(case: ET.Element) -> float:
    props = {p.get("name"): p.get("value") for p in case.iter("property")}
    assert props["sim_time_unit"] == "ns"
    return float(props["sim_time_stop"] or "nan")


def test_good_configuration_passes(tmp_path: Path) -> None:
    case = run(tmp_path, "steps_meet_the_drv8825", {})
    assert case.find("failure") is None and case.find("error") is None, ET.tostring(case)
    assert _sim_stop_ns(case) == END_NS


def test_dir_hold_knob_fails_the_test_during_the_run(tmp_path: Path) -> None:
    hold = 400
    case = run(tmp_path, "steps_meet_the_drv8825", {"DIR_HOLD_NS": hold})
    failure = case.find("failure")
    assert failure is not None, ET.tostring(case)
    assert failure.get("type") == "WavecheckViolation"
    message = failure.get("message") or ""
    # the first reversal: DIR changes 400 ns after the 10th step's rising edge (at 1 + 9 * 4 us)
    assert message.startswith("wavecheck: dir_hold failed against drv8825: 1 violation(s)")
    assert f"margin {hold - DRV8825_DIR_HOLD_NS} ns" in message  # -250 ns
    assert "worst at 37 us: measured 400 ns, limit 650 ns" in message
    # batch_time="10us": checks at the first edges 10 us apart (11, 21, 31, 41 us); the one at
    # 41 us sees the DIR change of 37.4 us and ends the test there, long before the DUT is done
    assert "(by 41 us of simulation)" in message
    assert _sim_stop_ns(case) == 41_000 < END_NS


def test_a_required_rule_not_checked_fails_the_test(tmp_path: Path) -> None:
    case = run(tmp_path, "requires_enable_setup", {})
    failure = case.find("failure")
    assert failure is not None, ET.tostring(case)
    assert failure.get("type") == "RequirementError"
    assert (failure.get("message") or "").endswith(
        "required but not decided: enable_setup not checked: no ENABLE channel"
    )
    assert _sim_stop_ns(case) == END_NS  # at finish(), after the whole run


# -- the monitor's report = wavecheck.check on the simulator's dump ---------------------------
CASES = {
    "bad-hold-x-mid-run": {"DIR_HOLD_NS": 400, "XZ_AT_NS": 63_500, "XZ_NS": 1000},
    "good": {},
    "odd-times": {"START_NS": 777, "HIGH_NS": 1901, "LOW_NS": 1899, "DIR_HOLD_NS": 649},
}


@pytest.mark.parametrize(
    ("case", "batch"),
    [("bad-hold-x-mid-run", 1), ("bad-hold-x-mid-run", 8192), ("good", 7), ("odd-times", 3)],
)
def test_report_equals_check_of_the_dump(tmp_path: Path, case: str, batch: int) -> None:
    from wavecheck.api import check

    summary = tmp_path / "summary.json"
    env = {"WAVECHECK_SUMMARY": str(summary), "WAVECHECK_BATCH": str(batch)}
    result = run(tmp_path, "report_of_the_run", CASES[case], env)
    assert result.find("failure") is None, ET.tostring(result)
    live = json.loads(summary.read_text())
    roles = {"step": f"{TOP}.step", "dir": f"{TOP}.dir"}
    fst = tmp_path / f"{TOP}.fst"
    assert live == figures_of(check(fst, "drv8825", map=roles))
    if shutil.which("fst2vcd"):  # the same run as VCD, written by GTKWave's converter
        vcd = tmp_path / f"{TOP}.vcd"
        subprocess.run(["fst2vcd", "-o", str(vcd), str(fst)], check=True, capture_output=True)
        assert live == figures_of(check(vcd, "drv8825", map=roles))
    assert live["tick_s"] == str(Fraction(1, 10**12))  # the simulator's precision, 1 ps
    rules = live["rules"]
    hold = CASES[case].get("DIR_HOLD_NS", 1000)
    assert Fraction(rules["dir_hold"]["min_margin_ns"]) == hold - DRV8825_DIR_HOLD_NS
    assert (rules["dir_hold"]["verdict"] == "fail") == (hold < DRV8825_DIR_HOLD_NS)
    if "XZ_AT_NS" in CASES[case]:  # DIR unknown before 500 ns and for 1 us from 63.5 us
        assert rules["dir_setup"]["unknown_at"] == [0, 63_500_000]


if __name__ == "__main__":  # pragma: no cover - by hand
    hold = int(sys.argv[1]) if len(sys.argv) > 1 else 1000
    out = run(Path("sim_build").resolve(), "steps_meet_the_drv8825", {"DIR_HOLD_NS": hold})
    print(ET.tostring(out, encoding="unicode"))


def test_several_axes(tmp_path: Path) -> None:
    from wavecheck.api import Axis, check_axes

    summary = tmp_path / "summary.json"
    result = run(tmp_path, "two_axes", {"DIR_HOLD_NS": 500}, {"WAVECHECK_SUMMARY": str(summary)})
    assert result.find("failure") is None, ET.tostring(result)
    live = json.loads(summary.read_text())
    machine = check_axes(
        tmp_path / f"{TOP}.fst",
        {"x": {"step": f"{TOP}.step", "dir": f"{TOP}.dir"},
         "y": Axis({"step": f"{TOP}.done"}, drive="leadshine-dm542")},
        drive="drv8825",
    )  # fmt: skip
    dump = {
        a.axis: [
            a.drive.id,
            a.steps.count,
            [[r.rule, r.verdict, str(r.min_margin_ns)] for r in a.rules],
        ]
        for a in machine.axes
    }
    assert live == dump
    assert live["x"][1] == 40 and live["y"][1] == 1
    assert ["dir_hold", "fail", "-150"] in live["x"][2]


def test_readme_example_is_the_shipped_test() -> None:
    from tests.doc_pages import marked

    example = marked("tests/wavecheck/cocotb/stepgen_cocotb.py", kind="cocotb-example")
    assert example in (HERE / "stepgen_cocotb.py").read_text(encoding="utf-8")
