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
    code, out, _ = run(
        capsys, "--drive", "gecko-g202", "--latency", "11us", "--base-period", "16000ns"
    )
    assert code == 0
    assert "--latency 11us" in out
    assert "max step rate 31,250 steps/s" in out
    assert "simple BASE_PERIOD      31000 ns" in out and "16,129 steps/s" in out
    assert "hold = dirhold·P − J" in out
    assert "dirhold          2     32000" in out
    assert "assume the STEP pin not inverted: the drive's falling edge is the end" in out
    assert (
        "(the other reading, with --invert-step: steplen 1, stepspace 1, dirsetup 1, dirhold 1"
        in out
    )


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
        ("11 µs", 11000),
        ("0.011ms", 11000),
        ("11000ns", 11000),
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
        (["--drive", "xylotex", "--latency", "31kHz"], "a frequency where a time is expected"),
        (["--drive", "xylotex", "--latency", "no-such-file.txt"], "neither a time"),
        (
            ["--drive", "xylotex", "--latency", "11us", "--base-period", "10us"],
            "not longer than the latency",
        ),
        (
            ["--drive", "xylotex", "--latency", "11us", "--base-period", "16000.5ns"],
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


# --------------------------------------------------------------------------- latency files

NOX = """\
    1 s   base min:  -3.100 us max:   6.400 us sdev:   0.500 us
    1 s  servo min:  -9.000 us max:  30.000 us sdev:   2.000 us
    2 s   base min: -11.300 us max:  10.200 us sdev:   0.900 us
"""
CYCLICTEST = """\
policy: fifo: loadavg: 0.10 0.05 0.01 1/123 4567
T: 0 ( 1234) P:80 I:1000 C:  10000 Min:      2 Act:    3 Avg:    3 Max:      15
T: 1 ( 1235) P:80 I:1500 C:   6667 Min:      2 Act:    4 Avg:    3 Max:      12
"""
HISTOGRAM = """\
# Histogram
000000 000010\t000020
000001 000100\t000090
000013 000001\t000000
# Total: 000000111 000000110
# Min Latencies: 00000 00000
# Avg Latencies: 00001 00001
# Max Latencies: 00013 00001
# Histogram Overflows: 00000 00000
"""


@pytest.mark.parametrize(
    ("name", "content", "extra", "ns", "phrase"),
    [
        # reference §10.1: latency-test writes the largest Max Jitter (ns) to ~/.latency
        (".latency", "10636\n", [], 10636, "latency-test"),
        # reference §10.2: --nox lines, base thread max(|min|, max) = 11.3 us
        ("nox.txt", NOX, [], 11300, "latency-histogram --nox"),
        # reference §10.4: cyclictest summary, worst Max: over threads, µs
        ("ct.txt", CYCLICTEST, [], 15000, "cyclictest summary"),
        # ... run with -N: the same numbers are ns
        ("ct-n.txt", CYCLICTEST, ["--cyclictest-nsecs"], 15, "cyclictest summary"),
        # reference §10.4: cyclictest -h footer '# Max Latencies'
        ("hist.txt", HISTOGRAM, [], 13000, "Max Latencies"),
    ],
)
def test_latency_files(
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    name: str,
    content: str,
    extra: list[str],
    ns: int,
    phrase: str,
) -> None:
    path = tmp_path / name
    path.write_text(content)
    code, out, _ = run(
        capsys, "--drive", "xylotex", "--latency", str(path), *extra, "--format", "json"
    )
    assert code == 0
    doc = json.loads(out)
    assert doc["latency"]["ns"] == ns
    assert str(path) in doc["latency"]["source"] and phrase in doc["latency"]["source"]
    assert doc["min_base_period_ns"] == ns + 2000  # J + Xylotex's 2 us high time


def test_latency_file_shown_in_text_and_hal(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / ".latency"
    path.write_text("11000\n")
    _, text, _ = run(capsys, "--drive", "gecko-g202", "--latency", str(path))
    assert f"latency J = 11 us ({path}: LinuxCNC latency-test" in text.splitlines()[0]
    _, hal, _ = run(capsys, "--drive", "gecko-g202", "--latency", str(path), "--format", "hal")
    assert str(path) in hal.splitlines()[0] and hal.splitlines()[0].startswith("#")


def test_unreadable_latency_file(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "notes.txt"
    path.write_text("nothing useful here\n")
    code, out, err = run(capsys, "--drive", "xylotex", "--latency", str(path))
    assert code == 2 and out == "" and err.count("\n") == 1 and str(path) in err
