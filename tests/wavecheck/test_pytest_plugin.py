"""The pytest plugin: a temporary project with a wavecheck.toml, run by pytest itself."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.wavecheck.report.traces import write_stepgen_vcd
from wavecheck.pytest_plugin import WavecheckConfigError, load_specs

pytest_plugins = ["pytester"]

CONFIG = """\
[[capture]]
name = "g202-p20-j11"
path = "runs/fail.vcd"
drive = "gecko-g202"
map = { step = "STEP", dir = "DIR" }
expect = "pass"

[[capture]]
name = "g202-p25"
path = "runs/pass.vcd"
drive = "gecko-g202"
map = "step=STEP,dir=DIR"

[[capture]]
name = "known-bad"
path = "runs/fail.vcd"
drive = "gecko-g202"
expect = "fail"
expect_rules = { dir_hold = "fail" }
"""

RULES = ["step_high", "step_low", "step_period", "dir_setup", "dir_hold", "enable_setup"]


@pytest.fixture
def project(pytester: pytest.Pytester) -> pytest.Pytester:
    runs = pytester.path / "runs"
    runs.mkdir()
    write_stepgen_vcd(runs / "fail.vcd")  # dir_hold 9 µs < 20 µs, three times
    write_stepgen_vcd(runs / "pass.vcd", period_ns=25_000, latency_ns=0)
    (pytester.path / "wavecheck.toml").write_text(CONFIG)
    pytester.makepyfile(
        test_api="""
        def test_fixture(wavecheck_check):
            report = wavecheck_check("runs/pass.vcd", "gecko-g202")
            wavecheck_check.expect(report, "pass")

        def test_fixture_fails_readably(wavecheck_check):
            wavecheck_check.expect(wavecheck_check("runs/fail.vcd", "gecko-g202"), "pass")
        """
    )
    return pytester


def test_items_and_outcomes(project: pytest.Pytester) -> None:
    result = project.runpytest("-v", "-p", "no:cacheprovider", "-p", "no:randomly")
    out = result.stdout.str()
    for name in ("g202-p20-j11", "g202-p25", "known-bad"):
        for rule in ["verdict", *RULES[:5]]:
            assert f"wavecheck.toml::{name}::{rule} " in out, (name, rule)
    # enable_setup is not stated by the G202: no item
    assert "::enable_setup" not in out
    lines = {ln.split(" ")[0]: ln for ln in out.splitlines() if ln.startswith("wavecheck.toml::")}
    assert "FAILED" in lines["wavecheck.toml::g202-p20-j11::dir_hold"]
    assert "FAILED" in lines["wavecheck.toml::g202-p20-j11::verdict"]
    assert "PASSED" in lines["wavecheck.toml::g202-p20-j11::step_high"]
    assert "PASSED" in lines["wavecheck.toml::known-bad::dir_hold"]  # expected to fail
    assert "PASSED" in lines["wavecheck.toml::known-bad::verdict"]
    # 3 captures × (verdict + 5 rules) = 18 items + 2 python tests
    result.assert_outcomes(passed=17, failed=3)
    # the failure text is the worst violation, not a traceback
    assert "g202-p20-j11: expected PASS, got dir_hold: FAIL — 3 violation(s)" in out
    assert "at 0.001231000 s: measured 9 us, limit 20 us, margin -11 us" in out
    assert "expected PASS, got verdict FAIL (3 violation(s))" in out  # the fixture's expect()


def test_only_selected_items_run(project: pytest.Pytester) -> None:
    result = project.runpytest("-p", "no:cacheprovider", "wavecheck.toml::g202-p25::dir_hold")
    result.assert_outcomes(passed=1)


def test_with_xdist(project: pytest.Pytester) -> None:
    result = project.runpytest_subprocess("-n", "2", "-p", "no:cacheprovider", "wavecheck.toml")
    result.assert_outcomes(passed=16, failed=2)
    assert "wavecheck.toml::g202-p20-j11::dir_hold" in result.stdout.str()


def test_report_dir(project: pytest.Pytester) -> None:
    result = project.runpytest(
        "-p",
        "no:cacheprovider",
        "--wavecheck-report-dir",
        "reports",
        "wavecheck.toml::g202-p20-j11::dir_hold",
        "wavecheck.toml::g202-p25::dir_hold",
    )
    result.assert_outcomes(passed=1, failed=1)
    assert (project.path / "reports" / "g202-p20-j11.html").exists()
    assert not (project.path / "reports" / "g202-p25.html").exists()


def test_pyproject_table_and_bad_config(pytester: pytest.Pytester) -> None:
    runs = pytester.path / "runs"
    runs.mkdir()
    write_stepgen_vcd(runs / "pass.vcd", period_ns=25_000, latency_ns=0)
    pytester.makefile(
        ".toml",
        pyproject='[[tool.wavecheck.capture]]\npath = "runs/pass.vcd"\ndrive = "gecko-g202"\n',
    )
    result = pytester.runpytest("-p", "no:cacheprovider", "pyproject.toml")
    result.assert_outcomes(passed=6)
    (pytester.path / "pyproject.toml").write_text(
        '[[tool.wavecheck.capture]]\npath = "runs/pass.vcd"\ndrive = "gecko-g202"\nexpec = "fail"\n'
    )
    result = pytester.runpytest("-p", "no:cacheprovider", "pyproject.toml")
    result.assert_outcomes(errors=1)
    assert "unknown key(s) expec" in result.stdout.str()


def test_load_specs_rejects_duplicates(tmp_path: Path) -> None:
    p = tmp_path / "wavecheck.toml"
    p.write_text(
        '[[capture]]\npath = "a.vcd"\ndrive = "x"\n[[capture]]\npath = "b/a.vcd"\ndrive = "x"\n'
    )
    with pytest.raises(WavecheckConfigError, match="two captures are named 'a'"):
        load_specs(p)
