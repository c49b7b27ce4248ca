"""Motors, limits and repeats as each firmware applies them, and refusals with the true reason
(issue 32, classes 3 and 6). Each test names the firmware code that decides it."""

from __future__ import annotations

import json
from fractions import Fraction as F
from pathlib import Path

import pytest

from tests.wavecheck.firmware.fixapply import apply
from tools.firmware_corpus import CORPUS
from wavecheck.cli import main
from wavecheck.drives.library import load_drive
from wavecheck.drives.overrides import tune_drive
from wavecheck.errors import ConfigError
from wavecheck.firmware import read_firmware
from wavecheck.firmware.evaluate import evaluate_config

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


# -- grbl ---------------------------------------------------------------------------------------
GRBL = CORPUS / "grbl/siredmar+grbl_settings/grbl_settings.txt"


def test_grbl_slow_axis_steps_on_the_fast_axis_ticks(tmp_path: Path) -> None:
    """grbl 1.1h stepper.c:413-440: every step lands on a tick of the dominant axis; a slow axis
    steps floor(dominant / its rate) ticks apart, which tends to one tick of a dominant just under
    twice its rate. X 40 kHz, Z 400 x 300 mm/min = 2 kHz: Z's steps are >= 1 / 4 kHz apart (the
    reader said 1 / 2 kHz, less the pulse)."""
    (tmp_path / "d.txt").write_text("$0=10\n$100=80\n$101=80\n$102=400\n$110=30000\n"
                                    "$111=30000\n$112=300\n")  # fmt: skip
    cfg = read_firmware(tmp_path / "d.txt")
    pulse = F(10_000) - F(1125, 2)
    assert cfg.axis("Z").idle.value == F(250_000) - pulse
    assert cfg.axis("X").idle.value == F(25_000) - pulse  # the fastest axis: one of its ticks


@pytest.mark.parametrize(
    ("path", "hold"),
    [
        (GRBL, 46875),  # every axis 21333 Hz: one tick, 46.875 us
        (CORPUS / "grbl/bullestock+krydsogtrolle/grbl-settings.txt", 62500),  # 2 kHz: AMASS tick
    ],
)
def test_grbl_dir_hold_is_one_interrupt_tick(path: Path, hold: int) -> None:
    """The new block's DIR is written at the tick after its last step (stepper.c:323-324,
    358-375): one tick, at least min(1 / the fastest axis's rate, 62.5 us of AMASS: 50,
    1021-1026), whatever $0 is (the reader said the pulse)."""
    assert read_firmware(path).axis("X").dir_hold.value == hold


def test_grbl_dir_hold_fix_lowers_the_rates(tmp_path: Path) -> None:
    cfg = read_firmware(GRBL)
    x = cfg.axis("X")
    assert "tops out" in cfg.fix(x, "hold", F(70_000))
    fix = cfg.fix(x, "hold", F(50_000))
    copy = tmp_path / "grbl_settings.txt"
    copy.write_bytes(GRBL.read_bytes())
    apply("grbl", copy, fix, cfg)
    assert read_firmware(copy).axis("X").dir_hold.value >= 50_000


def test_fluidnc_slow_axis_steps_on_the_fast_axis_ticks() -> None:
    """FluidNC's Stepper.cpp keeps grbl's Bresenham: 4x_2209_xyyz_pwm z 395.8 x 1000 / 60 Hz
    (lines 122-123) beside x 28590 Hz: z steps >= 1 / (2 x 6596.7 Hz) apart, less the 4 us pulse."""
    cfg = read_firmware(CORPUS / "fluidnc/contributed/4x_2209/4x_2209_xyyz_pwm.yaml")
    assert cfg.axis("z").idle.value == F(10**9) / (2 * F(19790, 3)) - 4000


# -- Klipper ------------------------------------------------------------------------------------


@pytest.mark.parametrize("name", ["sample-glyphs.cfg", "sample-pwm-tool.cfg"])
def test_klipper_add_on_files_are_refused_for_the_true_reason(name: str) -> None:
    """[display_glyph …] and [pwm_tool …] are Klipper module sections: such a file is Klipper's
    and has no stepper (was 'not a configuration wavecheck recognises')."""
    with pytest.raises(ConfigError, match="no section with a step_pin"):
        read_firmware(CORPUS / "klipper" / name)


@pytest.mark.parametrize(
    "name", ["sample-bigtreetech-ebb-canbus-v1.2.cfg", "sample-huvud-v0.61.cfg"]
)
def test_klipper_toolhead_sample_header_names_its_mcu(name: str) -> None:
    """A toolhead board's sample has no [mcu] section: its header names the board's chip
    (STM32G0B1, STM32F103), so the TMC2209's 100 ns both-edge stepping is decided (klippy/
    stepper.py:88-110; src/stepper.c:233-235 edge path). It was 'AVR possible', both edges off."""
    e = read_firmware(CORPUS / "klipper" / name).axis("extruder")
    assert e.both_edges and "named in the file" in e.info["mcu"]


@pytest.mark.parametrize(
    ("name", "axis", "hz"),
    [
        ("example-hybrid-corexy.cfg", "stepper_y", 300 * 80),
        ("example-hybrid-corexz.cfg", "stepper_z", 25 * 400),
    ],
)
def test_klipper_hybrid_kinematics_cartesian_rails_have_a_rate(
    name: str, axis: str, hz: int
) -> None:
    """hybrid_corexy.py:21-22 and hybrid_corexz.py:21-22 set up y and z with
    cartesian_stepper_alloc: each moves one axis alone, bounded by max_velocity (max_z_velocity
    for z) x steps/mm (was unknown)."""
    assert read_firmware(CORPUS / "klipper" / name).axis(axis).max_rate.value == hz


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


def test_smoothie_max_rate_over_the_base_frequency_is_floored() -> None:
    """Robot::check_max_actuator_speeds: where steps/mm x max_rate passes the base frequency, max_rate
    becomes floorf(base / steps/mm) mm/s. Smoothieboard beta 333.3333 steps/mm (line 17) x 30000
    mm/min (45): floor(300.00003) = 300 mm/s, 99999.99 Hz; rotary.delta 338.5693208 (53):
    295 mm/s, 99877.95 Hz (both read as the 100 kHz base before)."""
    board = read_firmware(CORPUS / "smoothie/Smoothieboard/config")
    assert board.axis("beta").max_rate.value == F("99999.99")
    delta = read_firmware(CORPUS / "smoothie/rotary.delta/config")
    assert delta.axis("alpha").max_rate.value == 295 * F("338.5693208")


def test_smoothie_steps_per_mm_defaults(tmp_path: Path) -> None:
    """Robot::load_config: steps_per_mm by_default(a == 2 ? 2560 : 80), max_rate 30000 mm/min."""
    (tmp_path / "config").write_text(
        "alpha_step_pin 2.0\nalpha_dir_pin 0.5\ngamma_step_pin 2.2\ngamma_dir_pin 0.20\n"
        "gamma_max_rate 300\n"
    )
    cfg = read_firmware(tmp_path / "config")
    assert cfg.axis("alpha").max_rate.value == 80 * 500
    assert cfg.axis("gamma").max_rate.value == 2560 * 5


def test_smoothie_low_time_and_dir_setup_are_not_enforced(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """StepTicker::step_tick starts the unstep timer after the tick's steps, so the real pulse is
    longer than the setting and the low time shorter than tick - setting; start_next_block writes
    DIR about a tick ahead with no delay of its own. Against the DM542 (5 us setup, 2.5 us low)
    these were PASSes; now indeterminate, never a PASS."""
    assert main(["config", str(CORPUS / "smoothie/Smoothieboard/config"), "--drive",
                 "leadshine-dm542", "--format", "json"]) in (0, 1, 3)  # fmt: skip
    doc = json.loads(capsys.readouterr().out)
    rows = {(p["axis"], r["rule"]): r for p in doc["pairs"] for r in p["rules"]}
    for rule in ("dir_setup", "step_low"):
        row = rows[("alpha", rule)]
        assert row["verdict"] == "indeterminate" and "not enforced" in row["note"], row


@pytest.mark.parametrize(
    ("extra", "axes"),
    [
        ("delta_step_pin 2.3\ndelta_dir_pin 0.22\n", ("alpha", "beta", "gamma", "delta")),
        ("epsilon_step_pin 2.8\nepsilon_dir_pin 2.13\n", ("alpha", "beta", "gamma")),
        ("delta_step_pin 2.3\n", ("alpha", "beta", "gamma")),
    ],
)
def test_smoothie_motors_after_gamma_are_contiguous(
    tmp_path: Path, extra: str, axes: tuple[str, ...]
) -> None:
    """Robot::load_config: a motor needs its step and dir pins, and the motors after gamma are
    taken in order, the first one missing ending them (an epsilon without a delta is no motor)."""
    (tmp_path / "config").write_text(
        "".join(
            f"{m}_steps_per_mm 80\n{m}_step_pin 2.{i}\n{m}_dir_pin 0.{i}\n"
            for i, m in enumerate(("alpha", "beta", "gamma"))
        )
        + extra  # fmt: skip
    )
    assert read_firmware(tmp_path / "config").axis_names == axes


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


def test_fluidnc_i2s_dir_setup_is_one_frame_of_the_current_engine() -> None:
    """Current FluidNC runs I2S_STATIC and I2S_STREAM as one I2S engine (Stepping.cpp
    find_engine matches the name's start). Its finish_dir pushes the DIR change as one FIFO sample
    and then spins dir_delay_us; the step's samples follow that sample in the FIFO, so DIR leads
    the step by one I2S frame (i2so min_pulse_us, default 2 us), whatever dir_delay_us says.
    6_pack_TMC2130_XYZ.yaml lines 4-7 (I2S_STREAM, dir_delay_us 1): 2 us (round 4 read 1 us, the
    spin, as if the FIFO were always empty)."""
    x = read_firmware(FLUIDNC).axis("x")
    assert x.dir_setup.value == 2000 and "finish_dir" in x.dir_setup.note
    assert x.dir_setup.status == "derived"


@pytest.mark.parametrize(
    ("i2so", "pulse_us", "pulse_ns", "setup_ns"),
    [
        ("", 4, 4000, 2000),  # 2 frames of the default 2 us
        ("", 1, 2000, 2000),  # pulse_us below one frame: one frame (init_engine)
        ("  min_pulse_us: 4\n", 5, 8000, 4000),  # ceil(5 / 4) = 2 frames of 4 us
        ("  min_pulse_us: 1\n", 30, 20000, 1000),  # capped at I2S_MAX_USEC_PER_PULSE 20
    ],
)
def test_fluidnc_i2s_pulse_is_whole_frames(
    tmp_path: Path, i2so: str, pulse_us: int, pulse_ns: int, setup_ns: int
) -> None:
    """i2s_engine.cpp init_engine: pulse_us clamped to [frame, 20] and made ceil(pulse_us / frame)
    FIFO frames, hardware-timed; the frame is i2so min_pulse_us (1, 2 or 4)."""
    text = FLUIDNC.read_text().replace("  pulse_us: 4\n", f"  pulse_us: {pulse_us}\n", 1)
    text = text.replace("i2so:\n", "i2so:\n" + i2so, 1)
    (tmp_path / "m.yaml").write_text(text)
    x = read_firmware(tmp_path / "m.yaml").axis("x")
    assert (x.pulse.value, x.dir_setup.value) == (pulse_ns, setup_ns)


def test_fluidnc_i2s_frame_fluidnc_does_not_take_is_refused(tmp_path: Path) -> None:
    (tmp_path / "m.yaml").write_text(
        FLUIDNC.read_text().replace("i2so:\n", "i2so:\n  min_pulse_us: 3\n")
    )
    with pytest.raises(ConfigError, match=r"m.yaml:\d+: i2so min_pulse_us 3 .*1, 2 or 4"):
        read_firmware(tmp_path / "m.yaml")


def test_fluidnc_i2s_setup_fix_is_the_frame(tmp_path: Path) -> None:
    """dir_delay_us cannot lengthen the I2S DIR setup; the fix is the frame (min_pulse_us)."""
    x = read_firmware(FLUIDNC).axis("x")
    cfg = read_firmware(FLUIDNC)
    assert (
        cfg.fix(x, "setup", F(3000)) == "set `i2so: min_pulse_us: 4` (the I2S frame: 1, 2 or 4 us)"
    )
    assert "tops out" in cfg.fix(x, "setup", F(5000))


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


@pytest.mark.parametrize(
    ("rates", "limit", "verdict"),
    [
        # X 80 x 30000 / 60 = 40 kHz: the tick is 25 us, the pulse >= $0 - 562.5 ns = 9.4375 us,
        # so the hold from the pulse's end is at most 15.5625 us at that rate; jitter may take
        # any part of it (stepper.c:319-336 and the interrupts that delay it): never a PASS
        ("$110=30000\n$111=30000\n", "dir_hold=5us", "indeterminate"),
        # a drive asking more than the tick less the pulse fails even without any jitter
        ("$110=30000\n$111=30000\n", "dir_hold=20us", "fail"),
    ],
)
def test_grbl_trailing_dir_hold_is_the_tick_less_the_pulse(
    tmp_path: Path, rates: str, limit: str, verdict: str
) -> None:
    """With STEP inverted ($2) a drive that counts its rising edge counts the end of grbl's
    pulse; the next block's DIR is written one interrupt tick after the pulse started, so the
    hold from the pulse's end is the tick less the pulse, not 0 (the reader said 0, a certain
    FAIL against any drive stating a hold: held-out grbl dumps with $2 set)."""
    (tmp_path / "d.txt").write_text(f"$0=10\n$2=3\n$100=80\n$101=80\n{rates}")
    cfg = read_firmware(tmp_path / "d.txt")
    x = cfg.axis("X")
    assert x.pulse_level == 0 and x.dir_hold_trailing is not None
    assert x.dir_hold_trailing.value == F(25_000) - (F(10_000) - F(1125, 2))
    drive = tune_drive(load_drive("drv8825"), [limit])
    row = next(r for r in evaluate_config(cfg, [(x, drive)]).pairs[0].rows if r.rule == "dir_hold")
    assert row.verdict == verdict, row.note
