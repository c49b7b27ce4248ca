"""Motors, limits and repeats as each firmware applies them, and refusals with the true reason
(issue 32, classes 3 and 6). Each test names the firmware code that decides it."""

from __future__ import annotations

from fractions import Fraction as F
from pathlib import Path

import pytest

from tools.firmware_corpus import CORPUS
from wavecheck.errors import ConfigError
from wavecheck.firmware import read_firmware

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
