"""LinuxCNC's INI and HAL syntax as the ``linuxcnc`` script and halcmd read it: values continued
with ``\\``, ``#INCLUDE`` files, lines LinuxCNC ignores, Tcl HAL files' literal commands, and the
bound on every file (a device or a FIFO is refused unread)."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from wavecheck.config_text import read_text
from wavecheck.errors import ConfigError
from wavecheck.linuxcnc.files import hal_lines, int_ns, read_ini


def test_continued_values_and_includes(tmp_path: Path) -> None:
    (tmp_path / "base.inc").write_text("[EMCMOT]\nBASE_PERIOD = 25000\n")
    (tmp_path / "m.ini").write_text(
        "#INCLUDE base.inc\n[APPLICATIONS]\nAPP = sim_pin \\\n  a \\\n  b\n[HAL]\nHALFILE = m.hal\n"
    )
    ini = read_ini(tmp_path / "m.ini")
    assert ini.get("EMCMOT", "BASE_PERIOD") == ("25000", 2)
    assert ini.place("EMCMOT", "BASE_PERIOD") == f"{tmp_path / 'base.inc'}:2"  # its own file
    assert ini.get("APPLICATIONS", "APP") == ("sim_pin a b", 3)
    assert ini.place("HAL", "HALFILE") == f"{tmp_path / 'm.ini'}:7"


def test_lines_linuxcnc_ignores_are_listed_not_refused(tmp_path: Path) -> None:
    (tmp_path / "m.ini").write_text("[DISPLAY]\nthis is no setting\nDISPLAY = axis\n")
    ini = read_ini(tmp_path / "m.ini")
    assert ini.get("DISPLAY", "DISPLAY") == ("axis", 3)
    assert len(ini.ignored) == 1 and "m.ini:2" in ini.ignored[0]


@pytest.mark.parametrize(
    ("files", "needle"),
    [
        ({"m.ini": "#INCLUDE missing.inc\n"}, r"m\.ini:1: #INCLUDE missing\.inc: no such file"),
        ({"m.ini": "#INCLUDE a.inc\n", "a.inc": "#INCLUDE m.ini\n"}, "loops"),
    ],
)
def test_include_errors(tmp_path: Path, files: dict[str, str], needle: str) -> None:
    for name, text in files.items():
        (tmp_path / name).write_text(text)
    with pytest.raises(ConfigError, match=needle):
        read_ini(tmp_path / "m.ini")


def test_hal_continuations_keep_their_first_line(tmp_path: Path) -> None:
    (tmp_path / "m.hal").write_text(
        "# c\nloadrt stepgen \\\n  step_type=0\nsetp stepgen.0.steplen 1 # x\n"
    )
    lines, computed = hal_lines(tmp_path / "m.hal")
    assert [(x.text, x.where.rsplit(":", 1)[1]) for x in lines] == [
        ("loadrt stepgen step_type=0", "2"), ("setp stepgen.0.steplen 1", "4")]  # fmt: skip
    assert computed == []


def test_tcl_hal_files_give_their_literal_commands(tmp_path: Path) -> None:
    (tmp_path / "m.tcl").write_text(
        "proc f {} {}\nloadrt stepgen step_type=0\nsetp stepgen.0.steplen $::JOINT_0(STEPLEN)\n"
        "loadrt $::KINS(KINEMATICS) ;# ini\nloadrt $kins\nset x [expr 1]\n"
    )
    lines, computed = hal_lines(tmp_path / "m.tcl")
    assert [x.text for x in lines] == [
        "loadrt stepgen step_type=0", "setp stepgen.0.steplen [JOINT_0](STEPLEN)",
        "loadrt [KINS](KINEMATICS)"]  # fmt: skip
    assert len(computed) == 1 and "m.tcl:5" in computed[0]


def test_devices_and_fifos_are_refused_unread(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="/dev/zero: is a character device"):
        read_text("/dev/zero")
    os.mkfifo(tmp_path / "f.ini")
    with pytest.raises(ConfigError, match="FIFO"):
        read_ini(tmp_path / "f.ini")  # would block forever if opened


@pytest.mark.parametrize("value", ["1e999999999", "1e400", "9" * 5000, "nan", "-1", "4294967296"])
def test_ns_values_are_bounded(value: str) -> None:
    with pytest.raises(ConfigError, match=r"^m\.hal:3: steplen "):
        int_ns(value, "m.hal:3", "steplen")
