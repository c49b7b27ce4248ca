"""Each real configuration in ../shared/firmware/ is read: the figures a person reads off the
file by hand (the line they come from is named beside each), as wavecheck reads them."""

from __future__ import annotations

from fractions import Fraction

import pytest

from tests.conftest import SHARED
from wavecheck.firmware import detect, read_firmware

FW = SHARED / "firmware"
pytestmark = pytest.mark.skipif(not FW.is_dir(), reason="shared firmware files not present")
F = Fraction


def v(x: object) -> Fraction | None:
    return getattr(x, "value", None)


def test_grbl_settings_md() -> None:
    cfg = read_firmware(FW / "grbl/settings.md")
    assert cfg.firmware == "grbl" and cfg.axis_names == ("X", "Y", "Z")
    x = cfg.axis("X")
    assert v(x.pulse) == 9437.5  # line 32: $0=10 (us), less 562.5 ns (grbl stepper.c:241)
    assert x.pulse.where.endswith("settings.md:32")
    assert x.pulse_level == 1  # line 34: $2=0
    assert not x.dir_inverted  # line 35: $3=0
    assert v(x.max_rate) == F(250) * 500 / 60  # lines 54, 57: $100=250.000, $110=500.000 mm/min
    # grbl writes DIR a few cycles before STEP with no delay (stepper.c:323-333): not enforced
    assert x.dir_setup.value is None and x.dir_setup.status == "not_enforced"


def test_grbl_user_dumps() -> None:
    cfg = read_firmware(FW / "grbl/GRBL-config.md")  # first dump, lines 6-39
    assert v(cfg.axis("X").pulse) == 9437.5  # line 6: $0=10, less 562.5 ns
    assert [a.dir_inverted for a in cfg.axes] == [True, False, True]  # line 9: $3=5 (X, Z)
    assert v(cfg.axis("X").max_rate) == F(800 * 1000, 60)  # lines 28, 31: $100=800, $110=1000
    assert v(cfg.axis("Y").max_rate) == F(800 * 800, 60)  # lines 29, 32: $101=800, $111=800
    assert v(cfg.axis("Z").max_rate) == F(800 * 500, 60)  # lines 30, 33: $102=800, $112=500
    assert any("second one" in n for n in cfg.notes)  # the 1.1h default dump follows at line 46


def test_klipper_skr_mini_e3_tmc_uart_both_edges() -> None:
    cfg = read_firmware(FW / "klipper/generic-bigtreetech-skr-mini-e3-v2.0.cfg")
    x = cfg.axis("stepper_x")
    # [tmc2209 stepper_x] line 25, uart_pin: 100 ns (klippy/extras/tmc.py:487) = 6 or 7 ticks of
    # an STM32F103 (header comment) at 64/72 MHz, <= EDGE_STEP_TICKS = ceil(clock / 8 MHz) = 8/9
    # (klipper src/stepper.c:132, 233-235): the optimised edge path, which enforces no time
    # between edges (src/stepper.c:139-150)
    assert x.pulse.value is None and x.pulse.status == "not_enforced"
    assert x.dir_hold.value is None and "stepper_load_next" in (x.dir_hold.note)
    assert x.both_edges and x.active_edge == "both"
    assert x.dir_inverted  # line 16: dir_pin: !PB12
    assert not cfg.axis("stepper_z").dir_inverted  # line 52: dir_pin: PC5
    # lines 18-19: microsteps 16, rotation_distance 40 -> 80 steps/mm; line 114 max_velocity 300
    assert v(x.max_rate) == 300 * 80
    # line 55: rotation_distance 8 -> 400 steps/mm; line 116 max_z_velocity 5
    assert v(cfg.axis("stepper_z").max_rate) == 5 * 400


def test_klipper_mellow_explicit_duration_wins() -> None:
    cfg = read_firmware(FW / "klipper/generic-mellow-fly-e3-v2.cfg")
    x = cfg.axis("stepper_x")
    assert v(x.pulse) == 4000 and x.pulse.where.endswith(":29")  # line 29: 0.000004 s
    assert not x.both_edges  # 4 us > 500 ns: the TMC section's both-edge request is refused
    assert v(x.dir_setup) == 4000 and v(x.dir_hold) == 4000
    ext = cfg.axis("extruder")
    # [tmc2209 extruder] line 134, no duration: 100 ns = 16 ticks of the STM32F407's 168 MHz,
    # <= EDGE_STEP_TICKS 21 (src/stepper.c:132): the edge path, nothing enforced
    assert ext.pulse.value is None and ext.pulse.status == "not_enforced" and ext.both_edges


def test_klipper_duet3_6xd_default_2us() -> None:
    cfg = read_firmware(FW / "klipper/generic-duet3-6xd.cfg")
    x = cfg.axis("stepper_x")
    assert v(x.pulse) == 2000 and x.pulse.status == "default"  # no step_pulse_duration, no TMC
    assert v(x.max_rate) == 350 * F(200 * 128, 40)  # line 38-39: 128 microsteps, 40 mm; line 107


def test_klipper_ender3_avr_pulse_unknown() -> None:
    cfg = read_firmware(FW / "klipper/printer-creality-ender3-2018.cfg")
    x = cfg.axis("stepper_x")
    assert x.pulse.value is None  # AVR fast path (line 1-2: atmega1284p): instruction time
    assert x.dir_inverted  # line 16: dir_pin: !PC5


MARLIN = FW / "marlin"


def test_marlin_ender3_skr14_tmc2209_edge_stepping() -> None:
    cfg = read_firmware(MARLIN / "Creality_Ender-3_Pro_BigTreeTech_SKR_1.4_Turbo/Configuration.h")
    x = cfg.axis("X")
    assert v(x.pulse) == 1000  # Configuration_adv.h:2595 MINIMUM_STEPPER_PULSE_NS 1000
    assert x.pulse.where.endswith("Configuration_adv.h:2595")
    assert v(x.dir_setup) == 100 and x.dir_setup.status == "default"  # TMC default POST_DIR_DELAY
    assert v(x.dir_hold) == 1000 + 100  # pulse + PRE_DIR_DELAY (TMC default 100)
    assert v(x.idle) == 1000  # max(1e9 / 5 MHz (TMC default) - 1000, 1000)
    assert x.both_edges  # Configuration_adv.h:3479 EDGE_STEPPING + Configuration.h:154 TMC2209
    # Configuration.h:1291 {80,...}, :1303 {500,...} mm/s: the sustained rate; multi-stepping
    # may step X at the TMC driver rate (stepper.cpp pulse_phase_isr)
    assert v(x.max_rate) == 5_000_000 and f"{80 * 500} Hz" in x.max_rate.note
    assert cfg.axis("X").dir_inverted and not cfg.axis("Z").dir_inverted  # lines 1809, 1811


def test_marlin_voron_drv8825_defaults() -> None:
    cfg = read_firmware(MARLIN / "VORONDesign")
    x = cfg.axis("X")
    assert detect(MARLIN / "VORONDesign/Configuration.h") == "marlin"
    assert v(x.pulse) == 2000 and "DRV8825" in x.pulse.where  # Configuration.h:154 DRV8825
    assert v(x.dir_setup) == 650 and v(x.dir_hold_trailing) == 650
    assert v(x.idle) == 2000  # max(1e9/250 kHz - 2000, 2000)
    assert not x.both_edges  # EDGE_STEPPING (adv:3479) has no effect without TMC
    # COREXY is enabled (a Voron 2): X and Y motors are coupled, so steps/unit x feedrate does not
    # bound them; the driver rate Marlin times pulses for is what is left (uncertain)
    assert v(x.max_rate) == 250_000 and x.max_rate.status == "uncertain"
    # Configuration.h:1291, :1303 (Z is cartesian): its sustained rate, below the driver rate
    assert f"{400 * 5} Hz" in cfg.axis("Z").max_rate.note


def test_marlin_ortur_old_format() -> None:
    cfg = read_firmware(MARLIN / "Ortur_4_release-2.0.9.7/Configuration.h")
    x = cfg.axis("X")
    assert v(x.pulse) == 1000 and x.pulse.unit == "us"  # adv:2237 MINIMUM_STEPPER_PULSE 1
    assert v(x.dir_setup) == 200  # adv:2223 MINIMUM_STEPPER_POST_DIR_DELAY 200 (setup)
    assert v(x.dir_hold_trailing) == 200  # adv:2224 MINIMUM_STEPPER_PRE_DIR_DELAY 200 (hold)
    assert v(x.idle) == 1000  # adv:2251 MAXIMUM_STEPPER_RATE 500000: max(2000 - 1000, 1000)
    assert x.pulse_level == 1  # adv:1025 INVERT_X_STEP_PIN false
    assert cfg.axis("Y").dir_inverted  # Configuration.h:1532 INVERT_Y_DIR true
    assert f"{400 * 8} Hz" in cfg.axis("Z").max_rate.note  # Configuration.h:1089, :1096


def test_rrf_cnc_one_external_drivers() -> None:
    cfg = read_firmware(FW / "reprapfirmware/cnc-one/config.g")
    x = cfg.axis("X")  # line 20: M584 X3 Y2:1 Z0; line 21: M569 P3 ... T5:5:10:0
    assert (v(x.pulse), v(x.idle), v(x.dir_setup)) == (5000, 5000, 10000)
    # hold counts from the falling edge; T field 4 = 0 is no wait (not enforced), but DIR changes
    # only after STEP went low: from the rising edge, the 5 us high time
    assert x.dir_hold_trailing is not None and x.dir_hold_trailing.status == "not_enforced"
    assert v(x.dir_hold) == 5000
    assert v(x.max_rate) == F(160 * 12000, 60)  # line 27: M92 X160; line 29: M203 X12000 mm/min
    assert cfg.axis("Y").info["drivers"] == "2,1"  # line 20: M584 Y2:1


def test_rrf_hummel_default_timing() -> None:
    cfg = read_firmware(FW / "reprapfirmware/Hummel_SKR1.4_DWC/config.g")
    x = cfg.axis("X")  # line 19: M569 P0 S1, no T: a fast driver, no wait (DDA::StepDrivers)
    assert x.pulse.value is None and x.pulse.status == "not_enforced"
    assert x.dir_setup.value is None
    # line 10: M669 K2 is CoreXZ in RRF's KinematicsType (the file's comment says CoreXY): X and Z
    # are coupled, so M92 x M203 does not bound them; Y moves alone
    assert x.max_rate.value is None and "M669 K2" in x.max_rate.note
    assert v(cfg.axis("Y").max_rate) == F(80 * 6000, 60)  # line 25: M92 Y80; line 27: M203 Y6000


def test_smoothieboard_defaults() -> None:
    cfg = read_firmware(FW / "smoothieware/Smoothieboard/config")
    a = cfg.axis("alpha")
    assert v(a.pulse) == 1000 and a.pulse.status == "default"  # no microseconds_per_step_pulse
    assert v(a.max_rate) == F(80 * 30000, 60)  # lines 16, 39: 80 steps/mm, 30000 mm/min
    # 333.3333 x 30000/60 > 100 kHz: Robot::check_max_actuator_speeds floors max_rate to 300 mm/s
    assert v(cfg.axis("beta").max_rate) == F("333.3333") * 300
    assert v(cfg.axis("gamma").max_rate) == F(1600 * 300, 60)  # lines 18, 51


def test_hm2_5i20() -> None:
    cfg = read_firmware(FW / "linuxcnc/hm2-stepper/5i20.ini")
    assert cfg.firmware == "hm2" and cfg.axis_names == ("stepgen.00", "stepgen.01", "stepgen.02")
    s = cfg.axes[0]  # 5i20.ini:123-126 DIRSETUP 200, DIRHOLD 200, STEPLEN 40000, STEPSPACE 40000
    assert (v(s.pulse), v(s.idle), v(s.dir_setup)) == (40000, 40000, 200)
    # DIR hold: the hold counter starts with the pulse and DIR may change when it runs out, even
    # while STEP is high (kubstepgenz.vhd:212-219): 200 ns from the leading edge, 0 from the end
    assert v(s.dir_hold) == 200 and v(s.dir_hold_trailing) == 0
    assert s.pulse.where.endswith("hm2-stepper.hal:84")
    assert v(s.max_rate) == 12 * 1000  # 5i20.ini:106 STEPGEN_MAX_VEL 12 x :110 SCALE 1000


def test_hm2_clock_rounding() -> None:
    cfg = read_firmware(FW / "linuxcnc/plasma-5i20/plasma-5i20.ini", clock_hz=F(33_000_000))
    s = cfg.axes[0]  # plasma-5i20.ini:105 STEPLEN 1000 -> 33 clocks -> 34 clocks high
    assert v(s.pulse) == F(34 * 10**9, 33_000_000)
    assert v(s.dir_setup) == F(6 * 10**9, 33_000_000)  # :103 DIRSETUP 200 -> 6 clocks


def test_plasma_without_clock() -> None:
    cfg = read_firmware(FW / "linuxcnc/plasma-5i20/plasma-5i20.ini")
    s = cfg.axes[0]  # :105 STEPLEN 1000, :106 STEPSPACE 2000; maxvel 0
    assert (v(s.pulse), v(s.idle)) == (1000, 2000)
    assert v(s.max_rate) == F(10**9, 3000)
