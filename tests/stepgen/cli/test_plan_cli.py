"""`stepgen plan` on the command line: formats, the latency reading, one-line errors."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from stepgen.cli import main

JSON_KEYS = {
    "min_base_period_ns",
    "simple_base_period_ns",
    "base_period_ns",
    "params",
    "max_step_rate_hz",
    "margins_ns",
}


def run(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    code = main(["plan", *argv])
    out, err = capsys.readouterr()
    return code, out, err


def test_json_g202_seed(capsys: pytest.CaptureFixture[str]) -> None:
    """Seed 000: G202, J = 11 us, P = 16 us → dirhold 2 periods, 31,250 steps/s; 31 us simple."""
    code, out, _ = run(
        capsys,
        "--drive",
        "gecko-g202",
        "--latency",
        "11us",
        "--base-period",
        "16us",
        "--format",
        "json",
    )
    assert code == 0
    doc = json.loads(out)
    assert JSON_KEYS <= doc.keys()
    assert doc["base_period_ns"] == 16000
    assert doc["simple_base_period_ns"] == 31000
    assert doc["min_base_period_ns"] == 15500
    assert set(doc["params"]) == {"steplen", "stepspace", "dirsetup", "dirhold"}
    assert doc["params"]["dirhold"] == {
        "ns": 32000,
        "periods": 2,
        "reason": doc["params"]["dirhold"]["reason"],
    }
    assert all({"ns", "periods"} <= v.keys() for v in doc["params"].values())
    assert doc["max_step_rate_hz"] == 31250
    assert doc["margins_ns"]["dir_hold"] == 1000
    assert doc["latency"] == {"ns": 11000, "source": "--latency 11us"}
    assert doc["step_inverted"] is False and doc["active_edge_at"] == "end"
    assert any("below 25 us" in w for w in doc["warnings"])


def test_text_states_mapping_and_latency_source(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run(capsys, "--drive", "gecko-g202", "--latency", "11", "--base-period", "16000")
    assert code == 0
    assert "bare number below 1000 is us" in out
    assert "max step rate 31,250 steps/s" in out
    assert "simple BASE_PERIOD      31000 ns" in out and "16,129 steps/s" in out
    assert "hold = dirhold·P − J" in out
    assert "dirhold          2     32000" in out


def test_invert_step_changes_the_reading(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run(
        capsys,
        "--drive",
        "gecko-g202",
        "--latency",
        "11us",
        "--base-period",
        "16us",
        "--invert-step",
        "--format",
        "json",
    )
    doc = json.loads(out)
    assert code == 0 and doc["step_inverted"] is True and doc["active_edge_at"] == "start"
    assert doc["params"]["dirhold"]["periods"] == 1


def test_ini_format(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run(
        capsys, "--drive", "xylotex", "--latency", "11us", "--format", "ini", "--channel", "1"
    )
    assert code == 0
    lines = out.splitlines()
    assert lines[lines.index("[EMCMOT]") + 1] == "BASE_PERIOD = 13000"
    assert "[JOINT_1]" in lines and "STEPLEN = 13000" in lines and "DIRHOLD = 13000" in lines
    assert all(line.startswith("#") for line in lines[: lines.index("[EMCMOT]")])
    assert "not inverted" in out


def test_hal_format(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run(
        capsys,
        "--drive",
        "gecko-g202",
        "--latency",
        "11us",
        "--base-period",
        "16us",
        "--format",
        "hal",
        "--channel",
        "2",
    )
    assert code == 0
    setp = [line for line in out.splitlines() if not line.startswith("#")]
    assert setp == [
        "setp stepgen.2.steplen 16000",
        "setp stepgen.2.stepspace 16000",
        "setp stepgen.2.dirsetup 16000",
        "setp stepgen.2.dirhold 32000",
    ]
    assert "# BASE_PERIOD = 16000 ns" in out


def test_output_file(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    target = tmp_path / "stepgen.hal"
    code, out, err = run(
        capsys, "--drive", "xylotex", "--latency", "11us", "--format", "hal", "-o", str(target)
    )
    assert code == 0 and out == "" and "wrote" in err
    assert "setp stepgen.0.steplen 13000" in target.read_text()


@pytest.mark.parametrize(
    ("latency", "reading_ns"),
    [
        ("11us", 11000),
        ("11", 11000),
        ("999", 999000),
        ("11000", 11000),
        ("10.6us", 10600),
        ("15000 ns", 15000),
    ],
)
def test_latency_reading(capsys: pytest.CaptureFixture[str], latency: str, reading_ns: int) -> None:
    code, out, _ = run(capsys, "--drive", "xylotex", "--latency", latency, "--format", "json")
    assert code == 0 and json.loads(out)["latency"]["ns"] == reading_ns


@pytest.mark.parametrize(
    ("argv", "phrase"),
    [
        (["--drive", "xylotex", "--latency", "0"], "must be positive"),
        (["--drive", "xylotex", "--latency=-5us"], "must be positive"),
        (["--drive", "xylotex", "--latency", "5s"], "over 1 ms"),
        (["--drive", "xylotex", "--latency", "2ms"], "over 1 ms"),
        (["--drive", "xylotex", "--latency", "31kHz"], "neither a time"),
        (["--drive", "xylotex", "--latency", "no-such-file.txt"], "neither a time"),
        (
            ["--drive", "xylotex", "--latency", "11us", "--base-period", "10us"],
            "not longer than the latency",
        ),
        (
            ["--drive", "xylotex", "--latency", "11us", "--base-period", "16.5ns"],
            "whole number of ns",
        ),
        (["--drive", "xylotex", "--latency", "11us", "--base-period", "2 MHz"], "frequency"),
        (["--drive", "no-such-drive", "--latency", "11us"], "no-such-drive"),
        (
            ["--drive", "xylotex", "--latency", "11us", "--format", "hal", "--channel", "16"],
            "channels 0..15",
        ),
    ],
)
def test_bad_input_exit_2_one_line(
    capsys: pytest.CaptureFixture[str], argv: list[str], phrase: str
) -> None:
    code, out, err = run(capsys, *argv)
    assert code == 2 and out == ""
    assert err.count("\n") == 1 and phrase in err, err


def test_incomplete_drive_file(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    rule = tmp_path / "half-drive.toml"
    rule.write_text(
        'id = "half-drive"\nname = "Half"\nkind = "user"\ninterface = "step-dir"\n'
        'active_edge = "rising"\n[limits.step_high]\nvalue = "2us"\nsource = "X"\nstatus = "datasheet"\n'
        '[limits.step_low]\nvalue = "2us"\nsource = "X"\nstatus = "datasheet"\n'
        '[limits.dir_setup]\nvalue = "1us"\nsource = "X"\nstatus = "datasheet"\n'
        '[sources]\nX = "test"\n'
    )
    code, out, err = run(capsys, "--drive", str(rule), "--latency", "11us")
    assert code == 2 and out == ""
    assert err.count("\n") == 1 and "gives no dir_hold figure" in err
