"""``stepgen simulate --ini/--hal``: LinuxCNC's files fill the options left at their defaults."""

from __future__ import annotations

from pathlib import Path

from stepgen.cli import main
from wavecheck.capture.open import open_capture


def _files(tmp_path: Path) -> tuple[Path, Path]:
    ini = tmp_path / "m.ini"
    ini.write_text(
        "[EMCMOT]\nBASE_PERIOD = 20000\nSERVO_PERIOD = 1000000\n[JOINT_1]\nSTEPLEN = 40000\n"
    )
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
        [
            "simulate",
            "--ini",
            str(ini),
            "--hal",
            str(hal),
            "--channel",
            "1",
            "--velocity",
            "1000",
            "--duration",
            "20ms",
            "-q",
            "-o",
            str(out),
        ]
    )
    assert code == 0
    assert "base 20000 ns" in out.read_text().splitlines()[0]
    assert _high_times(out) == {40_000}  # steplen 40 µs = 2 periods of 20 µs


def test_command_line_wins(tmp_path: Path) -> None:
    ini, hal = _files(tmp_path)
    out = tmp_path / "b.vcd"
    code = main(
        [
            "simulate",
            "--ini",
            str(ini),
            "--hal",
            str(hal),
            "--channel",
            "1",
            "--steplen",
            "20us",
            "--velocity",
            "1000",
            "--duration",
            "20ms",
            "-q",
            "-o",
            str(out),
        ]
    )
    assert code == 0 and _high_times(out) == {20_000}


def test_bad_file_is_one_line_exit_2(tmp_path: Path, capsys) -> None:
    ini = tmp_path / "m.ini"
    ini.write_text("[EMCMOT]\nBASE_PERIOD = soon\n")
    code = main(
        ["simulate", "--ini", str(ini), "--velocity", "1", "-q", "-o", str(tmp_path / "c.vcd")]
    )
    err = capsys.readouterr().err
    assert code == 2 and "m.ini:2" in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "c.vcd").exists()


# LinuxCNC's tests/stepgen.0 set-up as reference §8 describes it (written here, not copied): one
# exact 100 µs thread "fast" running update-freq, make-pulses, capture-position, sampler in that
# order; step_type 0, position mode, maxvel 0.15, maxaccel 2, scale 32000, position-cmd 0.04.
STEPGEN0_HAL = """\
loadrt stepgen step_type=0
loadrt threads name1=fast period1=100000
loadrt sampler cfg=bb depth=4096
net dir-out stepgen.0.dir sampler.0.pin.0
net step-out stepgen.0.step sampler.0.pin.1
addf stepgen.update-freq fast
addf stepgen.make-pulses fast
addf stepgen.capture-position fast
addf sampler.0 fast
setp stepgen.0.position-scale 32000
setp stepgen.0.maxvel .15
setp stepgen.0.maxaccel 2
setp stepgen.0.position-cmd .04
setp stepgen.0.enable 1
start
"""


def _rises(vcd: Path) -> list[int]:
    step = open_capture(vcd).channel("step")
    e = step.edges.tolist()
    return e[0::2] if step.initial == 0 else e[1::2]


def test_stepgen0_hal_runs_as_written(tmp_path: Path, capsys) -> None:
    """§8: the tests/stepgen.0 HAL, 3500 periods: 1280 single-period pulses at P = 100 µs, the
    first rising edge at period 39 (update-freq first: the start-up quirk of §3). Nothing ignored."""
    hal = tmp_path / "test.hal"
    hal.write_text(STEPGEN0_HAL)
    out = tmp_path / "s0.vcd"
    assert main(["simulate", "--hal", str(hal), "--periods", "3500", "-q", "-o", str(out)]) == 0
    assert capsys.readouterr().err == ""
    rises = _rises(out)
    assert len(rises) == 1280
    assert rises[0] == 39 * 100_000
    assert _high_times(out) == {100_000}


def test_addf_order_sets_the_thread_order(tmp_path: Path) -> None:
    """§3: with make-pulses added first there is no start-up quirk, so the first edge moves."""
    hal = tmp_path / "test.hal"
    hal.write_text(
        STEPGEN0_HAL.replace("addf stepgen.update-freq fast\n", "").replace(
            "addf stepgen.make-pulses fast\n",
            "addf stepgen.make-pulses fast\naddf stepgen.update-freq fast\n",
        )
    )
    out = tmp_path / "s1.vcd"
    assert main(["simulate", "--hal", str(hal), "--periods", "3500", "-q", "-o", str(out)]) == 0
    rises = _rises(out)
    assert len(rises) == 1280 and rises[0] != 39 * 100_000


def test_what_the_model_cannot_honour_is_named(tmp_path: Path, capsys) -> None:
    """A net driving position-cmd, a setp the model has no use for, a command overridden on the
    command line: each is one ``stepgen: ignored:`` line naming the file and line."""
    hal = tmp_path / "m.hal"
    hal.write_text(
        "loadrt threads name1=base period1=25000 name2=servo period2=1000000\n"
        "loadrt stepgen step_type=0\n"
        "addf stepgen.make-pulses base\n"
        "addf stepgen.update-freq servo\n"
        "net xpos joint.0.motor-pos-cmd => stepgen.0.position-cmd\n"
        "net xen joint.0.amp-enable-out => stepgen.0.enable\n"
        "setp stepgen.0.position-cmd 2\n"
        "setp stepgen.0.frobnicate 1\n"
    )
    out = tmp_path / "m.vcd"
    code = main(
        [
            "simulate",
            "--hal",
            str(hal),
            "--move",
            "1",
            "--move-vel",
            "100",
            "--move-accel",
            "1000",
            "-q",
            "-o",
            str(out),
        ]
    )
    err = capsys.readouterr().err.splitlines()
    assert code == 0
    assert (
        f"stepgen: ignored: net xpos joint.0.motor-pos-cmd => stepgen.0.position-cmd ({hal}:5) (the model drives position-cmd itself"
        in "\n".join(err)
    )
    assert any(f"({hal}:6) (the model keeps enable on)" in e for e in err)
    assert any(f"stepgen.0.position-cmd 2 ({hal}:7): --move drives the command" in e for e in err)
    assert any(f"frobnicate 1 ({hal}:8)" in e for e in err)
    assert len(err) == 4
    assert "base 25000 ns" in out.read_text().splitlines()[0]
