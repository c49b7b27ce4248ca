"""The pytest plugin on the dump a cocotb test wrote in the same test run: the
``wavecheck_dump`` fixture and a ``wavecheck.toml`` whose ``path`` is a glob
(``sim_build/*.fst``), in a pytest project whose first test runs the simulation."""

from __future__ import annotations

import shutil

import pytest

pytest_plugins = ["pytester"]

pytestmark = [
    pytest.mark.skipif(
        shutil.which("iverilog") is None or shutil.which("vvp") is None,
        reason="needs Debian's iverilog (make system-deps)",
    ),
    pytest.mark.slow,
]

SIMULATE = """
from pathlib import Path
from tests.wavecheck.cocotb.test_cocotb_monitor import run

def test_simulate(wavecheck_dump, wavecheck_check, tmp_path):
    build = Path("sim_build").resolve()
    case = run(build, "report_of_the_run", {"DIR_HOLD_NS": 400},
               {"WAVECHECK_SUMMARY": str(tmp_path / "s.json")})
    assert case.find("failure") is None
    dump = wavecheck_dump("sim_build")
    assert dump == build / "stepgen_dut.fst"
    report = wavecheck_check(dump, "drv8825", map={"step": "step", "dir": "dir"})
    assert report.rule("dir_hold").min_margin_ns == -250
    wavecheck_check.expect(report, "fail")

def test_no_dump_fails_readably(wavecheck_dump):
    wavecheck_dump("elsewhere/*.vcd")
"""

TOML = """
[[capture]]
name = "sim"
path = "sim_build/*.fst"
drive = "drv8825"
map = { step = "stepgen_dut.step", dir = "stepgen_dut.dir" }
expect = "fail"
expect_rules = { dir_hold = "fail" }
"""


def test_fixture_and_glob_path_check_the_dump_of_this_run(pytester: pytest.Pytester) -> None:
    pytester.makepyfile(test_a_simulate=SIMULATE)
    pytester.makefile(".toml", wavecheck=TOML)
    result = pytester.runpytest("-p", "no:xdist", "-v")
    result.assert_outcomes(passed=1 + 6, failed=1)
    result.stdout.fnmatch_lines(
        [
            "*test_a_simulate.py::test_simulate PASSED*",
            "*wavecheck.toml::sim::verdict PASSED*",
            "*wavecheck.toml::sim::dir_hold PASSED*",
            "*no file matches */elsewhere/[*].vcd (has the simulation that writes it run?)*",
        ]
    )


def test_glob_path_with_no_dump_yet_fails_the_item(pytester: pytest.Pytester) -> None:
    pytester.makefile(".toml", wavecheck=TOML)
    result = pytester.runpytest("-p", "no:xdist", "-k", "verdict")
    result.assert_outcomes(failed=1)
    result.stdout.fnmatch_lines(["*no file matches */sim_build/[*].fst*"])
