"""What a verdict claims, on the command line (issue 26).

Every grbl capture of sigrok-dumps has no DIR channel: ``check`` used to print a plain
``verdict: PASS`` with the DIR rules unchecked further down. The verdict line now says what was
not checked and why, in text, JSON, JUnit and HTML; ``--require RULES|all`` makes a rule that is
unchecked or indeterminate fail the run with exit 4 and a line saying why (check, watch, config).
"""

from __future__ import annotations

import json
import re
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from wavecheck.cli import main

REPO = Path(__file__).resolve().parents[3]
GOLDEN = REPO / "captures" / "golden" / "g202-p20-worst-dirhold.vcd"
GRBL_SETTINGS = REPO / "captures" / "firmware" / "grbl" / "settings.md"
NO_DIR = "dir_setup, dir_hold not checked: no DIR channel"


def _run(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def test_a_pass_without_dir_says_so_on_the_verdict_line(grbl_sr: Path, capsys) -> None:
    code, out, _ = _run(capsys, "check", grbl_sr, "--map", "step=1", "--drive", "drv8825")
    first = out.splitlines()[0]
    assert code == 0
    assert first == (
        f"verdict: PASS ({NO_DIR}; enable_setup not checked: drive drv8825 states no figure)"
    )


def test_require_all_fails_the_run_with_exit_4_and_says_why(grbl_sr: Path, capsys) -> None:
    code, out, _ = _run(
        capsys, "check", grbl_sr, "--map", "step=1", "--drive", "drv8825", "--require", "all"
    )
    assert code == 4
    # issue 34: the first line says what the exit code says, not "verdict: PASS"
    assert out.splitlines()[0] == (
        f"verdict: NOT DECIDED (exit 4: required {NO_DIR}); the rules checked: "
        f"PASS ({NO_DIR}; enable_setup not checked: drive drv8825 states no figure)"
    )
    assert out.splitlines()[1] == f"required but not decided: {NO_DIR}"
    # all = every rule the drive gives a figure for: the DRV8825 states no enable_setup
    code, out, _ = _run(
        capsys, "check", grbl_sr, "--map", "step=1", "--drive", "drv8825",
        "--require", "step_high,step_period",
    )  # fmt: skip
    assert code == 0 and "required" not in out


def test_json_and_junit_carry_the_same_claims(grbl_sr: Path, tmp_path: Path, capsys) -> None:
    args = ["check", grbl_sr, "--map", "step=1", "--drive", "drv8825", "--require", "dir_hold"]
    code, out, _ = _run(capsys, *args, "--format", "json")
    doc = json.loads(out)
    assert code == 4 and doc["exit_code"] == 4 and doc["verdict"] == "pass"  # keys kept
    assert doc["verdict_line"].startswith(f"PASS ({NO_DIR}")
    assert {"why": "no DIR channel", "rules": ["dir_setup", "dir_hold"]} in doc["unchecked"]
    assert doc["required"] == {
        "rules": ["dir_hold"],
        "unmet": [
            {"rule": "dir_hold", "axis": None, "verdict": "unchecked", "why": "no DIR channel"}
        ],
    }
    xml = tmp_path / "out.xml"
    code, out, _ = _run(capsys, *args, "--format", "junit", "-o", xml)
    assert code == 4 and out.splitlines()[0].startswith(
        "NOT DECIDED (exit 4: required dir_hold not checked: no DIR channel); "
        f"the rules checked: PASS ({NO_DIR}"
    )
    assert out.splitlines()[1] == "required but not decided: dir_hold not checked: no DIR channel"
    suite = ET.parse(xml).getroot().find("testsuite")
    assert suite is not None
    props = {p.get("name"): p.get("value") for p in suite.iter("property")}
    assert props["verdict"] == "pass" and props["verdict_line"].startswith(f"PASS ({NO_DIR}")
    cases = {c.get("name"): c for c in suite.findall("testcase")}
    failure = cases["dir_hold"].find("failure")
    assert failure is not None and failure.get("type") == "required"
    assert failure.get("message") == "required but not checked: no DIR channel"
    skipped = cases["dir_setup"].find("skipped")  # not required: skipped, with why
    assert skipped is not None and skipped.get("message") == "dir_setup not checked: no DIR channel"


def test_indeterminate_required_rule_exits_4_a_failed_one_1(capsys) -> None:
    # at T = 16 us every interval of the golden trace is within one sample of its limit
    base = ["check", GOLDEN, "--drive", "gecko-g202", "--resolution", "16us"]
    code, out, _ = _run(capsys, *base)
    assert code == 3 and out.startswith("verdict: INDETERMINATE")
    code, out, _ = _run(capsys, *base, "--require", "step_high")
    assert code == 4
    line = out.splitlines()[1]
    assert line.startswith("required but not decided: step_high indeterminate: ")
    assert "within one sample of the limit at T = 16 us" in line
    code, _, _ = _run(capsys, "check", GOLDEN, "--drive", "gecko-g202", "--require", "all")
    assert code == 1  # dir_hold fails: a failed rule says more than a requirement


def test_several_captures_worst_exit_and_summary(grbl_sr: Path, tmp_path: Path, capsys) -> None:
    code, out, _ = _run(
        capsys, "check", grbl_sr, grbl_sr, "--map", "step=1", "--drive", "drv8825",
        "--require", "dir_setup", "-j", "1",
    )  # fmt: skip
    assert code == 4
    summary = out.split("== summary ==\n", 1)[1].splitlines()
    assert len(summary) == 2 and all(NO_DIR in s for s in summary)
    assert all(s.endswith("required but not decided: dir_setup not checked: "
                          "no DIR channel") for s in summary)  # fmt: skip


def test_unknown_rule_is_one_line_exit_2(capsys) -> None:
    code, out, err = _run(capsys, "check", GOLDEN, "--drive", "gecko-g202", "--require", "dirhold")
    assert code == 2 and out == ""
    assert err.count("\n") == 1 and "--require 'dirhold' is not a rule" in err


def test_config_require(capsys) -> None:
    """grbl's $$ dump against a TB6600, which states no DIR figures: INDETERMINATE (exit 3: its
    low time is a time between stepper interrupts, which no source bounds) unless the DIR rules
    are required (exit 4; config's verdict line and ``--require`` are check's mechanism)."""
    base = ["config", GRBL_SETTINGS, "--drive", "tb6600"]
    code, out, _ = _run(capsys, *base)
    assert code == 3
    code, out, _ = _run(capsys, *base, "--require", "dir_setup,dir_hold")
    assert code == 4
    assert out.splitlines()[-1] == (
        "required but not decided: dir_setup, dir_hold not checked: drive tb6600 states no figure"
    )
    code, out, _ = _run(capsys, *base, "--require", "dir_setup", "--format", "json")
    doc = json.loads(out)
    assert code == 4 and doc["exit_code"] == 4
    assert [u["axis"] for u in doc["required"]["unmet"]] == ["X", "Y", "Z"]
    code, out, _ = _run(capsys, *base, "--require", "dir_setup", "--format", "junit")
    failures = re.findall(r'<failure message="([^"]*)" type="required"', out)
    assert code == 4 and len(failures) == 3


def test_html_says_what_was_not_checked(grbl_sr: Path, tmp_path: Path, capsys) -> None:
    page = tmp_path / "r.html"
    code, _, _ = _run(
        capsys, "check", grbl_sr, "--map", "step=1", "--drive", "drv8825", "--html", page,
        "--require", "all",
    )  # fmt: skip
    html = page.read_text()
    assert code == 4
    assert (
        f'<p class="verdict-line">Verdict: NOT DECIDED (exit 4: required {NO_DIR}); '
        f"the rules checked: PASS ({NO_DIR};" in html
    )
    assert f'<p class="required">required but not decided: {NO_DIR}</p>' in html
