"""``wavecheck config``'s verdict line names the rules it did not check and why (issue 26: a
grbl configuration against a TB6600 was a plain PASS with DIR setup unchecked), the result
keeps them as data, and ``--format junit`` gives CI one test case per axis and rule."""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from tests.conftest import SHARED
from wavecheck.cli import main
from wavecheck.drives.library import load_drive
from wavecheck.firmware import read_firmware
from wavecheck.firmware.evaluate import evaluate_config

GRBL = SHARED / "firmware/grbl/settings.md"
pytestmark = pytest.mark.skipif(not GRBL.is_file(), reason="shared firmware files not present")


HM2 = SHARED / "firmware/linuxcnc/hm2-stepper/5i20.ini"


def test_a_pass_names_what_was_not_checked(capsys: pytest.CaptureFixture[str]) -> None:
    """TB6600 states no DIR setup/hold and no max rate (rules/tb6600.toml): those are not
    checked, and the verdict line says so instead of a plain PASS (hm2 with its clock: every
    figure in whole clocks, no band; grbl's low time now has one, see test_bands.py)."""
    assert main(["config", str(HM2), "--hm2-clock", "33MHz", "--drive", "tb6600"]) == 0
    last = capsys.readouterr().out.strip().splitlines()[-1]
    assert last.startswith("verdict: PASS (")
    assert "step_period, dir_setup, dir_hold not checked: drive tb6600 states no figure" in last


def test_unchecked_rules_are_data_on_the_result() -> None:
    cfg = read_firmware(GRBL)
    result = evaluate_config(cfg, [(a, load_drive("tb6600")) for a in cfg.axes])
    # grbl's low time is a time between interrupts, which no source bounds: indeterminate
    assert result.verdict == "indeterminate" and result.exit_code == 3
    assert result.unchecked["drive tb6600 states no figure"] == (
        "step_period", "dir_setup", "dir_hold")  # fmt: skip
    assert result.verdict_line.startswith(
        "INDETERMINATE (step_period, dir_setup, dir_hold not checked"
    )


def test_json_carries_the_verdict_line(capsys: pytest.CaptureFixture[str]) -> None:
    main(["config", str(GRBL), "--drive", "tb6600", "--format", "json"])
    doc = json.loads(capsys.readouterr().out)
    assert doc["verdict"] == "indeterminate"
    assert doc["verdict_line"].startswith("INDETERMINATE (")
    assert {"why": "drive tb6600 states no figure",
            "rules": ["step_period", "dir_setup", "dir_hold"]} in doc["unchecked"]  # fmt: skip


def test_junit(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "config.xml"
    code = main(["config", str(GRBL), "--drive", "leadshine-dm542", "--limit", "step_high=10us",
                 "--format", "junit", "-o", str(out)])  # fmt: skip
    assert code == 1  # grbl's $0=10 is 9.4375 us at the pin, under the 10 us limit given
    assert capsys.readouterr().out.startswith("FAIL (")
    root = ET.parse(out).getroot()
    suites = root.findall("testsuite")
    assert [s.get("name", "").split("[")[1] for s in suites] == [
        f"axis {a}, drive leadshine-dm542]" for a in "XYZ"]  # fmt: skip
    x = {c.get("name"): c for c in suites[0].findall("testcase")}
    failure = x["step_high"].find("failure")
    assert failure is not None and failure.get("type") == "fail"
    # grbl keeps no DIR setup (stepper.c:323-333): not enforced, so not proven, never a pass
    undecided = x["dir_setup"].find("failure")
    assert undecided is not None and undecided.get("type") == "indeterminate"
    # the low time is between stepper interrupts, which others may delay (stepper.c:319-336)
    low = x["step_low"].find("failure")
    assert low is not None and low.get("type") == "indeterminate"
    assert "no source bounds" in (low.text or "")
    assert x["step_high"].find("skipped") is None
    skipped = x["enable_setup"].find("skipped")
    assert skipped is not None and "says nothing" in skipped.get("message", "")
    assert root.get("failures") == str(sum(int(s.get("failures", "0")) for s in suites))
    assert x["dir_setup"].get("classname", "").endswith("grbl/settings.X")
