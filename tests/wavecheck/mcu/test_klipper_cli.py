"""``wavecheck simulate klipper`` on bad input: one line naming the file and the place, exit 2, no
VCD left behind; every run bounded in simulated and wall time. The first tests stop before any
build; the rest build Klipper (slow)."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.wavecheck.mcu.helpers import (
    KLIPPER_SRC,
    REPO,
    SIMAVR_SRC,
    build_avr,
    rising,
    vcd_changes,
)
from wavecheck.cli import main
from wavecheck.errors import ConfigError

CONFIG = REPO / "docs" / "klipper" / "printer.cfg"
ZIGZAG = REPO / "docs" / "klipper" / "zigzag.gcode"
START = "SET_KINEMATIC_POSITION X=100 Y=100 Z=10\n"


def _run(tmp: Path, gcode: str | Path, *extra: str, config: Path = CONFIG) -> Path:
    g = gcode if isinstance(gcode, Path) else tmp / "job.gcode"
    if not isinstance(gcode, Path):
        g.write_text(gcode)
    vcd = tmp / "out.vcd"
    code = main(
        ["simulate", "klipper", "--config", str(config), "--gcode", str(g), "--vcd", str(vcd)]
        + ["--drive", "drv8825", "--klipper-src", str(KLIPPER_SRC)]
        + ["--simavr-src", str(SIMAVR_SRC), *extra]
    )
    assert code == 2
    assert not vcd.exists()
    return g


def _error(capsys: pytest.CaptureFixture[str]) -> str:
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("wavecheck: error: "), err
    return err[0]


@pytest.mark.parametrize(
    "extra, says",
    [
        (("--settings", "s.txt"), "--settings is an option of simulate grbl only"),
        (("--elf", str(CONFIG)), "--elf and --dict go together"),
        (("--axes", "q"), "--axes q: "),
    ],
)
def test_options_that_do_not_fit(tmp_path, capsys, extra, says):
    _run(tmp_path, START, *extra)
    assert says in _error(capsys)


def test_a_pin_that_is_not_the_mcus(tmp_path, capsys):
    cfg = tmp_path / "printer.cfg"
    cfg.write_text(CONFIG.read_text().replace("step_pin: PC6", "step_pin: host:gpio17"))
    _run(tmp_path, START, config=cfg)
    line = _error(capsys)
    assert f"{cfg} [stepper_y]: pin 'host:gpio17'" in line


slow = pytest.mark.slow


@slow
def test_gcode_klippy_rejects(klipper_build, klippy, runner, tmp_path, capsys):
    g = _run(tmp_path, START + "G1 X110 F6000\nG1 X500\nG1 X100\n")  # position_max: 200
    line = _error(capsys)
    assert f"{g}: klippy rejected the job: Move out of range: 500.000 100.000 10.000" in line


@slow
def test_a_command_klippy_does_not_know_names_its_line(
    klipper_build, klippy, runner, tmp_path, capsys
):
    g = _run(tmp_path, START + "G1 X110 F6000\nFOO X1\n")
    line = _error(capsys)
    assert f'{g}:3: klippy does not know the command (Unknown command:"FOO"' in line


@slow
def test_a_config_klippy_refuses(klipper_build, klippy, runner, tmp_path, capsys):
    cfg = tmp_path / "printer.cfg"
    cfg.write_text(CONFIG.read_text().replace("rotation_distance: 8\n", ""))
    _run(tmp_path, START, config=cfg)
    line = _error(capsys)
    assert f"{cfg}: klippy refused the config" in line and "rotation_distance" in line


#: An ATmega644P program that has Klipper's free-list symbol but never answers.
SILENT = "void *move_free_list;\nint main(void) { for (;;) {} }\n"


@slow
def test_a_build_that_never_answers(klipper_build, klippy, runner, tmp_path, capsys):
    elf = build_avr(tmp_path, "silent", SILENT, mcu="atmega644p")
    _, dictionary = klipper_build
    job = START + "G1 X110 F6000\n"
    _run(tmp_path, job, "--elf", str(elf), "--dict", str(dictionary), "--max-time", "2s")
    assert "never answered the first message block" in _error(capsys)


@slow
def test_a_job_longer_than_the_simulated_time_limit(
    klipper_build, klippy, runner, tmp_path, capsys
):
    _run(tmp_path, ZIGZAG, "--max-time", "1s")
    assert "did not finish within the simulated time limit (1.000000 s)" in _error(capsys)


@slow
def test_klippy_over_the_wall_time(klipper_build, klippy, runner, tmp_path, capsys):
    _run(tmp_path, ZIGZAG, "--timeout", "0.2s")
    assert "klippy's batch run took over 0.2 s of wall time" in _error(capsys)


@slow
def test_the_simulation_over_the_wall_time(klipper_build, klippy, runner, tmp_path):
    from wavecheck.mcu import klipper
    from wavecheck.mcu.klipper_msg import Dictionary

    elf, dict_path = klipper_build
    dictionary = Dictionary.load(dict_path)
    sent = klipper.job(
        klipper.batch(klippy, CONFIG, ZIGZAG, dict_path, decoder=dictionary), dictionary, "zigzag"
    )
    vcd = tmp_path / "slow.vcd"
    signals = klipper.pins(klipper.steppers(CONFIG))
    with pytest.raises(ConfigError, match="ran over 0.2 s of wall time"):
        klipper.run(runner, elf, dictionary, sent, str(vcd), signals, (60, 0.05, 0.2), print)
    assert not vcd.exists()


@slow
def test_fed_all_at_once_the_mcu_overflows_before_its_first_step(
    klipper_build, klippy, runner, tmp_path
):
    """Without pacing (klippy's batch mode assumes 500 slots, the 644P has fewer) the MCU shuts
    down with "Move queue overflow" (src/basecmd.c:88-90) and makes no step."""
    from wavecheck.mcu import klipper
    from wavecheck.mcu.klipper_msg import Dictionary

    elf, dict_path = klipper_build
    dictionary = Dictionary.load(dict_path)
    sent = klipper.job(
        klipper.batch(klippy, CONFIG, ZIGZAG, dict_path, decoder=dictionary), dictionary, "zigzag"
    )
    vcd = tmp_path / "unpaced.vcd"
    signals = klipper.pins(klipper.steppers(CONFIG))
    done = klipper.run(
        runner,
        elf,
        dictionary,
        sent,
        str(vcd),
        signals,
        (60, 0.05, 600),
        lambda r: None,
        paced=False,
    )
    with pytest.raises(ConfigError, match="shut down at 0.1[0-9]+ s: 'Move queue overflow'"):
        klipper.outcome(done, dictionary)
    changes, _ = vcd_changes(vcd)
    assert rising(changes["X_STEP"]) == []
    assert sum(sent.needs) > 500  # the job's slots: more than either figure


@slow
def test_a_job_without_a_step(klipper_build, klippy, runner, tmp_path, capsys):
    g = _run(tmp_path, START + "G1 X100 F6000\n")  # where it already is
    assert f"{g} (klippy's batch output): klippy commands no step" in _error(capsys)
