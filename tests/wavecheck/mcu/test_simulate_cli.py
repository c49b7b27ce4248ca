"""``wavecheck simulate grbl`` on bad input: one line naming the file and the place, exit 2, no
VCD left behind; every run bounded in simulated and wall time."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.wavecheck.mcu.helpers import GRBL_SRC, SIMAVR_SRC, build_avr
from tests.wavecheck.mcu.test_simavr_fixes import CTC_ZERO
from wavecheck.cli import main


def _run(tmp: Path, gcode: str, *extra: str) -> Path:
    g = tmp / "job.nc"
    g.write_text(gcode)
    vcd = tmp / "out.vcd"
    code = main(
        ["simulate", "grbl", "--gcode", str(g), "--vcd", str(vcd), "--drive", "drv8825"]
        + ["--grbl-src", str(GRBL_SRC), "--simavr-src", str(SIMAVR_SRC), *extra]
    )
    assert code == 2
    assert not vcd.exists()
    return g


def _error(capsys: pytest.CaptureFixture[str]) -> str:
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("wavecheck: error: "), err
    return err[0]


def test_rejected_gcode_names_the_line_and_grbls_error(grbl, tmp_path, capsys):
    g = _run(tmp_path, "G21\nG1 X10\n")  # no feed rate yet: grbl's error:22
    line = _error(capsys)
    assert f"{g}:2: grbl rejected 'G1 X10': error:22 (gcode undefined feed rate)" in line


def test_a_firmware_without_the_banner(runner, tmp_path, capsys):
    elf = build_avr(tmp_path, "quiet", CTC_ZERO)
    _run(tmp_path, "G1 X1 F100\n", "--elf", str(elf), "--max-time", "50ms")
    assert "no grbl banner" in _error(capsys)


@pytest.mark.parametrize("mcu, expect", [("atmega2560", "avr6 family")])
def test_an_elf_for_another_mcu(runner, tmp_path, capsys, mcu, expect):
    elf = build_avr(tmp_path, "other", CTC_ZERO, mcu=mcu)
    _run(tmp_path, "G1 X1 F100\n", "--elf", str(elf))
    line = _error(capsys)
    assert str(elf) in line and expect in line and "-mmcu=atmega328p" in line


def test_a_file_that_is_no_elf(runner, tmp_path, capsys):
    bad = tmp_path / "grbl.hex"
    bad.write_text(":100000000C9434000C9451000C9451000C94510049\n")
    _run(tmp_path, "G1 X1 F100\n", "--elf", str(bad))
    assert "not a 32-bit little-endian ELF" in _error(capsys)


def test_a_job_longer_than_the_simulated_time_limit(grbl, tmp_path, capsys):
    _run(tmp_path, "G1 X100 F60\n", "--max-time", "0.5s")  # 100 s of motion
    line = _error(capsys)
    assert "did not finish within the simulated time limit" in line and "--max-time" in line


def test_the_wall_time_limit(grbl, tmp_path, capsys):
    _run(tmp_path, "G1 X100 F60\n", "--max-time", "200s", "--timeout", "0.2s")
    assert "wall time" in _error(capsys)


def test_settings_that_are_gcode(tmp_path, capsys):
    s = tmp_path / "s.txt"
    s.write_text("$0=10\nG1 X1\n")
    _run(tmp_path, "G1 X1 F100\n", "--settings", str(s))
    assert f"{s}:2: 'G1 X1' is not a grbl setting" in _error(capsys)


def test_an_alarm_names_the_line_and_gives_the_hint(grbl, tmp_path, capsys):
    s = tmp_path / "s.txt"
    s.write_text("$20=1\n$22=1\n")  # as a $$ dump lists them: $20 before $22 (sent after it)
    g = _run(tmp_path, "G21\nG1 X5 F500\n", "--settings", str(s))
    line = _error(capsys)
    assert f"{g}:2: grbl raised ALARM:2 (soft limit)" in line and "$20=0" in line


def test_soft_limits_from_a_dump_inside_them(grbl, tmp_path, capsys):
    s, g = tmp_path / "s.txt", tmp_path / "job.nc"
    s.write_text("$20=1\n$22=1\n$130=200\n")
    g.write_text("G1 X-5 F500\n")  # machine space is negative (grbl's default, config.h)
    vcd = tmp_path / "out.vcd"
    code = main(
        ["simulate", "grbl", "--gcode", str(g), "--settings", str(s), "--vcd", str(vcd)]
        + ["--drive", "drv8825", "--grbl-src", str(GRBL_SRC), "--simavr-src", str(SIMAVR_SRC)]
    )
    assert code == 0 and "steps:   1250" in capsys.readouterr().out


def test_a_line_longer_than_the_runner_sends(tmp_path, capsys):
    g = _run(tmp_path, "G1 X1 F100\nG1 X2 (" + "a" * 5000 + ")\n")
    assert f"{g}:2: a line of 5008 characters" in _error(capsys)


def test_axes_that_grbl_has_not(tmp_path, capsys):
    _run(tmp_path, "G1 X1 F100\n", "--axes", "xa")
    assert "--axes xa: grbl's axes are x, y and z" in _error(capsys)
