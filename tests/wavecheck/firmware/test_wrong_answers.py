"""Each wrong answer of issue 24, on a real configuration: before this change each gave a wrong
figure or verdict (or refused a file a user expects read); the documented fact each checks is
named (FT = ../shared/reference/firmware-timing.md, SG = stepgen-linuxcnc.md)."""

from __future__ import annotations

import json
import re
import shutil
from fractions import Fraction
from pathlib import Path

import pytest

from tests.conftest import SHARED
from tools.firmware_corpus import CORPUS
from wavecheck.cli import main
from wavecheck.errors import ConfigError
from wavecheck.firmware import read_firmware

FW = SHARED / "firmware"
LCNC = CORPUS / "linuxcnc/configs"
pytestmark = pytest.mark.skipif(not CORPUS.is_dir(), reason="shared firmware corpus not present")


def _config(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, dict]:  # type: ignore[type-arg]
    code = main(["config", *argv, "--format", "json"])
    return code, json.loads(capsys.readouterr().out)


def _rule(doc: dict, axis: str, rule: str) -> dict:  # type: ignore[type-arg]
    pair = next(p for p in doc["pairs"] if p["axis"] == axis)
    return next(r for r in pair["rules"] if r["rule"] == rule)


# -- LinuxCNC: the step generator is what the HAL files load ---------------------------------


def test_a_simulator_with_a_base_period_has_no_invented_stepgen(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """gmoccapy.ini sets BASE_PERIOD 100000 but loads no stepgen: it was read as stepgen.0 with
    "stepgen default (1 ns = one period)" figures and PASSed."""
    code = main(["config", str(LCNC / "sim/gmoccapy/gmoccapy.ini"), "--drive", "leadshine-dm542"])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1
    assert "no step generator" in err and "gmoccapy.ini:" in err and "stepgen" in err


def test_halfiles_from_linuxcnc_hal_library_are_read() -> None:
    """stepper_mm.ini's core_stepper.hal (which loads stepgen) is in LinuxCNC's HAL library, not
    beside the INI: it was 'not found' and the stepgen came from defaults of nothing loaded."""
    cfg = read_firmware(LCNC / "by_interface/parport/stepper/stepper_mm.ini")
    assert any(f.endswith("lib/hallib/core_stepper.hal") for f in cfg.files)
    assert cfg.axis_names == ("stepgen.0", "stepgen.1", "stepgen.2")  # step_type=0,0,0
    assert cfg.axis("x").axis == "stepgen.0"  # joint 0 -> [TRAJ] COORDINATES X Y Z


def test_parport_reset_makes_the_pulse(capsys: pytest.CaptureFixture[str]) -> None:
    """Gecko_540B3: steplen 1, stepspace 0 and parport reset (reset-time 1000): the low time was
    reported as 0 s (FAIL); on the pin the pulse is the reset time and the rest of the 23 us
    period is low (SG §2.3, hal_parport's reset function)."""
    ini = LCNC / "by_interface/parport/gecko/Gecko_540B3/Gecko_540B3.ini"
    code, doc = _config(capsys, str(ini), "--drive", "gecko-g540")
    assert _rule(doc, "stepgen.0", "step_low")["generator_ns"] == 22000
    assert _rule(doc, "stepgen.0", "step_high")["generator_ns"] == 1000
    assert _rule(doc, "stepgen.0", "step_low")["verdict"] == "pass"
    assert code == 3  # dir_setup rests on dirsetup, which stepgen may not keep (LinuxCNC #2332)


def test_ini_continuations_and_includes_are_read() -> None:
    """eoffsets.ini continues a value with '\\' (refused: "is not KEY = VALUE"); corexy_by_kins.ini
    takes its [HAL] section from an #INCLUDE (refused: not recognised)."""
    with pytest.raises(ConfigError, match="no step generator"):  # a simulator, read to its end
        read_firmware(LCNC / "sim/axis/external_offsets/eoffsets.ini")
    cfg = read_firmware(LCNC / "sim/axis/corexy/corexy_by_kins.ini")
    assert cfg.firmware == "linuxcnc" and len(cfg.axes) == 3


def test_other_cards_are_named_not_asked_for_a_base_period(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """GM6-PCI (hal_gm) got the misleading "no BASE_PERIOD"."""
    ini = LCNC / "by_interface/general_mechatronics/GM6-PCI/3-axis-stepper.ini"
    assert main(["config", str(ini), "--drive", "leadshine-dm542"]) == 2
    err = capsys.readouterr().err
    assert "hal_gm" in err and "GM6-PCI" in err and "BASE_PERIOD" not in err


def test_hm2_without_a_hostmot2_section_is_hm2(tmp_path: Path) -> None:
    """A Mesa configuration whose HAL loads hostmot2 and names the board itself, with no
    [HOSTMOT2] section in the INI (as the smithy configurations do), was read as a software
    stepgen. Made from the real 5i20 configuration: its [HOSTMOT2] values written into the HAL."""
    ini = (FW / "linuxcnc/hm2-stepper/5i20.ini").read_text()
    hal = (FW / "linuxcnc/hm2-stepper/hm2-stepper.hal").read_text()
    section = re.search(r"^\[HOSTMOT2\]\n(?:[^\[].*\n|\n)*", ini, re.M)
    assert section
    values = dict(re.findall(r"^(\w+)\s*=\s*(\S+)", section.group(0), re.M))
    for key, value in values.items():
        hal = hal.replace(f"[HOSTMOT2]({key})", value)
    (tmp_path / "5i20.ini").write_text(
        ini.replace(section.group(0), "[EMCMOT]\nBASE_PERIOD = 1000000\n")
    )
    (tmp_path / "hm2-stepper.hal").write_text(hal)
    cfg = read_firmware(tmp_path / "5i20.ini")
    assert cfg.firmware == "hm2" and cfg.axis_names[0] == "stepgen.00"
    assert cfg.axes[0].pulse.value == 40000  # STEPLEN, not a 1 ms software-stepgen period


def test_hm2_dir_hold_is_what_the_hardware_does(capsys: pytest.CaptureFixture[str]) -> None:
    """5i20 (DIRHOLD 200, STEPLEN 40000): the hold counter is loaded with the pulse and DIR may
    change when it runs out, while STEP is still high (kubstepgenz.vhd:212-219, run under GHDL):
    200 ns after the leading edge (was max(steplen, dirhold) = 40 us, a PASS for a 650 ns hold),
    and before the trailing edge (0)."""
    ini = str(FW / "linuxcnc/hm2-stepper/5i20.ini")
    _, doc = _config(capsys, ini, "--drive", "drv8825")  # rising edge, 650 ns hold
    hold = _rule(doc, "stepgen.00", "dir_hold")
    assert hold["generator_ns"] == 200 and hold["verdict"] == "fail"
    _, doc = _config(capsys, ini, "--drive", "gecko-g202")  # falling edge, 20 us hold
    hold = _rule(doc, "stepgen.00", "dir_hold")
    assert hold["generator_ns"] == 0 and hold["verdict"] == "fail"


# -- Marlin ----------------------------------------------------------------------------------


def test_marlin_2_0_0_pulse_0_is_not_enforced(capsys: pytest.CaptureFixture[str]) -> None:
    """Renkforce RF100 (2.0.0) sets MINIMUM_STEPPER_PULSE 0 (adv line 1546). It was read as
    "not set", high = low = 5e8 / rate: that is the 2020 pulse code. 2.0.0's
    stepper_pulse_phase_isr waits for the high time only ``#if MINIMUM_STEPPER_PULSE``: a 0
    pulse is the code between PULSE_START and PULSE_STOP, and no DIR delay is 0 ns of wait.
    Neither may PASS."""
    cfg = read_firmware(CORPUS / "marlin/200/Renkforce/RF100/Configuration.h")
    x = cfg.axis("X")
    assert x.pulse.value is None and x.pulse.status == "not_enforced"
    assert x.dir_setup.value is None and x.dir_setup.status == "not_enforced"
    assert any("Marlin 2.0" in n for n in cfg.notes)  # the version inferred is stated
    code, doc = _config(capsys, str(CORPUS / "marlin/200/Renkforce/RF100/Configuration.h"),
                        "--drive", "a4988")  # fmt: skip
    assert _rule(doc, "X", "step_high")["verdict"] == "indeterminate"


def test_marlin_old_tmc_configs_get_their_own_dir_default() -> None:
    """2.0.9.5 TMC2209 (SKR Mini E3 1.2) got 2.1.3's 100 ns DIR delay; its own releases default
    to 20 or 70 ns (FT §4 "Older tables differ"): the smaller is the bound."""
    cfg = read_firmware(CORPUS / "marlin/2097/Creality/Ender-3/BigTreeTech_SKR_Mini_E3_1.2")
    assert cfg.axis("X").dir_setup.value == 20


@pytest.mark.parametrize(
    ("file", "pulse_ns", "idle_ns", "hold_ns"),
    [
        # MINIMUM_STEPPER_PULSE, _DIR_DELAY(s), _RATE all unset: the #else defaults 2 us, 0 ns,
        # 250 kHz (not A4988's 1 us, 200 ns, 500 kHz): low = max(1e9 / 250 kHz - 2000, 2000);
        # DIR is written after the pulse ended: hold >= the pulse
        ("marlin/119/Creality/Ender-3/Configuration.h", 2000, 2000, 2000),
        ("marlin/200/Anet/A8/Configuration.h", 2000, 2000, 2000),
        # MINIMUM_STEPPER_PULSE 0 in 2.0.0: no high-time wait (see above)
        ("marlin/200/Renkforce/RF100/Configuration.h", None, None, None),
    ],
)
def test_marlin_without_driver_types_uses_the_else_defaults(
    file: str, pulse_ns: int | None, idle_ns: int | None, hold_ns: int | None
) -> None:
    """1.1.9 and 2.0.0 files with every X_DRIVER_TYPE commented out were read as A4988s (the
    file's comment says "A4988 is assumed"). The code decides otherwise: drivers.h tests
    ``defined(A##_DRIVER_TYPE) && …`` (MarlinFirmware/Marlin:Marlin/drivers.h:43 @ 268245c6 for
    1.1.x, Marlin/src/core/drivers.h:51 @ ae1cc796 for 2.0.0) and no fallback type is defined
    before the later 2.0.x Conditionals_LCD.h, so no HAS_DRIVER(T) holds and the ``#else``
    defaults apply; the 0 ns DIR delay is not enforced."""
    cfg = read_firmware(CORPUS / file)
    x = cfg.axis("X")
    assert "A4988" not in x.info["driver type"]
    assert (x.pulse.value, x.idle.value, x.dir_hold.value) == (pulse_ns, idle_ns, hold_ns)
    assert x.dir_setup.value is None and x.dir_setup.status == "not_enforced"
    assert not cfg.unsupported


def test_marlin_steps_per_unit_expressions_do_not_refuse_the_file() -> None:
    cfg = read_firmware(CORPUS / "marlin/21x/RepRapWorld/Megatronics/Configuration.h")
    x = cfg.axis("X")  # { 78.7402*2, ...} x 300 mm/s: the sustained rate (in the note)
    assert f"{float(Fraction('78.7402') * 2 * 300):g} Hz" in x.max_rate.note


def test_marlin_driver_named_through_a_macro() -> None:
    """Sapphire Plus: Y_DRIVER_TYPE is X_DRIVER_TYPE, which is TERN(SAPPHIRE_PLUS_TMC_UART, ...):
    it was read as a driver type called "X_DRIVER_TYPE"."""
    cfg = read_firmware(CORPUS / "marlin/21x/Two_Trees/Sapphire_Plus/Sapphire_Plus_V2.1")
    assert cfg.axis("Y").info["driver type"].startswith("TMC2208_STANDALONE")


def test_marlin_driver_type_in_the_active_branch(tmp_path: Path) -> None:
    """A driver type inside #if/#else took the first #define whatever branch was active (no
    such file is in the development corpus: a real 2.1.3 file with its Z driver put in a branch
    decided by its own MOTHERBOARD, the active branch an A4988)."""
    folder = CORPUS / "marlin/21x/BIQU/B1"
    text = (folder / "Configuration.h").read_text()
    board = re.search(r"^\s*#define MOTHERBOARD (\w+)", text, re.M)
    assert board and board.group(1) == "BOARD_BTT_SKR_V2_0_REV_B"
    branch = (f"#if MOTHERBOARD != {board.group(1)}\n#define Z_DRIVER_TYPE TMC2209\n#else\n"
              f"#define Z_DRIVER_TYPE A4988\n#endif")  # fmt: skip
    text = re.sub(r"^#define Z_DRIVER_TYPE .*$", branch, text, count=1, flags=re.M)
    (tmp_path / "Configuration.h").write_text(text)
    shutil.copy(folder / "Configuration_adv.h", tmp_path)
    cfg = read_firmware(tmp_path / "Configuration.h")
    assert cfg.axis("Z").info["driver type"].startswith("A4988")
    assert cfg.axis("X").pulse.value == 1000  # the A4988 sets the machine's pulse


# -- Klipper ---------------------------------------------------------------------------------


def test_klipper_z1_to_z3_use_max_z_velocity() -> None:
    """kit-voron2: stepper_z1..z3 took max_velocity 350 instead of max_z_velocity 50."""
    cfg = read_firmware(CORPUS / "klipper/kit-voron2-250mm.cfg")
    for z in ("stepper_z", "stepper_z1", "stepper_z2", "stepper_z3"):
        assert cfg.axis(z).max_rate.value == 50 * 400


def test_klipper_extruder_steppers_are_read() -> None:
    """[extruder_stepper …] sections were skipped silently."""
    cfg = read_firmware(CORPUS / "klipper/printer-geeetech-A10T-A20T-2021.cfg")
    assert "extruder_stepper extruder_1" in cfg.axis_names


def test_klipper_avr_found_only_by_pins_is_not_firm_2us(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """example-cartesian names no chip; its PF0..PL3 pins are an ATmega2560's: the 2 us figure
    was firm (PASS); an AVR's fast path makes the pulse instruction time (FT §3)."""
    code, doc = _config(capsys, str(CORPUS / "klipper/example-cartesian.cfg"), "--drive", "a4988")
    assert _rule(doc, "stepper_x", "step_high")["verdict"] == "indeterminate" and code == 3


def test_klipper_truncation_note_only_where_true() -> None:
    """ "truncated to the MCU clock" was printed for every file, e.g. the Spider's 2 us = 360
    ticks of its STM32F446's 180 MHz; it is kept where truncation shortens the pulse."""
    spider = read_firmware(CORPUS / "klipper/generic-fysetc-spider.cfg")
    assert not any("truncated" in n for n in spider.notes)
    assert "truncated" not in spider.axis("stepper_x").pulse.note
    made = read_firmware(FW / "klipper/generic-mellow-fly-e3-v2.cfg")  # 4 us on the STM32F407
    assert "truncated" not in made.axis("stepper_x").pulse.note  # 672 whole ticks


# -- RRF, grbl, FluidNC ------------------------------------------------------------------------


def test_rrf_config_of_includes_is_read() -> None:
    """A config.g that only M98-includes drives.g, speed.g … was "not recognised"."""
    cfg = read_firmware(CORPUS / "rrf/benagricola+rrf-config-new/full/sys/config.g")
    assert any(f.endswith("drives.g") for f in cfg.files)
    assert cfg.axis("X").info["steps/mm"].startswith("800")  # drives.g:25 M92 X800


def test_grbl_esp32_is_not_grblhal(capsys: pytest.CaptureFixture[str]) -> None:
    """Grbl_ESP32 dumps were labelled grblHAL and told to set $29."""
    path = CORPUS / "grbl/HACManchester+Tools.OxCNC/Firmware/esp32-grbl/GRBL-ESP32-Settings-old.txt"
    cfg = read_firmware(path)
    assert "Grbl_ESP32" in cfg.notes[0] and "grblHAL" not in cfg.notes[0]
    _, doc = _config(capsys, str(path), "--drive", "leadshine-dm542")
    assert "$29" not in json.dumps(doc)


def test_grbl_dump_without_0_uses_the_default(tmp_path: Path) -> None:
    """A grbl dump without $0 was refused; grbl's default (10 us, defaults.h) applies, marked."""
    text = (CORPUS / "grbl/tiago-rorke+wandering-gaze/grbl_settings.txt").read_text()
    (tmp_path / "dump.txt").write_text(re.sub(r"^\$0=.*\n", "", text, flags=re.M))
    x = read_firmware(tmp_path / "dump.txt").axis("X")
    assert x.pulse.value == 9437.5 and x.pulse.status == "default"  # 10 us - 562.5 ns


def test_fluidnc_is_read() -> None:
    """FluidNC files were "not a configuration wavecheck recognises"."""
    cfg = read_firmware(CORPUS / "fluidnc/official/6_pack_TMC2130_XYZ.yaml")
    assert cfg.firmware == "fluidnc" and cfg.axis("x").pulse.value == 4000
