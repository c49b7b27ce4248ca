"""Motors, limits and repeats as each firmware applies them, and refusals with the true reason
(issue 32, classes 3 and 6). Each test names the firmware code that decides it."""

from __future__ import annotations

import json
import shutil
from fractions import Fraction as F
from pathlib import Path

import pytest

from tools.firmware_corpus import CORPUS
from wavecheck.cli import main
from wavecheck.errors import ConfigError
from wavecheck.firmware import read_firmware
from wavecheck.firmware.guarantee import FirmwareConfig

pytestmark = pytest.mark.skipif(not CORPUS.is_dir(), reason="shared firmware corpus not present")
FLUIDNC = CORPUS / "fluidnc/official/6_pack_TMC2130_XYZ.yaml"
LCNC = CORPUS / "linuxcnc/configs"

# -- FluidNC ------------------------------------------------------------------------------------


def test_fluidnc_repeated_key_keeps_the_last(tmp_path: Path) -> None:
    """FluidNC's parser assigns each `key: value` as it reads it: `pulse_us: 10` then
    `pulse_us: 2` is 2 us (was a PASS at 10 us)."""
    text = FLUIDNC.read_text().replace("  pulse_us: 4\n", "  pulse_us: 10\n  pulse_us: 2\n", 1)
    (tmp_path / "m.yaml").write_text(text)
    x = read_firmware(tmp_path / "m.yaml").axis("x")
    assert x.pulse.value == 2000  # I2S_STREAM frames of 2 us: 2 us is one frame


def test_fluidnc_repeated_section_keeps_the_first(tmp_path: Path) -> None:
    text = FLUIDNC.read_text() + "  x:\n    steps_per_mm: 1\n    max_rate_mm_per_min: 1\n"
    (tmp_path / "m.yaml").write_text(text)
    cfg = read_firmware(tmp_path / "m.yaml")
    assert cfg.axis_names == ("x", "y", "z") and cfg.axis("x").max_rate.value == F(200000, 3)


def test_fluidnc_no_pin_motor_is_no_axis(tmp_path: Path) -> None:
    """`step_pin: NO_PIN` is FluidNC's unconnected pin: that motor makes no steps."""
    text = FLUIDNC.read_text().replace("step_pin: I2SO.5", "step_pin: NO_PIN")
    (tmp_path / "m.yaml").write_text(text)
    assert read_firmware(tmp_path / "m.yaml").axis_names == ("x", "z")


def test_fluidnc_without_step_pins_says_so(tmp_path: Path) -> None:
    """A FluidNC file with no motor step_pin was 'not a configuration wavecheck recognises'."""
    (tmp_path / "m.yaml").write_text(
        "name: io board\nboard: 6 Pack\nstepping:\n  engine: RMT\n  pulse_us: 4\n"
        "coolant:\n  flood_pin: gpio.2\n"
    )
    with pytest.raises(ConfigError, match="no axis has a motor with a step_pin"):
        read_firmware(tmp_path / "m.yaml")


# -- Smoothieware ---------------------------------------------------------------------------------


def test_smoothie_delta_actuators_are_clamped_by_their_max_rate() -> None:
    """Robot.cpp append_milestone scales the move so that no actuator passes its max_rate, on
    any arm solution: AzteegX5Mini.delta line 17 100 steps/mm x line 36 30000 mm/min = 50 kHz
    (was the 100 kHz base frequency)."""
    cfg = read_firmware(CORPUS / "smoothie/AzteegX5Mini.delta/Version3/config")
    assert cfg.axis("alpha").max_rate.value == 50000


def test_smoothie_extruder_modules_are_motors() -> None:
    """Extruder.cpp config_load makes a StepperMotor of each enabled extruder.NAME module:
    Smoothieboard/config 55-62 hotend, 140 steps/mm x max_speed 50 mm/s."""
    cfg = read_firmware(CORPUS / "smoothie/Smoothieboard/config")
    e = cfg.axis("extruder.hotend")
    assert e.max_rate.value == 7000 and cfg.axis("e") is e


def test_smoothie_delta_epsilon_only_file_is_read(tmp_path: Path) -> None:
    (tmp_path / "config").write_text(
        "delta_steps_per_mm 100\ndelta_step_pin 2.3\ndelta_dir_pin 0.22\n"
        "epsilon_steps_per_mm 100\nepsilon_step_pin 2.8\nepsilon_dir_pin 2.13\n"
    )
    assert read_firmware(tmp_path / "config").axis_names == ("delta", "epsilon")


def test_smoothie_repeated_key_keeps_the_last(tmp_path: Path) -> None:
    """ConfigCache::replace_or_push_back: a key read again replaces the earlier value."""
    (tmp_path / "config").write_text(
        "alpha_steps_per_mm 80\nalpha_step_pin 2.0\nmicroseconds_per_step_pulse 5\n"
        "microseconds_per_step_pulse 1\n"
    )
    assert read_firmware(tmp_path / "config").axis("alpha").pulse.value == 1000


# -- LinuxCNC -------------------------------------------------------------------------------------


def test_software_stepgen_maxvel_clamps_the_rate() -> None:
    """stepgen.c clamps the velocity to maxvel: Sherline4Axis_inch.ini [JOINT_0] STEPGEN_MAXVEL
    .4 (line 150) x INPUT_SCALE 16000 (153) = 6400 steps/s, under the 10 kHz of
    (steplen + stepspace) x BASE_PERIOD."""
    cfg = read_firmware(LCNC / "by_machine/sherline/Sherline4Axis/Sherline4Axis_inch.ini")
    assert cfg.axis("stepgen.0").max_rate.value == 6400


def test_a_hal_file_alone_is_read_with_the_ini_naming_it(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """Gecko_540B3.hal refers to [EMCMOT] values: it was refused with 'give --ini FILE', an option
    `config` does not have. The INI beside it whose HALFILE names it is read."""
    hal = LCNC / "by_interface/parport/gecko/Gecko_540B3/Gecko_540B3.hal"
    code = main(["config", str(hal), "--drive", "gecko-g540", "--format", "json"])
    doc = json.loads(capsys.readouterr().out)
    assert code in (0, 1, 3)
    assert any(n.startswith("a HAL file given alone: read with") for n in doc["notes"])


def test_a_hal_file_named_by_several_inis_asks_for_one(tmp_path: Path) -> None:
    src = LCNC / "by_machine/sherline/Sherline4Axis"
    with pytest.raises(ConfigError, match="2 INIs beside it") as err:
        read_firmware(src / "stepper_xyza.hal")
    assert "--ini" not in str(err.value) and "Sherline4Axis_mm.ini" in str(err.value)


SHERLINE = LCNC / "by_machine/sherline/Sherline4Axis"


def _figures(doc: dict[str, object]) -> object:
    return doc["axes"], doc["pairs"], doc["exit_code"]


@pytest.mark.parametrize("order", ["hal ini", "ini hal", "hal --drive ini"])
def test_a_hal_file_with_its_ini_as_a_second_file(
    capsys: pytest.CaptureFixture[str], order: str
) -> None:
    """stepper_xyza.hal is named by two INIs beside it: `config` refused it and took no second
    file. Given with Sherline4Axis_inch.ini (either order, also after the options: `config HAL
    --drive X INI` was refused as an unrecognised argument), it reads what the INI alone gives:
    the INI's [HAL] HALFILE runs it."""
    hal, ini = str(SHERLINE / "stepper_xyza.hal"), str(SHERLINE / "Sherline4Axis_inch.ini")
    drive = ["--drive", "gecko-g540", "--format", "json"]
    argv = {"hal ini": [hal, ini, *drive], "ini hal": [ini, hal, *drive],
            "hal --drive ini": [hal, *drive, ini]}[order]  # fmt: skip
    code = main(["config", *argv])
    doc = json.loads(capsys.readouterr().out)
    assert code in (0, 1, 3)
    assert any("read with the INI given" in n for n in doc["notes"])
    main(["config", str(ini), "--drive", "gecko-g540", "--format", "json"])
    assert _figures(doc) == _figures(json.loads(capsys.readouterr().out))


def test_the_several_inis_refusal_advises_a_command_that_works(
    capsys: pytest.CaptureFixture[str],
) -> None:
    with pytest.raises(ConfigError) as err:
        read_firmware(SHERLINE / "stepper_xyza.hal")
    advised = str(err.value).split("(wavecheck config ", 1)[1].split(" …)")[0].split()
    code = main(["config", *(str(SHERLINE / f) for f in advised), "--drive", "gecko-g540"])
    assert code in (0, 1, 3), capsys.readouterr().err


def test_an_ini_that_does_not_run_the_hal_file_only_gives_its_values(tmp_path: Path) -> None:
    """As `halcmd -i INI -f HAL` (LinuxCNC/linuxcnc:scripts/linuxcnc.in @ 013b2f9, step 4.3.6
    runs each HALFILE that way): the HAL file alone, its [EMCMOT]BASE_PERIOD references
    resolved from the INI given; the INI's own HALFILEs (which name another file) not read."""
    src = LCNC / "by_interface/parport/gecko/Gecko_540B3"
    shutil.copy(src / "Gecko_540B3.hal", tmp_path)
    cfg = read_firmware(tmp_path / "Gecko_540B3.hal", ini=src / "Gecko_540B3.ini")
    assert cfg.files == (str(tmp_path / "Gecko_540B3.hal"), str(src / "Gecko_540B3.ini"))
    assert any("do not name it" in n for n in cfg.notes) and cfg.axes
    whole = read_firmware(src / "Gecko_540B3.ini")

    def values(c: FirmwareConfig) -> list[tuple[object, ...]]:
        return [(a.axis, a.pulse.value, a.idle.value, a.dir_setup.value, a.max_rate.value)
                for a in c.axes]  # fmt: skip

    assert values(cfg) == values(whole)[: len(cfg.axes)]


@pytest.mark.parametrize(
    ("first", "second", "message"),
    [
        (SHERLINE / "stepper_xyza.hal", SHERLINE / "standard_pinout.hal", "two HAL files"),
        (SHERLINE / "Sherline4Axis_mm.ini", SHERLINE / "Sherline4Axis_inch.ini", "two INIs"),
        (FLUIDNC, SHERLINE / "Sherline4Axis_mm.ini", "read only with a LinuxCNC HAL file"),
    ],
)
def test_a_second_file_that_is_not_the_hal_files_ini_is_refused(
    capsys: pytest.CaptureFixture[str], first: Path, second: Path, message: str
) -> None:
    code = main(["config", str(first), str(second), "--drive", "gecko-g540"])
    err = capsys.readouterr().err
    assert code == 2 and message in err and len(err.strip().splitlines()) == 1


def test_a_hal_file_without_its_ini_never_advises_a_missing_option(tmp_path: Path) -> None:
    shutil.copy(LCNC / "by_interface/parport/gecko/Gecko_540B3/Gecko_540B3.hal", tmp_path)
    with pytest.raises(ConfigError) as err:
        read_firmware(tmp_path / "Gecko_540B3.hal")
    assert "--ini" not in str(err.value) and "give the INI" in str(err.value)


# -- Marlin ---------------------------------------------------------------------------------------


def test_marlin_200_has_trinamic_decides_square_wave_stepping(tmp_path: Path) -> None:
    """Marlin 2.0.0 names the condition HAS_TRINAMIC (its Configuration_adv.h wraps the TMC
    options, SQUARE_WAVE_STEPPING among them, in `#if HAS_TRINAMIC`, e.g. FYSETC/Cheetah line
    1877): with TMC2209 drivers it is true, so both edges step."""
    (tmp_path / "Configuration.h").write_text(
        "#define CONFIGURATION_H_VERSION 020000\n#define MOTHERBOARD BOARD_RAMPS_14_EFB\n"
        "#define X_DRIVER_TYPE TMC2209\n#define Y_DRIVER_TYPE TMC2209\n"
        "#define Z_DRIVER_TYPE TMC2209\n#define E0_DRIVER_TYPE TMC2209\n"
        "#define DEFAULT_AXIS_STEPS_PER_UNIT { 80, 80, 400, 93 }\n"
        "#define DEFAULT_MAX_FEEDRATE { 300, 300, 5, 25 }\n"
    )
    (tmp_path / "Configuration_adv.h").write_text(
        "#define CONFIGURATION_ADV_H_VERSION 020000\n#if HAS_TRINAMIC\n"
        "  #define SQUARE_WAVE_STEPPING\n#endif\n"
    )
    assert read_firmware(tmp_path / "Configuration.h").axis("X").both_edges


def test_fluidnc_i2s_dir_delay_follows_the_current_engine() -> None:
    """Current FluidNC runs I2S_STATIC and I2S_STREAM as one engine (Stepping.cpp's engine
    notes): DIR is shifted out at once and finish_dir spins delay_us(dir_delay_us) before the
    step. 6_pack_TMC2130_XYZ.yaml lines 4-7 (I2S_STREAM, dir_delay_us 1): 1 us (the older
    frame model said one 2 us frame)."""
    x = read_firmware(FLUIDNC).axis("x")
    assert x.dir_setup.value == 1000 and "finish_dir" in x.dir_setup.note


# -- RepRapFirmware ---------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("m584", "axes", "noted"),
    [
        ("", ("X", "Y", "Z", "E0"), True),
        ("M584 X0 Y1 Z2 E3:4\n", ("X", "Y", "Z", "E0", "E1"), False),
    ],
)
def test_rrf_default_extruders_are_not_decided_by_the_file(
    tmp_path: Path, m584: str, axes: tuple[str, ...], noted: bool
) -> None:
    """Without M584 E, RRF's extruder count is its default: 3.x GCodes::Init sets numExtruders =
    NumDefaultExtruders (Duet3D/RepRapFirmware:src/GCodes/GCodes.cpp @ fa22ccf), per board 0 to
    3; 2.0x the smart drivers minus 3. E1's values were dropped without a word; the report now
    says E0 on driver 3 is an assumption the file does not decide."""
    cfg_g = tmp_path / "config.g"
    cfg_g.write_text(f"{m584}M92 X80 Y80 Z400 E420:430\nM203 X6000 Y6000 Z180 E1200:1200\n")
    cfg = read_firmware(cfg_g)
    assert cfg.axis_names == axes
    assert any(n.startswith("no M584 E: E0 on driver 3 assumed") for n in cfg.notes) == noted
