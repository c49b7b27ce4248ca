"""Constructs seen in real configurations outside the development corpus (the held-out probe,
``tools/heldout_probe.py``), each reduced to a few lines of our own. Each test names the public
file where the construct was seen and the firmware fact it checks."""

from __future__ import annotations

from pathlib import Path

import pytest

from wavecheck.drives.library import load_drive
from wavecheck.errors import ConfigError
from wavecheck.firmware import read_firmware
from wavecheck.firmware.evaluate import evaluate_config


def test_klipper_printer_cfg_of_missing_includes_says_so(tmp_path: Path) -> None:
    """Seen in 3lementalS/MK3SKlipperConfigs printer.cfg: every stepper is in
    ``[include Configuration/002_Motion/*.cfg]``; given alone, the file was refused as "a Klipper
    file without steppers". Klipper reads includes beside the file and stops on a missing one that is no glob
    (../shared/firmware-src/klipper/klippy/configfile.py:181-189), so the true reason is the
    includes that are not there."""
    cfg = tmp_path / "printer.cfg"
    cfg.write_text("[include mainsail.cfg]\n[include motion/*.cfg]\n\n[printer]\nkinematics: cartesian\n"
                   "max_velocity: 300\nmax_accel: 3000\n")  # fmt: skip
    with pytest.raises(ConfigError) as err:
        read_firmware(cfg)
    text = str(err.value)
    assert "2 [include] match no file" in text and "mainsail.cfg" in text
    assert "without steppers" not in text


def test_klipper_file_without_steppers_or_includes_is_still_refused_as_such(
    tmp_path: Path,
) -> None:
    """The other side: no includes at all, no steppers (a partial sample file)."""
    cfg = tmp_path / "sample.cfg"
    cfg.write_text("[mcu]\nserial: /dev/ttyACM0\n\n[printer]\nkinematics: none\nmax_velocity: 1\n"
                   "max_accel: 1\n\n[fan]\npin: PA8\n")  # fmt: skip
    with pytest.raises(ConfigError, match="without steppers"):
        read_firmware(cfg)


def test_rrf_one_e_value_is_every_extruders(tmp_path: Path) -> None:
    """Seen in uwo-fast/hangprinter-v4 config.g (``M584 E121.0:0:1:2:3:4:5`` then ``M92 E391.50``
    and ``M203 ... E3600``), and common wherever two extruders share one ``M92 E``: only E0 got
    the value and E1.. were dropped as unconfigured. RepRapFirmware reads E with
    ``gb.GetFloatArray(eVals, eCount, true)``; with one value given and doPad true it fills the
    rest of the array with it (GCodeBuffer.cpp GetFloatArray: "If there is one entry and doPad is
    true, fill the rest of the array with the first entry"), for M92 and M203 alike."""
    cfg = tmp_path / "config.g"
    cfg.write_text("M584 X0 Y1 Z2 E3:4\nM92 X80 Y80 Z400 E420\nM203 X6000 Y6000 Z600 E1200\n")
    got = read_firmware(cfg)
    assert got.axis_names == ("X", "Y", "Z", "E0", "E1")
    for e in ("E0", "E1"):
        assert got.axis(e).max_rate.value == 420 * 1200 / 60  # steps/mm x mm/min / 60


def test_rrf_axis_without_figures_is_named_not_dropped(tmp_path: Path) -> None:
    """Seen in uwo-fast/hangprinter-v4 config.g: ``M584 X40.0 Y41.0 Z42.0 U43.0`` makes four
    motor axes, and U (the D anchor) has no M92, M203 or M569 T. The reader left it out without a
    word, so the report read as if the machine had three; it is now named as not checked."""
    cfg = tmp_path / "config.g"
    cfg.write_text("M584 X0 Y1 Z2 U3 E4\nM92 X80 Y80 Z400 E420\nM203 X6000 Y6000 Z600 E1200\n")
    got = read_firmware(cfg)
    assert "U" not in got.axis_names
    assert any(n.startswith("axis U (driver 0.3)") and "not checked" in n for n in got.notes)
    # and the verdict line says so: a verdict of X, Y, Z and E0 is not the whole machine's
    drive = load_drive("gecko-g202")
    line = evaluate_config(got, [(g, drive) for g in got.axes]).verdict_line
    assert " (axis U not checked: no M92, M203 or M569 T in the file; " in line


def test_rrf_e_list_is_read_value_by_value(tmp_path: Path) -> None:
    """The other side: a list gives each extruder its own value, no padding."""
    cfg = tmp_path / "config.g"
    cfg.write_text(
        "M584 X0 Y1 Z2 E3:4\nM92 X80 Y80 Z400 E420:830\nM203 X6000 Y6000 Z600 E1200:600\n"
    )
    got = read_firmware(cfg)
    assert got.axis("E0").max_rate.value == 420 * 1200 / 60
    assert got.axis("E1").max_rate.value == 830 * 600 / 60


_SMOOTHIE_OLD_EXTRUDER = """alpha_steps_per_mm 100
alpha_step_pin 2.0
alpha_dir_pin 0.5
alpha_max_rate 30000.0
extruder_module_enable {enable}
extruder_steps_per_mm 140
extruder_max_speed 100   # mm/s
extruder_step_pin 2.3
extruder_dir_pin 0.22!
"""


def test_smoothie_old_single_extruder_syntax_is_a_motor(tmp_path: Path) -> None:
    """Seen in Smoothieware/Smoothieware ConfigSamples/Smoothieboard.Kossel/config (and other
    pre-2014 samples): ``extruder_module_enable true`` with ``extruder_step_pin`` etc. The
    extruder motor was missing from the axes. ExtruderMaker::on_module_loaded makes an Extruder
    with single_config when ``extruder_module_enable`` is true, and Extruder::on_config_reload
    reads ``extruder_steps_per_mm`` (default 1), ``extruder_step_pin``/``extruder_dir_pin`` and
    ``set_max_rate(extruder_max_speed)`` (mm/s, default 1000) for it (src/modules/tools/extruder/
    ExtruderMaker.cpp, Extruder.cpp)."""
    cfg = tmp_path / "config"
    cfg.write_text(_SMOOTHIE_OLD_EXTRUDER.format(enable="true"))
    got = read_firmware(cfg)
    assert got.axis_names == ("alpha", "extruder")
    e = got.axis("e")
    assert e.axis == "extruder" and e.dir_inverted
    assert e.max_rate.value == 140 * 100  # steps/mm x mm/s


def test_smoothie_old_extruder_disabled_is_no_motor(tmp_path: Path) -> None:
    """The other side (ConfigSamples/NucleoF411RE/config): ``extruder_module_enable false``."""
    cfg = tmp_path / "config"
    cfg.write_text(_SMOOTHIE_OLD_EXTRUDER.format(enable="false"))
    assert read_firmware(cfg).axis_names == ("alpha",)


_SMOOTHIE_PINS = """alpha_step_pin 2.0
alpha_dir_pin 0.5
beta_step_pin 2.1
beta_dir_pin 0.11
gamma_step_pin 2.2
gamma_dir_pin 0.20
delta_steps_per_mm 100
delta_step_pin 2.3
delta_dir_pin 0.22
epsilon_steps_per_mm 100
epsilon_step_pin {pin}
epsilon_dir_pin {pin}
zeta_steps_per_mm 100
zeta_step_pin 1.31
zeta_dir_pin 1.30
"""


@pytest.mark.parametrize(
    ("pin", "axes"),
    [
        ("xx", ("alpha", "beta", "gamma", "delta")),  # no build reads it: no pin
        ("0.32", ("alpha", "beta", "gamma", "delta")),  # index 32: no build reads it
        ("nc", ("alpha", "beta", "gamma", "delta")),
        ("2.8", ("alpha", "beta", "gamma", "delta", "epsilon", "zeta")),
        ("B.3", ("alpha", "beta", "gamma", "delta", "epsilon", "zeta")),  # an STM32 build's pin
        ("5.1", ("alpha", "beta", "gamma", "delta", "epsilon", "zeta")),  # STM32 builds' ports
    ],
)
def test_smoothie_pin_no_build_reads_is_no_pin(
    tmp_path: Path, pin: str, axes: tuple[str, ...]
) -> None:
    """Seen in Smoothieware/Smoothieware ConfigSamples/Snippets/six-axis.config: ``zeta_step_pin
    xx`` (a placeholder). ``Pin::from_string`` (src/libs/Pin.cpp @ 1fd8a13) reads a port and an
    index with ``strtol`` (port ≤ 4, index < 32) and marks anything else invalid ("from_string
    failed"); ``Robot::load_config`` takes the motors after gamma in order while both pins are
    ``connected()``, so a motor with such a pin ends them. It was read as a motor; only "nc"
    was. A pin that some build reads (STM32 builds take port letters) is kept."""
    cfg = tmp_path / "config"
    cfg.write_text(_SMOOTHIE_PINS.format(pin=pin))
    assert read_firmware(cfg).axis_names == axes


_FLUIDNC_AXIS = """axes:
  x:
    steps_per_mm: 100
    max_rate_mm_per_min: 600
    motor0:
      standard_stepper:
        step_pin: gpio.4
        direction_pin: gpio.5
"""


def test_fluidnc_flow_mapping_is_not_read(tmp_path: Path) -> None:
    """Seen in a fluidnc-bob rev C README's config (``stepping: { engine: RMT, pulse_us: 5,
    dir_delay_us: 5 }``, ``standard_stepper: { step_pin: gpio.4, ... }``): read as YAML the
    braces gave a 5 us pulse and DIR delay and PASSed. FluidNC's tokenizer takes a line's key
    and the rest of the line as its value (FluidNC/src/Configuration/Tokenizer.cpp) and a
    section reads only the more-indented lines below it (ParserHandler::enterSection), so the
    settings in braces are never read: the pulse is the 4 us default, the DIR delay 0."""
    cfg = tmp_path / "config.yaml"
    cfg.write_text("stepping: { engine: RMT, pulse_us: 5, dir_delay_us: 5 }\n" + _FLUIDNC_AXIS)
    got = read_firmware(cfg)
    x = got.axis("x")
    assert x.pulse.value == 4000 and x.pulse.where == "firmware default"
    assert any("flow mapping" in n and ":1:" in n for n in got.notes)


def test_fluidnc_motor_in_braces_is_no_step_generator(tmp_path: Path) -> None:
    """The same README's motors: ``standard_stepper: { step_pin: gpio.4, ... }`` sets no pin in
    FluidNC; with every motor so, the refusal says why."""
    cfg = tmp_path / "config.yaml"
    cfg.write_text(_FLUIDNC_AXIS.replace(
        "      standard_stepper:\n        step_pin: gpio.4\n        direction_pin: gpio.5\n",
        "      standard_stepper: { step_pin: gpio.4, direction_pin: gpio.5 }\n",
    ))  # fmt: skip
    with pytest.raises(ConfigError, match=r"flow mapping.*line 6"):
        read_firmware(cfg)


@pytest.mark.parametrize(("delay", "want"), [("0", None), ("3", 3000)])
def test_fluidnc_timed_engine_without_dir_delay_is_not_enforced(
    tmp_path: Path, delay: str, want: int | None
) -> None:
    """Seen in the FluidNC wiki's MKS DLC32 Max example (``engine: Timed``, ``dir_delay_us: 0``):
    the DIR setup was a '0 s?' figure and FAILed. FluidNC's timed engine writes DIR, spins
    ``delay_us(_dir_delay_us)`` in finish_dir and then writes STEP (FluidNC/esp32/
    timed_engine.c): at 0 nothing keeps a setup, so it is not enforced (issue 32, 1); a set
    delay is spun (interrupts only lengthen it)."""
    cfg = tmp_path / "config.yaml"
    cfg.write_text(f"stepping:\n  engine: Timed\n  pulse_us: 4\n  dir_delay_us: {delay}\n"
                   + _FLUIDNC_AXIS)  # fmt: skip
    setup = read_firmware(cfg).axis("x").dir_setup
    assert setup.value == want
    assert (setup.status == "not_enforced") == (want is None)


_HM2_INI = """[EMCMOT]
SERVO_PERIOD = 1000000
[KINS]
JOINTS = 1
[HAL]
HALFILE = mill.hal
[JOINT_0]
SCALE = 1000
"""
_HM2_HAL = """loadrt hostmot2
loadrt hm2_pci config="num_stepgens=1"
setp hm2_5i20.0.stepgen.00.steplen 5000
setp hm2_5i20.0.stepgen.00.stepspace 5000
setp hm2_5i20.0.stepgen.00.dirsetup 5000
setp hm2_5i20.0.stepgen.00.dirhold 5000
setp hm2_5i20.0.stepgen.00.position-scale [JOINT_0]SCALE
net xpos joint.0.motor-pos-cmd => hm2_5i20.0.stepgen.00.position-cmd
setp hm2_5i20.0.gpio.040.is_output TRUE
setp hm2_5i20.0.gpio.040.invert_output TRUE
"""


@pytest.mark.parametrize("invert_step", [True, False])
def test_hm2_inverted_module_output_is_named(tmp_path: Path, invert_step: bool) -> None:
    """Seen in LinuxCNC configs/by_machine/smithy/622leadshine.hal: ``setp
    hm2_5i20.0.gpio.000.invert_output TRUE`` ("invert the step pulse polarity") for the step
    pins of stepgens 0..3; the report said "pulses high at the pin". hostmot2 gives a pin that
    is "an output for some other module" the invert_output parameter and writes it to the
    output-invert register (src/hal/drivers/mesa-hostmot2/ioport.c hm2_ioport_gpio_export_hal,
    hm2_ioport_update); which IO pin is a stepgen's STEP is in the bitfile's pin table, so the
    report says so. A plain GPIO output (``is_output`` TRUE, gpio.040 here) is no stepgen's."""
    (tmp_path / "mill.ini").write_text(_HM2_INI)
    extra = "setp hm2_5i20.0.gpio.000.invert_output TRUE\n" if invert_step else ""
    (tmp_path / "mill.hal").write_text(_HM2_HAL + extra)
    notes = read_firmware(tmp_path / "mill.ini").axis("stepgen.00").notes
    named = [n for n in notes if "invert_output" in n]
    assert bool(named) == invert_step
    assert not any("gpio.040" in n for n in named)


def test_rrf_axis_with_mirrored_second_driver_says_so(tmp_path: Path) -> None:
    """Seen in 4cello/mirandacnc-duet config.g: ``M569 P1 S1`` and ``M569 P3 S0`` with ``M584
    Y1:3`` (a gantry's second Y motor mirrored); Y was reported "DIR not inverted", true for
    driver 1 only. RepRapFirmware keeps the direction per driver (M569 S: SetDirectionValue per
    drive, GCodes ConfigureDriver), so the report names the driver that differs."""
    cfg = tmp_path / "config.g"
    cfg.write_text("M569 P1 S1\nM569 P3 S0\nM584 X0 Y1:3 Z2\nM92 X80 Y80 Z400\n"
                   "M203 X6000 Y6000 Z600\n")  # fmt: skip
    got = read_firmware(cfg)
    assert not got.axis("Y").dir_inverted
    assert any("driver 3 only" in n for n in got.axis("Y").notes)
    assert not got.axis("X").notes  # one driver: nothing to say


def test_rrf_unsupported_microstepping_is_not_applied(tmp_path: Path) -> None:
    """Seen in diabase/H-Series-Configuration config.g (``M350 ... W400 ...``): the whole file
    was refused ("M350 W '400' is out of range"). RepRapFirmware's M350 calls
    ChangeMicrostepping per letter; when the drive refuses the value it replies "Drive %c does
    not support %ux microstepping" and goes on with the next letter (GCodes M350), so the other
    axes are read and that drive keeps its microstepping (no steps/mm rescale)."""
    cfg = tmp_path / "config.g"
    cfg.write_text("M584 X0 Y1 Z2 W5\nM92 X80 Y80 Z400 W400\nM350 X32 W400\n"
                   "M203 X6000 Y6000 Z600 W600\n")  # fmt: skip
    got = read_firmware(cfg)
    assert got.axis("X").max_rate.value == 160 * 6000 / 60  # 80 steps/mm x 32/16
    assert got.axis("W").max_rate.value == 400 * 600 / 60  # not rescaled
    assert any("W400" in u and "not applied" in u for u in got.unsupported)
