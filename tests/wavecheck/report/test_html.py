"""The HTML page: self-contained, with the verdict and rule table; rendered in headless chromium."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
from pathlib import Path

import pytest

from wavecheck.engine.outcome import Report
from wavecheck.report.html import render_html, write_html


def test_self_contained(failing_report: Report) -> None:
    page = render_html([failing_report], plots=True)
    assert "<script" not in page and "<link" not in page
    # nothing is fetched: every src/href is a data: URL or a fragment in the page
    for url in re.findall(r'(?:src|href)="([^"]*)"', page):
        assert url.startswith(("data:image/png;base64,", "#")), url
    assert page.count("data:image/png;base64,") == 1
    assert 'id="verdict" class="verdict v-fail">FAIL<' in page


def test_rule_table_and_violations(failing_report: Report) -> None:
    page = render_html([failing_report], plots=False)
    for rule in ("step_high", "step_low", "step_period", "dir_setup", "dir_hold"):
        assert f"<td>{rule}</td>" in page
    assert '<tr class="r-fail"><td>dir_hold</td>' in page
    assert "3 violation(s), worst first." in page
    # the rule row and the three violations, identical (9 us each): one row that counts them
    assert page.count("<td>dir_hold</td>") == 2
    assert '<td>dir_hold</td><td class="num">3</td>' in page
    assert "48.7805 kHz" in page  # headroom


def test_several_captures_and_errors(failing_report: Report, passing_report: Report) -> None:
    page = render_html([passing_report, failing_report], plots=False, errors=["x.sr: no such file"])
    assert page.count('<section class="capture"') == 2
    assert 'data-verdict="pass"' in page and 'data-verdict="fail"' in page
    assert "x.sr: no such file" in page
    assert 'id="verdict" class="verdict v-error">ERROR<' in page


def _chromium() -> str:
    exe = shutil.which("chromium") or (
        "/usr/bin/chromium" if Path("/usr/bin/chromium").exists() else None
    )
    if exe is None:
        if os.environ.get("CI") == "true":
            pytest.fail("chromium is missing in CI (make test installs Debian's chromium)")
        pytest.skip("chromium not installed (apt-get install chromium)")
    return exe


def _dump_dom(page: Path, profile: Path) -> str:
    """The DOM headless chromium builds of ``page`` (after parsing and layout)."""
    cmd = [
        _chromium(),
        "--headless",
        "--no-sandbox",
        "--disable-gpu",
        "--disable-quic",
        "--no-first-run",
        "--disable-background-networking",
        "--disable-component-update",
        "--disable-sync",
        f"--user-data-dir={profile}",
        "--dump-dom",
        page.as_uri(),
    ]
    out = subprocess.run(cmd, capture_output=True, text=True, timeout=120, check=False)
    assert out.returncode == 0, out.stderr[-2000:]
    return out.stdout


@pytest.mark.browser
def test_several_axes_summary_has_an_axis_column(tmp_path: Path) -> None:
    """Issue 26: two axes of one capture were two identical summary rows. Each row names its
    axis, and each section's verdict line says what was not checked."""
    from wavecheck.cli import main

    capture = Path(__file__).resolve().parents[3] / "captures" / "examples" / "two-axis.vcd"
    page = tmp_path / "axes.html"
    main(["check", str(capture), "--drive", "gecko-g202", "--map", "x.step=x_step,x.dir=x_dir",
          "--map", "y.step=y_step", "--html", str(page)])  # fmt: skip
    dom = _dump_dom(page, tmp_path / "profile")
    table = re.search(r'<table class="summary">(.*?)</table>', dom, re.S)
    assert table is not None
    head = re.findall(r"<th>(\w+)</th>", table.group(1))
    assert head == ["capture", "axis", "drive", "verdict", "violations", "steps"]
    rows = re.findall(r"</a></td><td>(\w+)</td><td>gecko-g202</td>", table.group(1))
    assert rows == ["x", "y"]
    assert "dir_setup, dir_hold not checked: no DIR channel" in table.group(1)  # y's row only
    lines = re.findall(r'<p class="verdict-line">Verdict: ([^<]*)</p>', dom)
    assert lines == [
        "FAIL (enable_setup not checked: drive gecko-g202 states no figure)",
        "PASS (dir_setup, dir_hold not checked: no DIR channel; "
        "enable_setup not checked: drive gecko-g202 states no figure)",
    ]


@pytest.mark.browser
def test_chromium_renders_verdict_and_rule_table(failing_report: Report, tmp_path: Path) -> None:
    page = tmp_path / "report.html"
    write_html([failing_report], page)
    dom = _dump_dom(page, tmp_path / "profile")
    # the DOM after parsing and layout: the verdict element, the rule table, the image
    assert re.search(r'<span id="verdict" class="verdict v-fail">FAIL</span>', dom), dom[:2000]
    table = re.search(r'<table class="rules">(.*?)</table>', dom, re.S)
    assert table is not None
    rows = re.findall(r"<tr class=\"r-(\w+)\"><td>(\w+)</td>", table.group(1))
    assert rows == [
        ("pass", "step_high"),
        ("pass", "step_low"),
        ("pass", "step_period"),
        ("pass", "dir_setup"),
        ("fail", "dir_hold"),
    ]
    assert '<img alt="timing diagrams' in dom and "data:image/png;base64," in dom
