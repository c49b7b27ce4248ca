"""The joint's pid and following-error limits from LinuxCNC's INI/HAL (read_pid_config) and their
mapping into ``stepgen simulate --pid``.

The main pair is written the way pncconf writes a stepgen + pid joint (tests/stepgen/pncconf_pid.py
names the documented fact behind every line); the real configurations in
``shared/firmware/linuxcnc`` have no pid (hm2 position-mode stepgens), only ``[JOINT_n]`` FERROR,
MIN_FERROR and MAX_VELOCITY, which are checked as they are.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from stepgen.cli import main
from tests.conftest import SHARED
from tests.stepgen.pncconf_pid import HAL, INI, line_of, write_pair
from wavecheck.errors import ConfigError
from wavecheck.linuxcnc.pid_settings import read_pid_config
from wavecheck.linuxcnc.stepgen_config import read_config

FW = SHARED / "firmware/linuxcnc"


@pytest.mark.parametrize(
    "channel,name,joint,pgain",
    [
        (0, "pid.x", 0, 1000.0),  # [PNC] P = 1/servo period (1 ms → 1000)
        (1, "pid.y", 1, 800.0),  # the hand-tuned joint: its own instance, its own [JOINT_1]
    ],
)
def test_pncconf_pair(tmp_path: Path, channel: int, name: str, joint: int, pgain: float) -> None:
    """The instance is the one whose output is netted to stepgen.N.velocity-cmd (reference §3
    wiring), its joint the one netted to pid.command; every value is the INI's, through pncconf's
    ``setp pid.x.Pgain [JOINT_0]P`` references, and remembers its HAL line."""
    ini, hal = write_pair(tmp_path)
    pc = read_pid_config(ini, [hal], channel=channel)
    assert (pc.name, pc.joint, pc.drives) == (name, joint, f"stepgen.{channel}.velocity-cmd")
    assert pc.pins == {
        "Pgain": pgain,
        "Igain": 0.0,  # [PNC] I = D = FF0 = FF2 = BIAS = 0, DEADBAND = 0, MAX_OUTPUT = 0
        "Dgain": 0.0,
        "bias": 0.0,
        "FF0": 0.0,
        "FF1": 1.0,  # [PNC] FF1 = 1 (velocity-mode stepgen: the output is already units/s)
        "FF2": 0.0,
        "deadband": 0.0,
        "maxoutput": 0.0,
        "maxerror": 0.0127,  # [PNC] "%f" of 0.0127 mm for a stepper joint
    }
    assert pc.error_previous_target is True  # [PNC] writes it although it is the default
    # [PNC] metric FERROR/MIN_FERROR 10/1 mm; motion scales FERROR by the joint's MAX_VELOCITY (§4.4)
    assert (pc.ferror, pc.min_ferror, pc.max_velocity, pc.max_acceleration) == (10, 1, 20, 200)
    let = name[-1]
    assert pc.sources["Pgain"] == f"{hal}:{line_of(HAL, f'pid.{let}.Pgain')}"
    assert pc.sources["maxerror"] == f"{hal}:{line_of(HAL, f'pid.{let}.maxerror')}"
    section = INI.index(f"[JOINT_{joint}]")
    assert pc.sources["FERROR"] == f"{ini}:{INI[:section].count(chr(10)) + 4}"  # header, TYPE, HOME
    assert pc.ignored == []


def test_stepgen_settings_untouched_by_the_pid_block(tmp_path: Path) -> None:
    """The one INI/HAL parser still reads the stepgen side of the same pair as before."""
    ini, hal = write_pair(tmp_path)
    cfg = read_config(ini, [hal], 1)
    assert cfg.ctrl_type == "velocity"
    assert cfg.params == {"dirsetup": 10000, "dirhold": 10000, "steplen": 5000, "stepspace": 5000}
    assert cfg.floats == {"position-scale": 200.0, "maxaccel": 250.0, "maxvel": 25.0}


def _hal(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "x.hal"
    path.write_text(text)
    return path


def test_num_chan_instances_joint_refs_and_literal_values(tmp_path: Path) -> None:
    """``loadrt pid num_chan=2`` makes pid.0 and pid.1 (reference §1); without a net to the
    stepgen, the joint's instance is the one whose setp values read ``[JOINT_1]``; literal values
    and the ``pin = value`` form count as well; an INI gain no setp reads is listed, not used."""
    ini = tmp_path / "m.ini"
    ini.write_text("[JOINT_1]\nP = 50\nI = 7\nFERROR = 2\n")
    hal = _hal(
        tmp_path,
        "loadrt pid num_chan=2\nsetp pid.0.Pgain 3\nsetp pid.1.Pgain [JOINT_1]P\n"
        "pid.1.FF1 = 1\nsetp pid.1.error-previous-target false\n",
    )
    pc = read_pid_config(ini, [hal], joint=1)
    assert pc.name == "pid.1" and pc.pins == {"Pgain": 50.0, "FF1": 1.0}
    assert pc.error_previous_target is False and pc.ferror == 2.0 and pc.min_ferror is None
    assert len(pc.ignored) == 1 and "[JOINT_1]I = 7" in pc.ignored[0] and "m.ini:3" in pc.ignored[0]
    assert read_pid_config(ini, [hal], name="pid.0").pins == {"Pgain": 3.0}


def test_ini_only_gains(tmp_path: Path) -> None:
    """No pid in the HAL files: the INI's [JOINT_n] gains are the pins (as pncconf's setp lines
    would read them), the joint is the channel's."""
    ini = tmp_path / "m.ini"
    ini.write_text("[JOINT_2]\nP = 700\nFF1 = 1\nMAX_OUTPUT = 30\nMIN_FERROR = 0.1\n")
    pc = read_pid_config(ini, None, channel=2)
    assert pc.name is None and pc.joint == 2
    assert pc.pins == {"Pgain": 700.0, "FF1": 1.0, "maxoutput": 30.0}
    assert pc.sources["maxoutput"] == f"{ini}:4" and pc.min_ferror == 0.1


def test_nets_to_tunable_pins_are_listed(tmp_path: Path) -> None:
    hal = _hal(
        tmp_path,
        "loadrt pid names=pid.s\nsetp pid.s.Pgain 5\nnet ratio pid.s.maxoutput\n"
        "net vel-fb => pid.s.feedback-deriv\n",
    )
    pc = read_pid_config(None, [hal], name="pid.s")
    assert any("pid.s.maxoutput" in line for line in pc.ignored)
    assert any("feedback-deriv" in line and "derivative estimate" in line for line in pc.ignored)


@pytest.mark.parametrize(
    "ini_text,hal_text,kwargs,match",
    [
        (
            "",
            "setp pid.0.Pgain fast\n",
            {"joint": 0},
            r"x\.hal:1: pid\.0\.Pgain 'fast' is not a number",
        ),
        ("", "setp pid.0.Pgain nan\n", {"joint": 0}, r"x\.hal:1: .*not a finite number"),
        ("", "setp pid.0.Pgain [JOINT_0]P\n", {"joint": 0}, r"x\.hal:1: \[JOINT_0\]P is not in"),
        ("", "setp pid.0.error-previous-target maybe\n", {"joint": 0}, r"not 0, 1, true or false"),
        ("[JOINT_0]\nFERROR = 0\n", "", {}, r"m\.ini:2: \[JOINT_0\]FERROR 0 must be > 0"),
        ("[JOINT_0]\nMIN_FERROR = -1\n", "", {}, r"MIN_FERROR -1 must be >= 0"),
        ("[JOINT_0]\nP = 1e999\n", "", {}, r"m\.ini:2: \[JOINT_0\]P '1e999' is not a finite"),
        ("", "loadrt pid num_chan=40\n", {}, r"x\.hal:1: loadrt pid makes 40 instances"),
        ("", "loadrt pid num_chan=2 names=a\n", {}, r"num_chan= or names=, not both"),
        (
            "",
            "loadrt pid names=pid.x\n",
            {"name": "pid.z"},
            r"'pid\.z' is not in the HAL files \(pid instances: pid\.x\)",
        ),
    ],
)
def test_bad_values_name_file_and_line(tmp_path: Path, ini_text, hal_text, kwargs, match) -> None:
    ini = tmp_path / "m.ini"
    ini.write_text(ini_text)
    with pytest.raises(ConfigError, match=match):
        read_pid_config(ini, [_hal(tmp_path, hal_text)], **kwargs)


@pytest.mark.skipif(not FW.is_dir(), reason="shared LinuxCNC configurations not present")
@pytest.mark.parametrize(
    "ini,hal,limits",
    [
        ("hm2-stepper/5i20.ini", "hm2-stepper/hm2-stepper.hal", (0.05, 0.005, 10.0)),
        ("plasma-5i20/plasma-5i20.ini", "plasma-5i20/plasma-5i20.hal", (0.05, 0.005, 7.0)),
    ],
)
def test_real_configurations(ini: str, hal: str, limits: tuple[float, float, float]) -> None:
    """The shipped configurations drive hm2 stepgens in position mode with no pid (their HAL
    says "revel in the free time here from not having to run PID"): no instance, no gains,
    and [JOINT_0]'s FERROR/MIN_FERROR/MAX_VELOCITY as their INI writes them."""
    pc = read_pid_config(FW / ini, [FW / hal], channel=0)
    assert pc.name is None and pc.pins == {} and pc.drives is None
    assert (pc.ferror, pc.min_ferror, pc.max_velocity) == limits


# --- stepgen simulate --pid --ini/--hal --------------------------------------------------------


def _simulate(capsys, *argv: str) -> tuple[int, str, str]:
    code = main(["simulate", "--pid", *argv])
    out = capsys.readouterr()
    return code, out.out, out.err


def test_simulate_takes_gains_and_limits_from_the_files(tmp_path: Path, capsys) -> None:
    """pncconf's gains (P = 1000, FF1 = 1, maxerror 0.0127) drive the loop; FERROR 10 scaled
    by MAX_VELOCITY 20 and MIN_FERROR 1 are the check's limit; the move keeps to the joint's
    MAX_VELOCITY/MAX_ACCELERATION, so stepgen's 1.25× leaves the loop headroom and the error
    stays at the size test_servo_loop explains (< 2·(a·T)²/(2·maxaccel) = 1.6e-4)."""
    ini, hal = write_pair(tmp_path)
    code, out, err = _simulate(
        capsys, "--ini", str(ini), "--hal", str(hal), "--move", "10", "-o", str(tmp_path / "a.vcd")
    )
    assert code == 0
    assert "pid: Pgain 1000, FF1 1, maxerror 0.0127 (pid.x, joint 0" in out
    assert "limit max(FERROR 10·|v|/20, MIN_FERROR 1)" in out
    worst = float(out.split("following error: max ")[1].split()[0])
    assert 0 < worst < 1.6e-4
    assert "velocity-cmd" not in err  # the pid's net to velocity-cmd is honoured, not "ignored"


def test_simulate_command_line_wins(tmp_path: Path, capsys) -> None:
    ini, hal = write_pair(tmp_path)
    code, out, _ = _simulate(
        capsys,
        "--ini",
        str(ini),
        "--hal",
        str(hal),
        "--channel",
        "1",
        "--pgain",
        "500",
        "--ferror",
        "3",
        "--no-error-previous-target",
        "--move",
        "10",
        "-o",
        str(tmp_path / "b.vcd"),
    )
    assert code == 0
    assert (
        "pid: Pgain 500, FF1 1, maxerror 0.0127, error-previous-target false (pid.y, joint 1" in out
    )
    assert "FERROR 3·|v|/20, MIN_FERROR 1" in out


def test_files_set_only_some_pins_the_rest_are_the_component_defaults(
    tmp_path: Path, capsys
) -> None:
    """As in LinuxCNC: pid's pins the files do not set keep pid's own defaults (FF1 = 0), not
    pncconf's P = 1/T, FF1 = 1 that a run without files assumes."""
    ini = tmp_path / "m.ini"
    ini.write_text("[EMCMOT]\nBASE_PERIOD = 25000\nSERVO_PERIOD = 1000000\n[JOINT_0]\nP = 300\n")
    code, out, _ = _simulate(
        capsys,
        "--ini",
        str(ini),
        "--position-scale",
        "200",
        "--maxvel",
        "25",
        "--move",
        "1",
        "--move-vel",
        "10",
        "--move-accel",
        "100",
        "-o",
        str(tmp_path / "c.vcd"),
    )
    assert code == 0 and "pid: Pgain 300 ([JOINT_0] of the INI)" in out


def test_open_loop_run_notes_the_pid(tmp_path: Path, capsys) -> None:
    ini, hal = write_pair(tmp_path)
    code = main(
        [
            "simulate",
            "--ini",
            str(ini),
            "--hal",
            str(hal),
            "--velocity",
            "5",
            "--duration",
            "5ms",
            "-q",
            "-o",
            str(tmp_path / "d.vcd"),
        ]
    )
    assert code == 0 and "pid.x.output drives stepgen.0.velocity-cmd" in capsys.readouterr().err
