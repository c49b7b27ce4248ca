"""``wavecheck check`` with several captures, globs, report files and LinuxCNC configurations."""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from tests.wavecheck.report.traces import write_stepgen_vcd
from wavecheck.cli import main
from wavecheck.cli._batch import expand_captures
from wavecheck.verdict import worst_exit_code


@pytest.fixture
def runs(tmp_path: Path) -> Path:
    write_stepgen_vcd(tmp_path / "fail.vcd")  # G202 at P = 20 µs, J = 11 µs: dir_hold 9 µs
    write_stepgen_vcd(tmp_path / "pass.vcd", period_ns=25_000, latency_ns=0)
    return tmp_path


def _run(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_several_captures_summary_and_worst_exit(runs: Path, capsys) -> None:
    code, out, err = _run(
        capsys, "check", str(runs / "pass.vcd"), str(runs / "fail.vcd"), "--drive", "gecko-g202"
    )
    assert code == 1
    summary = out.split("== summary ==\n", 1)[1].splitlines()
    unchecked = "; enable_setup not checked: drive gecko-g202 states no figure"  # issue 26
    assert summary == [
        f"PASS          {runs / 'pass.vcd'}: 0 violation(s), 120 steps; closest dir_hold +5 us"
        + unchecked,
        f"FAIL          {runs / 'fail.vcd'}: 3 violation(s), 120 steps; closest dir_hold -11 us"
        + unchecked,
    ]
    assert out.count("verdict: ") == 2 and err == ""


def test_glob_and_unreadable_capture(runs: Path, capsys) -> None:
    (runs / "empty.vcd").write_text("")
    code, out, err = _run(capsys, "check", str(runs / "*.vcd"), "--drive", "gecko-g202")
    assert code == 2  # an unusable input is the worst
    assert err.count("\n") == 1 and "empty.vcd: the file is empty" in err
    assert out.splitlines()[-1].startswith("ERROR ") and "FAIL " in out and "PASS " in out


def test_json_and_junit_for_several(runs: Path, capsys, tmp_path: Path) -> None:
    out_json = tmp_path / "r.json"
    code, out, _ = _run(
        capsys,
        "check",
        str(runs / "*.vcd"),
        "--drive",
        "gecko-g202",
        "--format",
        "json",
        "-o",
        str(out_json),
    )
    assert code == 1 and "report written to" in out
    data = json.loads(out_json.read_text())
    assert [r["verdict"] for r in data["reports"]] == ["fail", "pass"]
    assert data["verdict"] == "fail" and data["exit_code"] == 1 and data["errors"] == []
    code, out, _ = _run(
        capsys, "check", str(runs / "*.vcd"), "--drive", "gecko-g202", "--format", "junit"
    )
    root = ET.fromstring(out)
    assert [s.get("name") for s in root.findall("testsuite")] == [
        str(runs / "fail.vcd"),
        str(runs / "pass.vcd"),
    ]
    assert root.get("failures") == "1"


def test_single_capture_keeps_its_shapes(runs: Path, capsys) -> None:
    code, out, _ = _run(
        capsys, "check", str(runs / "fail.vcd"), "--drive", "gecko-g202", "--format", "json"
    )
    assert code == 1 and json.loads(out)["verdict"] == "fail"  # one report object, not a list
    code, out, _ = _run(
        capsys, "check", str(runs / "fail.vcd"), "--drive", "gecko-g202", "--format", "junit"
    )
    assert ET.fromstring(out).find("testsuite/testcase[@name='dir_hold']/failure") is not None


def test_report_files(runs: Path, capsys, tmp_path: Path) -> None:
    out = tmp_path / "out"
    out.mkdir()
    code, _, _ = _run(
        capsys,
        "check",
        str(runs / "fail.vcd"),
        "--drive",
        "gecko-g202",
        "--plot",
        str(out / "p.png"),
        "--html",
        str(out / "r.html"),
        "--gtkw",
        str(out / "g.gtkw"),
    )
    assert code == 1
    assert (out / "p.png").read_bytes()[:4] == b"\x89PNG"
    assert 'id="verdict" class="verdict v-fail">FAIL<' in (out / "r.html").read_text()
    assert "dir_hold FAIL" in (out / "g.gtkw").read_text()


def test_missing_report_folder_fails_before_reading(runs: Path, capsys, tmp_path: Path) -> None:
    code, out, err = _run(
        capsys,
        "check",
        str(runs / "fail.vcd"),
        "--drive",
        "gecko-g202",
        "--plot",
        str(tmp_path / "no" / "p.png"),
    )
    assert code == 2 and out == "" and "--plot" in err and "does not exist" in err


def test_ini_hal_rates(runs: Path, capsys, tmp_path: Path) -> None:
    ini = tmp_path / "m.ini"
    ini.write_text("[EMCMOT]\nBASE_PERIOD = 16000\nSERVO_PERIOD = 1000000\n")
    hal = tmp_path / "m.hal"
    hal.write_text("loadrt stepgen step_type=0\nsetp stepgen.0.dirhold 32000\n")
    code, out, _ = _run(
        capsys,
        "check",
        str(runs / "pass.vcd"),
        "--drive",
        "gecko-g202",
        "--ini",
        str(ini),
        "--hal",
        str(hal),
        "--latency",
        "11us",
        "--format",
        "json",
    )
    rates = json.loads(out)["max_step_rate_hz"]
    assert rates["config"] == 31250 and rates["latency_safe"] == 31250
    code, out, _ = _run(
        capsys,
        "check",
        str(runs / "pass.vcd"),
        "--drive",
        "gecko-g202",
        "--ini",
        str(ini),
        "--hal",
        str(hal),
        "--latency",
        "11us",
    )
    assert "config 31.25 kHz, latency_safe (J = 11 us) 31.25 kHz" in out


def test_latency_without_config_is_a_usage_error(runs: Path, capsys) -> None:
    code, _, err = _run(
        capsys, "check", str(runs / "pass.vcd"), "--drive", "gecko-g202", "--latency", "11us"
    )
    assert code == 2 and "--latency needs the stepgen configuration" in err


def test_helpers(tmp_path: Path) -> None:
    assert worst_exit_code([0, 3, 1]) == 1
    assert worst_exit_code([0, 3]) == 3
    assert worst_exit_code([1, 2, 0]) == 2
    with pytest.raises(Exception, match="no file matches"):
        expand_captures([str(tmp_path / "*.sr")])
