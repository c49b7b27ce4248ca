"""``stepgen simulate --ini/--hal``: LinuxCNC's files fill the options left at their defaults."""

from __future__ import annotations

from pathlib import Path

from stepgen.cli import main
from wavecheck.capture.open import open_capture


def _files(tmp_path: Path) -> tuple[Path, Path]:
    ini = tmp_path / "m.ini"
    ini.write_text("[EMCMOT]\nBASE_PERIOD = 20000\nSERVO_PERIOD = 1000000\n[JOINT_1]\nSTEPLEN = 40000\n")
    hal = tmp_path / "m.hal"
    hal.write_text(
        "loadrt stepgen step_type=0,0 ctrl_type=p,v\n"
        "setp stepgen.1.steplen [JOINT_1]STEPLEN\n"
        "setp stepgen.1.stepspace 20000\n"
    )
    return ini, hal


def _high_times(vcd: Path) -> set[int]:
    step = open_capture(vcd).channel("step")
    e = step.edges.tolist()
    start = 0 if step.initial == 0 else 1
    return {e[i + 1] - e[i] for i in range(start, len(e) - 1, 2)}


def test_files_set_period_type_and_params(tmp_path: Path) -> None:
    ini, hal = _files(tmp_path)
    out = tmp_path / "a.vcd"
    code = main(
        ["simulate", "--ini", str(ini), "--hal", str(hal), "--channel", "1", "--velocity", "1000",
         "--duration", "20ms", "-q", "-o", str(out)]
    )
    assert code == 0
    assert "base 20000 ns" in out.read_text().splitlines()[0]
    assert _high_times(out) == {40_000}  # steplen 40 µs = 2 periods of 20 µs


def test_command_line_wins(tmp_path: Path) -> None:
    ini, hal = _files(tmp_path)
    out = tmp_path / "b.vcd"
    code = main(
        ["simulate", "--ini", str(ini), "--hal", str(hal), "--channel", "1", "--steplen", "20us",
         "--velocity", "1000", "--duration", "20ms", "-q", "-o", str(out)]
    )
    assert code == 0 and _high_times(out) == {20_000}


def test_bad_file_is_one_line_exit_2(tmp_path: Path, capsys) -> None:
    ini = tmp_path / "m.ini"
    ini.write_text("[EMCMOT]\nBASE_PERIOD = soon\n")
    code = main(["simulate", "--ini", str(ini), "--velocity", "1", "-q", "-o", str(tmp_path / "c.vcd")])
    err = capsys.readouterr().err
    assert code == 2 and "m.ini:2" in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "c.vcd").exists()
