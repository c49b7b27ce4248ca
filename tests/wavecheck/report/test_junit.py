"""JUnit XML: valid against the Jenkins-style schema, counts consistent, messages useful."""

from __future__ import annotations

import os
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from tests.engine_probe import run_check
from tests.wavecheck.waves import capture, drive, pulses
from wavecheck.engine.outcome import Report
from wavecheck.report.junit import Unreadable, classname, render_junit

XSD = Path(__file__).resolve().parents[2] / "data" / "junit-10.xsd"


def _validate(xml: str) -> None:
    try:
        from lxml import etree
    except ImportError:  # pragma: no cover - lxml is in the test extra
        if os.environ.get("CI") == "true":
            pytest.fail("lxml missing in CI (it is in pyproject's test extra)")
        pytest.skip("lxml not installed")
    schema = etree.XMLSchema(etree.parse(str(XSD)))
    doc = etree.fromstring(xml.encode("utf-8"))
    assert schema.validate(doc), schema.error_log


def _check_counts(root: ET.Element) -> None:
    for suite in root.iter("testsuite"):
        cases = suite.findall("testcase")
        assert int(suite.get("tests", "-1")) == len(cases)
        for kind, attr in (("failure", "failures"), ("error", "errors"), ("skipped", "skipped")):
            assert int(suite.get(attr, "-1")) == sum(1 for c in cases if c.find(kind) is not None)
        for c in cases:
            assert len(list(c)) <= 1  # one outcome element at most
    for attr in ("tests", "failures", "errors", "skipped"):
        assert int(root.get(attr, "-1")) == sum(int(s.get(attr, "0")) for s in root)


def test_failing_report_is_valid_and_names_the_worst(failing_report: Report) -> None:
    xml = render_junit([failing_report])
    _validate(xml)
    root = ET.fromstring(xml)
    _check_counts(root)
    (suite,) = root.findall("testsuite")
    names = [c.get("name") for c in suite.findall("testcase")]
    assert names == [
        "step_high",
        "step_low",
        "step_period",
        "dir_setup",
        "dir_hold",
        "enable_setup",
    ]
    assert {c.get("classname") for c in suite.findall("testcase")} == {"test"}
    failure = suite.find("testcase[@name='dir_hold']/failure")
    assert failure is not None
    assert failure.get("message") == (
        "3 violation(s); worst: dir_hold at 0.001231000 s: measured 9 us, limit 20 us "
        "(margin -11 us)"
    )
    assert suite.find("testcase[@name='enable_setup']/skipped") is not None
    assert suite.get("failures") == "1" and suite.get("skipped") == "1"


def test_several_captures_one_suite_each_and_an_unreadable_one(
    failing_report: Report, passing_report: Report
) -> None:
    xml = render_junit(
        [failing_report, passing_report], [Unreadable("runs/x.sr", "runs/x.sr: no such file")]
    )
    _validate(xml)
    root = ET.fromstring(xml)
    _check_counts(root)
    suites = root.findall("testsuite")
    assert len(suites) == 3
    err = suites[2].find("testcase/error")
    assert err is not None and err.get("message") == "runs/x.sr: no such file"
    assert suites[2].find("testcase").get("classname") == "runs/x"  # type: ignore[union-attr]
    assert root.get("failures") == "1" and root.get("errors") == "1"


def test_indeterminate_is_a_failure_and_unchecked_is_skipped() -> None:
    # 1 µs sampling: 4.5 µs pulses against a 4.5 µs limit cannot be decided; no DIR change
    cap = capture({"S": (0, pulses([0, 20, 40], 5))}, tick_ns=1000, resolution_ticks=1)
    d = drive("rising", step_high=4500, dir_hold=1000)
    report = run_check(cap, d, {"step": "S"})
    xml = render_junit([report])
    _validate(xml)
    root = ET.fromstring(xml)
    _check_counts(root)
    fail = root.find(".//testcase[@name='step_high']/failure")
    assert fail is not None and fail.get("type") == "indeterminate"
    assert "cannot be decided" in (fail.get("message") or "")
    assert root.find(".//testcase[@name='dir_hold']/skipped") is not None  # no DIR mapped


def test_classname_drops_the_extension() -> None:
    assert classname("captures/golden/g202-j11.vcd") == "captures/golden/g202-j11"
    assert classname("run") == "run"


@pytest.mark.parametrize("steps", [[], [0, 20]])
def test_all_unchecked_is_a_failure_as_the_exit_code_says(steps: list[int]) -> None:
    """Issue 12: a capture where every rule is unchecked exits 3, but its JUnit said
    failures="0" (a green dashboard for a red job)."""
    cap = capture({"S": (0, steps), "D": (0, [])}, end=100)
    d = drive("rising", dir_hold=1000, dir_setup=1000)
    report = run_check(cap, d, {"step": "S", "dir": "D"})
    assert report.verdict == "unchecked" and report.exit_code == 3
    xml = render_junit([report])
    _validate(xml)
    root = ET.fromstring(xml)
    _check_counts(root)
    assert int(root.get("failures", "0")) == 1
    fail = root.find(".//testcase[@name='verdict']/failure")
    assert fail is not None and fail.get("type") == "unchecked"


def test_junit_failures_match_the_exit_code(failing_report: Report, passing_report: Report) -> None:
    for report in (failing_report, passing_report):
        root = ET.fromstring(render_junit([report]))
        assert (int(root.get("failures", "0")) > 0) == (report.exit_code != 0)
