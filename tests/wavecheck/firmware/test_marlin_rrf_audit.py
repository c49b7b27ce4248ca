"""The reader errors the Marlin and RepRapFirmware audit (issue 32, corpus_figures.toml) found,
one test per class, each citing the firmware code that decides it."""

from __future__ import annotations

from fractions import Fraction
from pathlib import Path

import pytest

from tools.firmware_corpus import CORPUS
from wavecheck.firmware import read_firmware

pytestmark = pytest.mark.skipif(not CORPUS.is_dir(), reason="shared firmware corpus not present")


def _marlin(tmp_path: Path, version: str, conf: str, adv: str = "") -> Path:
    (tmp_path / "Configuration.h").write_text(
        f"#define CONFIGURATION_H_VERSION {version}\n#define MOTHERBOARD BOARD_RAMPS_14_EFB\n{conf}"
    )
    (tmp_path / "Configuration_adv.h").write_text(
        f"#define CONFIGURATION_ADV_H_VERSION {version}\n{adv}"
    )
    return tmp_path / "Configuration.h"


def _types(kind: str) -> str:
    return "".join(f"#define {a}_DRIVER_TYPE {kind}\n" for a in ("X", "Y", "Z", "E0"))


_MOTION = (
    "#define DEFAULT_AXIS_STEPS_PER_UNIT { 80, 80, 400, 93 }\n"
    "#define DEFAULT_MAX_FEEDRATE { 300, 300, 5, 25 }\n"
)


@pytest.mark.parametrize(("kind", "both"), [("TMC2100", False), ("TMC2209", True)])
def test_marlin_tmc2100_is_standalone_so_edge_stepping_is_off(
    tmp_path: Path, kind: str, both: bool
) -> None:
    """Marlin/src/core/drivers.h @ 04e8baa9 lines 97-101: HAS_TRINAMIC_CONFIG counts TMC2130,
    2160, 2208, 2209, 2660, 5130, 5160; TMC2100 is in HAS_TRINAMIC_STANDALONE (106-111). So
    EDGE_STEPPING inside ``#if HAS_TRINAMIC_CONFIG`` (Artillery Genius Pro adv 2986-3479) is
    not defined for a TMC2100: one edge steps. It was read as both edges."""
    path = _marlin(tmp_path, "02010300", _types(kind) + _MOTION,
                   "#if HAS_TRINAMIC_CONFIG\n  #define EDGE_STEPPING\n#endif\n")  # fmt: skip
    assert read_firmware(path).axis("X").both_edges is both


def test_marlin_scara_z_is_not_coupled() -> None:
    """A SCARA's arms couple X and Y; Z passes through (Marlin/src/module/scara.cpp
    inverse_kinematics: ``delta.set(DEGREES(THETA), DEGREES(THETA + PSI), raw.z)``). Z was left
    without a rate; 200/SCARA/Morgan lines 743/750: 200/1.25 steps/mm x 30 mm/s."""
    cfg = read_firmware(CORPUS / "marlin/200/SCARA/Morgan/Configuration.h")
    # its sustained rate (multi-stepping may burst it at the driver rate: see below)
    assert Fraction(200) / Fraction("1.25") * 30 == 4800
    assert "4800 Hz" in cfg.axis("Z").max_rate.note
    assert "couple" not in cfg.axis("Z").max_rate.note
    assert cfg.axis("X").max_rate.status == "uncertain"  # the driver rate only


def test_marlin_2_0_0_uses_its_own_table(tmp_path: Path) -> None:
    """2.0.0's Conditionals_post.h (its Configuration_adv.h documents the same table): the TMC
    rate is 400 kHz, not the 5 MHz of later releases; with MINIMUM_STEPPER_PULSE 1 the low
    time is max(1e9 / 400 kHz - 1 us, 1 us) = 1.5 us, not 1 us."""
    path = _marlin(tmp_path, "020000", _types("TMC2208") + _MOTION,
                   "#define MINIMUM_STEPPER_PULSE 1\n")  # fmt: skip
    x = read_firmware(path).axis("X")
    assert (x.pulse.value, x.idle.value, x.dir_setup.value) == (1000, 1500, 20)


def test_marlin_2_0_9_tmc_hold_uses_the_documented_table() -> None:
    """2.0.9.5 documents TMC DIR 20 ns with a 5 MHz rate (SKR Mini E3 1.2 adv lines 2210-2246):
    pulse 5e8 / 5 MHz = 100 ns plus PRE 20 ns is a hold of 120 ns; the two tables read before
    (400 kHz with 20 ns, 5 MHz with 70 ns) gave 170 ns, more than this release may give."""
    x = read_firmware(CORPUS / "marlin/2097/Creality/Ender-3/BigTreeTech_SKR_Mini_E3_1.2").axis("X")
    assert (x.pulse.value, x.dir_setup.value, x.dir_hold.value) == (100, 20, 120)


def test_marlin_dual_steppers_and_macro_dir_inversion(tmp_path: Path) -> None:
    """Found by the hand sample: 200/Formbot/T_Rex_3 (adv 548 DUAL_X_CARRIAGE, X2 type left
    out) lost its X2 stepper; 119/hangprinter (986 ``INVERT_Y_DIR INVERT_B_DIR``) lost Y's DIR
    inversion because the value names a macro."""
    path = _marlin(tmp_path, "020000",
                   "#define INVERT_B true\n#define INVERT_Y_DIR INVERT_B\n" + _MOTION,
                   "#define DUAL_X_CARRIAGE\n")  # fmt: skip
    cfg = read_firmware(path)
    assert "X2" in cfg.axis_names and cfg.axis("Y").dir_inverted


def test_rrf_expansion_driver_without_t_is_not_enforced() -> None:
    """idx_13963938548 lines 25-27: E0/E1 on tool boards 20.0/21.0 without T. Their boards run
    their own firmware; nothing in the file bounds the pulse (it was a 0.2 us 'uncertain')."""
    e0 = read_firmware(CORPUS / "rrf/idx_13963938548/config.g").axis("E0")
    assert e0.pulse.value is None and e0.pulse.status == "not_enforced"
    assert e0.dir_setup.value is None


def test_rrf_default_extruder_needs_m92_or_m203() -> None:
    """idx_2226796419: M584 X0 Y1:2 Z3 (line 18) puts Z on driver 3, and T on drivers 0-4
    (26-30) made a default E0 on driver 3 appear, with Z's timing. Without M584 E the extruders
    are the version's default (2.0x: smart drivers - 3; 3.x NumDefaultExtruders): no E axis is
    assumed unless the file gives it M92 or M203 values."""
    assert read_firmware(CORPUS / "rrf/idx_2226796419/config.g").axis_names == ("X", "Y", "Z")


def test_rrf_commands_inside_an_if_block_are_not_taken_as_run(tmp_path: Path) -> None:
    """GenMachine lines 19-35: M584 W50.0 A51.0 and M92 W/A run only ``if (global.closedLoop)``;
    RepRapFirmware's meta-commands are not evaluated here, so the W/A axes (closed-loop CAN
    drivers) were claimed unconditionally. The block's motion commands are now left out, and
    said so; the lines after the block (back at its indentation) are read again."""
    cfg_g = tmp_path / "config.g"
    cfg_g.write_text(
        "M584 X0 Y1 Z2 E3\nif (global.closedLoop)\n    M584 W50.0\n    M92 W26.667\n"
        "else\n    M92 X100\nM92 X80 Y80 Z400 E420\nM203 X6000 Y6000 Z180 E1200\n"
    )
    cfg = read_firmware(cfg_g)
    assert cfg.axis_names == ("X", "Y", "Z", "E0")
    assert cfg.axis("X").max_rate.value == 80 * 6000 / 60
    assert any("block of" in u and ":2" in u for u in cfg.unsupported)


@pytest.mark.parametrize(
    ("adv", "x_rate", "e_rate"),
    [
        # the default: up to 128 steps per interrupt (2.1.x Conditionals_adv.h "Multi-Stepping
        # Limit"), spaced by the A4988 driver timing: every axis may step at 500 kHz
        ("", 500000, 500000),
        ("#define MULTISTEPPING_LIMIT 16\n", 500000, 500000),
        # one step per interrupt: steps/unit x feedrate, the planner's per-axis cap, holds
        ("#define MULTISTEPPING_LIMIT 1\n", 80 * 300, 93 * 25),
    ],
)
def test_marlin_multistepping_packs_every_axis_at_the_driver_rate(
    tmp_path: Path, adv: str, x_rate: int, e_rate: int
) -> None:
    """Stepper::calc_timer_interval (stepper.h; 2.1.x calc_multistep_timer_interval) takes up
    to 128 steps of the leading axis in one interrupt above the CPU's
    MAX_STEP_ISR_FREQUENCY_1X, and stepper.cpp pulse_phase_isr steps every axis's Bresenham
    on each of those events with only the low time waited between them (AWAIT_LOW_PULSE): an
    axis's steps may come 1 / driver rate apart. The reader claimed 80 x 300 = 24 kHz for X
    (steps/unit x feedrate, the sustained rate only), which a drive rated for 100 kHz passed."""
    path = _marlin(tmp_path, "02010300", _types("A4988") + _MOTION, adv)
    cfg = read_firmware(path)
    assert (cfg.axis("X").max_rate.value, cfg.axis("E0").max_rate.value) == (x_rate, e_rate)
    if x_rate == 500000:
        assert cfg.axis("X").idle.value == 1000  # 1e9 / 500 kHz - the 1 us A4988 pulse
        assert "sustained" in cfg.axis("X").max_rate.note


def test_marlin_one_step_per_interrupt_spaces_a_slow_axis_by_the_leading_axis(
    tmp_path: Path,
) -> None:
    """With one step per interrupt (DISABLE_MULTI_STEPPING, 2.0.x) no low time is waited at
    all (pulse_phase_isr's AWAIT_LOW_PULSE runs only after an interrupt's first step): a slow
    axis steps on the leading axis's events, at least 1 / min(2 x its rate, the fastest) apart
    (grbl's Bresenham), less the pulse. Z: 400 x 5 = 2 kHz -> 250 us - 1 us; X 24 kHz is the
    fastest: 1 / 24 kHz - 1 us."""
    path = _marlin(tmp_path, "02000900", _types("A4988") + _MOTION,
                   "#define DISABLE_MULTI_STEPPING\n")  # fmt: skip
    cfg = read_firmware(path)
    z, x = cfg.axis("Z"), cfg.axis("X")
    assert z.idle.value == Fraction(10**9, 4000) - 1000 and z.idle.status == "uncertain"
    assert x.idle.value == Fraction(10**9, 24000) - 1000
    assert z.max_rate.value == 2000
    fix = cfg.fix(z, "idle", Fraction(300_000))
    assert "DEFAULT_MAX_FEEDRATE" in fix and "MAXIMUM_STEPPER_RATE" not in fix


def test_marlin_hangprinter_d_anchor_is_a_stepper(tmp_path: Path) -> None:
    """1.1.9's HANGPRINTER drives four anchors (enum.h ``D_AXIS = 3, E_AXIS = 4``); D's motor
    is on the first E socket the extruders leave free (1.1.x Marlin/pins.h HANGPRINTER block:
    ``D_STEP_PIN _EPIN(E_STEPPERS, STEP)``; 119/hangprinter/Configuration.h:988-989
    ``INVERT_E1_DIR INVERT_D_DIR``). The reader left it out: a motor with STEP/DIR pins and no
    verdict. It takes that socket's driver type and ``INVERT_D_DIR``, and is coupled."""
    path = _marlin(tmp_path, "010109",
                   "#define EXTRUDERS 1\n#define HANGPRINTER\n#define INVERT_D_DIR true\n"
                   "#define E1_DRIVER_TYPE DRV8825\n#define X_DRIVER_TYPE A4988\n"
                   "#define Y_DRIVER_TYPE A4988\n#define Z_DRIVER_TYPE A4988\n"
                   "#define E0_DRIVER_TYPE A4988\n"
                   "#define DEFAULT_AXIS_STEPS_PER_UNIT { 92, 92, 92, 92, 410 }\n"
                   "#define DEFAULT_MAX_FEEDRATE { 500, 500, 500, 300, 25 }\n")  # fmt: skip
    cfg = read_firmware(path)
    assert cfg.axis_names == ("X", "Y", "Z", "D", "E0")
    d = cfg.axis("D")
    assert d.dir_inverted and "DRV8825" in d.info["driver type"]
    assert "couple" in d.max_rate.note
    assert cfg.axis("E0").info["steps/unit"].startswith("410 ")


_RRF_MOTION = "M92 X80 Y80 Z400 E420\nM203 X6000 Y6000 Z180 E1200\n"


@pytest.mark.parametrize(
    ("header", "axes"),
    [
        # 2.0x GCodes::Init: numExtruders = min(MaxExtruders, GetNumSmartDrivers() - XYZ_AXES)
        # ("don't default dumb drivers to extruders"); a Duet 2 WiFi has 5 smart drivers, and
        # Platform::Init maps extruder n to driver n + MinAxes: E0 on 3, E1 on 4
        (
            "; Configuration file for Duet WiFi (firmware version 2.03)\n",
            ("X", "Y", "Z", "E0", "E1"),
        ),
        # 3.x: the board's NumDefaultExtruders, which differs between releases: not applied
        ("; Configuration file for Duet WiFi (firmware version 3)\n", ("X", "Y", "Z", "E0")),
        ("; my printer\n", ("X", "Y", "Z", "E0")),
    ],
)
def test_rrf_default_extruders_follow_the_stated_version_and_board(
    tmp_path: Path, header: str, axes: tuple[str, ...]
) -> None:
    cfg_g = tmp_path / "config.g"
    cfg_g.write_text(header + "M569 P3 S1\nM569 P4 S0\n" + _RRF_MOTION)
    cfg = read_firmware(cfg_g)
    assert cfg.axis_names == axes
    if "E1" in axes:
        e1 = cfg.axis("E1")
        assert e1.info["drivers"] == "4" and e1.dir_inverted  # M569 P4 S0
        assert any("E1 on driver 4" in n and "config.g:1" in n for n in cfg.notes)
    else:
        assert any("no M584 E" in n for n in cfg.notes)


@pytest.mark.parametrize(
    ("version", "t", "figures"),
    [
        # before 1.21: GCodes case 569 SetDriverStepTiming(drive, gb.GetFValue()): the first
        # number only, for the high and the low time (DDA::Step waits it before raising and
        # before lowering STEP); DIR is written while STEP is high: no setup, no hold
        ("1.20", "2:3:5:5", (2000, 2000, None)),
        ("1.19", "0.2", (200, 200, None)),  # slow from minStepPulseTiming 0.2 us (>=)
        # 1.21 and later: 1 or 4 values, each field its own figure
        ("2.02", "2:3:5:5", (2000, 3000, 5000)),
        ("2.02", "0.2", (None, None, None)),  # not over 0.2 us: a fast driver, no wait
    ],
)
def test_rrf_m569_t_is_read_as_the_stated_version_reads_it(
    tmp_path: Path, version: str, t: str, figures: tuple[int | None, ...]
) -> None:
    """RepRapFirmware 1.21's release notes (WHATS_NEW.md): "New M569 T parameter options to
    specify step pulse width, step pulse interval, direction setup and direction hold times";
    "the DIR signal is no longer changed before the step pulse has ended". A 1.20 file's
    T2:3:5:5 was read as 3 us of low time and 5 us of DIR setup, which that firmware never
    waits for."""
    cfg_g = tmp_path / "config.g"
    cfg_g.write_text(f"; Configuration file for Duet WiFi (firmware version {version})\n"
                     f"M569 P0 S1 T{t}\nM569 P1 S1\nM569 P2 S1\n" + _RRF_MOTION)  # fmt: skip
    x = read_firmware(cfg_g).axis("X")
    assert (x.pulse.value, x.idle.value, x.dir_setup.value) == figures
    if version < "1.21":
        assert x.dir_setup.status == x.dir_hold.status == "not_enforced"


def test_marlin_an_axis_faster_than_the_waits_leaves_the_low_time_unenforced() -> None:
    """200/Wanhao/Duplicator_i3_2.1 lines 732/739: E0 100 steps/mm x 10000 mm/s = 1 MHz, over
    the 250 kHz that 1 / (2 us pulse + 2 us low) allows. In a move E leads, the interrupt cannot
    keep its schedule: isr() runs the pulse phase again at once ("Advance pulses if not enough
    time to wait for the next ISR"), and an interrupt's first step waits no low time
    (pulse_phase_isr: AWAIT_LOW_PULSE after firstStep only). The 2 us low time was a PASS."""
    cfg = read_firmware(CORPUS / "marlin/200/Wanhao/Duplicator_i3_2.1/Configuration.h")
    for axis in ("X", "E0"):
        idle = cfg.axis(axis).idle
        assert idle.status == "not_enforced" and idle.value == 2000  # a FAIL under it stands
        assert "E0 1e+06 Hz" in idle.note
    a_sane_one = read_firmware(CORPUS / "marlin/200/Anet/A8/Configuration.h").axis("X").idle
    assert a_sane_one.status == "uncertain" and a_sane_one.value == 2000  # the timer band only


@pytest.mark.parametrize(
    ("file", "low", "band"),
    [
        # 2020 rewrite: PULSE_LOW_TICK_COUNT = NS_TO_PULSE_TIMER_TICKS(...) (nearest tick) and
        # AWAIT_LOW_PULSE counts whole ticks from any phase: 1.5 ticks of a 2 MHz timer
        ("marlin/21x/Creality/CR-20/RepRapWorld_Minitronics20/Configuration.h", 2000, 750),
        # 2.0.0: pulse_end += ADDED_STEP_TICKS (integer division of cycles) from the high
        # wait's target, at any phase: 2 ticks
        ("marlin/200/Mks/Sbase/Configuration.h", 2000, 1000),
    ],
)
def test_marlin_low_time_carries_the_timer_band(file: str, low: int, band: int) -> None:
    """The low time between the steps of one interrupt is waited on the same pulse timer as the
    pulse (stepper.cpp AWAIT_LOW_PULSE), so it may fall short as the pulse does. It was an exact
    'derived' figure: CR-20 Minitronics20 step_low 2 us was a PASS by 100 ns against a DRV8825's
    1.9 us, inside the 750 ns the timer may lose."""
    x = read_firmware(CORPUS / file).axis("X")
    assert (x.idle.value, x.idle.short_by, x.idle.status) == (low, band, "uncertain")
    assert "AWAIT_LOW_PULSE" in x.idle.short_why or "ADDED_STEP_TICKS" in x.idle.short_why
