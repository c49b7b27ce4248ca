"""Uncertain firmware figures are judged at the worst end of their band (issue 32).

A figure the firmware aims at but may miss carries :attr:`Guaranteed.short_by`, derived from the
firmware's source; a rule passes only when the band's worst end meets the limit, fails only when
the aim misses it, and is indeterminate in between. Each case says which fact decides it.
"""

from __future__ import annotations

import json
import shutil
from fractions import Fraction
from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

from tests.conftest import SHARED, write_vcd
from wavecheck.cli import main
from wavecheck.drives.library import load_drive
from wavecheck.drives.overrides import tune_drive
from wavecheck.firmware import read_firmware
from wavecheck.firmware.evaluate import band_verdict, evaluate_config, worst_end
from wavecheck.firmware.guarantee import Guaranteed, uncertain

CORPUS = SHARED / "firmware-corpus"
pytestmark = pytest.mark.skipif(not CORPUS.is_dir(), reason="shared firmware corpus not present")

_NS = st.fractions(min_value=0, max_value=10**6, max_denominator=1000)


@given(value=_NS, short=_NS, limit=_NS)
def test_the_verdict_is_what_every_point_of_the_band_says(
    value: Fraction, short: Fraction, limit: Fraction
) -> None:
    """PASS iff every figure from value - short up to value meets the limit, FAIL iff none
    does: the two ends decide (the band is an interval)."""
    worst = value - short
    ends = (worst >= limit, value >= limit)
    want = "pass" if all(ends) else "fail" if not any(ends) else "indeterminate"
    assert band_verdict(value, worst, limit) == want


@given(value=_NS, limit=_NS)
def test_an_unbounded_band_never_passes(value: Fraction, limit: Fraction) -> None:
    assert band_verdict(value, None, limit) == ("fail" if value < limit else "indeterminate")


@pytest.mark.parametrize(
    ("value", "short", "limit", "verdict"),
    [
        (1000, 750, 250, "pass"),  # the worst end exactly at the limit passes
        (1000, 750, 251, "indeterminate"),  # a ns more: inside the band
        (1000, 750, 1000, "indeterminate"),  # the aim exactly at the limit, the band below it
        (1000, 750, 1001, "fail"),  # the aim itself misses it
        (1000, 0, 1000, "pass"),  # an exact figure: the boundary passes
        (1000, 0, 1001, "fail"),
    ],
)
def test_boundaries(value: int, short: int, limit: int, verdict: str) -> None:
    fig = uncertain(Fraction(value), "x", "", "ns", Fraction(short), "why")
    assert band_verdict(Fraction(value), worst_end(fig, False), Fraction(limit)) == verdict


def test_a_rate_band_is_above_the_rate_and_a_time_band_stops_at_zero() -> None:
    rate = uncertain(Fraction(80_000), "r", "", "Hz", Fraction(20_000), "why")
    assert worst_end(rate, True) == Fraction(10_000)  # ns: the period of 100 kHz
    pulse = uncertain(Fraction(100), "p", "", "ns", Fraction(750), "why")
    assert worst_end(pulse, False) == 0


def test_an_uncertain_figure_must_say_why() -> None:
    with pytest.raises(ValueError, match="must say why"):
        Guaranteed(Fraction(1), "x", "", "ns", "uncertain")


# (case, drive, limits, axis, rule, verdict, fact)
_MARLIN_CR20 = "marlin/21x/Creality/CR-20/RepRapWorld_Minitronics20/Configuration.h"
_MARLIN_200 = "marlin/200/ArmEd/Configuration.h"
_GRBL_ESP32 = "grbl/HACManchester+Tools.OxCNC/Firmware/esp32-grbl/GRBL-ESP32-Settings-old.txt"
_GRBL = "grbl/siredmar+grbl_settings/grbl_settings.txt"
_RRF_EXP = "rrf/idx_13963938548/config.g"
_HM2 = "linuxcnc/configs/by_interface/mesa/plasma-5i20/plasma-5i20.ini"
_FLUIDNC = "fluidnc/contributed/pen_2209/V2/2x_2209_V2_default.yaml"
CASES = [
    # Marlin 2.1.3, DRV8825 default 2000 ns: NS_TO_PULSE_TIMER_TICKS rounds to the nearest tick
    # and AWAIT_TIMED_PULSE counts from any phase (stepper.cpp), 2 MHz timer (HAL/AVR/timers.h:35):
    # 1250 ns at worst < 1.9 us <= 2000 ns
    (_MARLIN_CR20, "drv8825", [], "X", "step_high", "indeterminate"),
    (_MARLIN_CR20, "tmc2209", [], "X", "step_high", "pass"),  # 1250 ns >= 100 ns
    (_MARLIN_CR20, "drv8825", ["step_high=1250ns"], "X", "step_high", "pass"),  # worst == limit
    # Marlin 2.0.0 (stepper_pulse_phase_isr, MIN_PULSE_TICKS whole us): one tick, 500 ns short
    (_MARLIN_200, "drv8825", [], "X", "step_high", "indeterminate"),  # 1500 ns < 1.9 us
    (_MARLIN_200, "drv8825", ["step_high=1500ns"], "X", "step_high", "pass"),
    # Grbl_ESP32: RMT is exact (StandardStepper.cpp:69) but the I2S and software engines are not,
    # and a dump does not say which was built: no bound
    (_GRBL_ESP32, "a4988", [], "X", "step_high", "indeterminate"),
    # grbl 1.1: the pulse's value $0 - 562.5 ns is its lower bound (Timer0's prescaler phase,
    # stepper.c:241, 344-345): a clear PASS stays; the low time and the DIR hold are times
    # between stepper interrupts (stepper.c:319-336), which other interrupts may delay
    # (serial.c:107, 143): no bound
    (_GRBL, "a4988", [], "X", "step_high", "pass"),
    (_GRBL, "a4988", [], "X", "step_low", "indeterminate"),
    (_GRBL, "a4988", [], "X", "dir_hold", "indeterminate"),
    # RRF: an expansion board times T on its own step clock (Duet3Expansion SetDriverStepTiming)
    (_RRF_EXP, "tmc2209", [], "Z", "step_high", "indeterminate"),
    # ... the main board's drivers (P0.x) round T up to its step clocks: exact, a PASS stays
    (_RRF_EXP, "tmc2209", [], "X", "step_high", "pass"),
    # hm2 without --hm2-clock: dirsetup is truncated to whole clocks (stepgen.c 381-385)
    (_HM2, "a4988", [], "stepgen.00", "dir_setup", "indeterminate"),
    # ... steplen is held N + 1 clocks (kubstepgenz.vhd 210-211, 199-201): more than the set
    # value, no band: 1 us against 1 us passes
    (_HM2, "a4988", [], "stepgen.00", "step_high", "pass"),
    # FluidNC RMT: the pulse is 4 x pulse_us ticks of 0.25 us, exact: a clear PASS stays
    (_FLUIDNC, "a4988", [], "x", "step_high", "pass"),
]


@pytest.mark.parametrize(("case", "drive", "limits", "axis", "rule", "verdict"), CASES)
def test_real_files(
    case: str, drive: str, limits: list[str], axis: str, rule: str, verdict: str
) -> None:
    cfg = read_firmware(CORPUS / case)
    d = tune_drive(load_drive(drive), limits, None) if limits else load_drive(drive)
    result = evaluate_config(cfg, [(cfg.axis(axis), d)])
    row = next(r for r in result.pairs[0].rows if r.rule == rule)
    assert row.verdict == verdict, row.note
    if verdict == "indeterminate":  # a fix only where some value clears the band
        assert row.in_band and "measure it" in row.note
        assert bool(row.fix) == (row.worst_ns is not None), row.fix


@pytest.mark.parametrize(
    ("case", "section", "duration", "tick_ns", "limit_ns"),
    [
        # no chip named, pins that fit an ATmega: the slowest AVR clock is 8 MHz
        # (src/avr/Kconfig:87); 3.5 us is over the AVR fast path (40 ticks at 8 MHz)
        ("sample-multi-extruder.cfg", "extruder", "0.0000035", Fraction(125), 3400),
        # an STM32G0B1 (not AVR; its clock is not in the table): the slowest non-AVR clock Klipper
        # builds for is the RP2040's 12 MHz (src/rp2040/Kconfig:41)
        ("sample-bigtreetech-ebb-sb-canbus-v1.0.cfg", "extruder", "0.0000025",
         Fraction(250, 3), 2450),
    ],
)  # fmt: skip
def test_klipper_unknown_clock_is_one_tick_of_the_slowest(
    tmp_path: Path, case: str, section: str, duration: str, tick_ns: Fraction, limit_ns: int
) -> None:
    """Klipper truncates the duration to whole MCU ticks (klippy/stepper.py:112
    seconds_to_clock, klippy/mcu.py:1141 int(time * freq)). No corpus file leaves the clock
    unknown with a duration off whole us, so the corpus file gets a ``step_pulse_duration``."""
    src = CORPUS / "klipper" / case
    text = src.read_text().replace(
        f"[{section}]\n", f"[{section}]\nstep_pulse_duration: {duration}\n", 1
    )
    path = tmp_path / "printer.cfg"
    path.write_text(text)
    cfg = read_firmware(path)
    x = cfg.axis(section)
    assert (x.pulse.status, x.pulse.short_by) == ("uncertain", tick_ns), x.pulse.note
    d = tune_drive(load_drive("a4988"), [f"step_high={limit_ns}ns"], None)
    row = next(r for r in evaluate_config(cfg, [(x, d)]).pairs[0].rows if r.rule == "step_high")
    assert row.verdict == "indeterminate"  # the duration - a tick < the limit <= the duration
    d = tune_drive(load_drive("a4988"), ["step_high=2000ns"], None)
    row = next(r for r in evaluate_config(cfg, [(x, d)]).pairs[0].rows if r.rule == "step_high")
    assert row.verdict == "pass"  # a clear PASS stays


def test_fluidnc_timed_pulse_is_the_set_value(tmp_path: Path) -> None:
    """FluidNC TIMED (timed_engine.c:41-46): the pulse's end is a cycle count taken after the
    STEP write: at least pulse_us, no band; its low time loses an interrupted spin and a late
    interrupt: no bound.
    No corpus file uses TIMED, so a corpus file's engine is switched."""
    src = CORPUS / _FLUIDNC
    text = src.read_text()
    assert "engine: RMT" in text
    path = tmp_path / "config.yaml"
    path.write_text(text.replace("engine: RMT", "engine: TIMED"))
    x = read_firmware(path).axis("x")
    assert not x.pulse.banded and not x.dir_setup.banded
    assert x.idle.short_by is None and "timed_engine.c" in x.idle.short_why
    assert x.dir_hold.short_by is None  # DIR is written by the stepping interrupt too


def _marlin_capture(tmp_path: Path, width_ns: int) -> Path:
    starts = [1000 + k * 1_000_000 for k in range(5)]
    edges = [t for s in starts for t in (s, s + width_ns)]
    return write_vcd(tmp_path / "run.vcd", {"STEP": (0, edges), "DIR": (0, [])}, end=6_000_000)


@pytest.mark.parametrize(
    ("width_ns", "verdict"),
    [(2000, "pass"), (1300, "pass"), (1250, "pass"), (1200, "fail")],
)
def test_check_firmware_finds_only_below_the_band(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], width_ns: int, verdict: str
) -> None:
    """Marlin's 2000 ns pulse may be 750 ns short (stepper.cpp NS_TO_PULSE_TIMER_TICKS, 2 MHz):
    a measured 1.3 us pulse is inside what the firmware does, not a setting that did not take
    effect; 1.2 us (below 1.25 us by more than the 1 ns resolution) is."""
    folder = tmp_path / "cfg"
    shutil.copytree((CORPUS / _MARLIN_CR20).parent, folder)
    vcd = _marlin_capture(tmp_path, width_ns)
    main(["check", str(vcd), "--drive", "tmc2209", "--firmware", str(folder / "Configuration.h"),
          "--firmware-axis", "STEP=X", "--format", "json", "-q"])  # fmt: skip
    doc = json.loads(capsys.readouterr().out)
    pulse = next(c for c in doc["firmware"]["comparisons"] if c["what"] == "pulse")
    assert pulse["verdict"] == verdict, pulse["message"]
    assert (pulse["configured"], pulse["short_by"], pulse["short_bounded"]) == (2000, 750, True)


@pytest.mark.parametrize(
    ("case", "figure", "short_by", "bounded"),
    [
        (_MARLIN_CR20, "pulse_ns", 750, True),  # 1.5 ticks of the 2 MHz pulse timer
        (_MARLIN_CR20, "dir_setup_ns", 0, True),  # a DELAY_NS: no band
        (_GRBL_ESP32, "pulse_ns", None, False),  # the engine built in is not in the dump
    ],
)
def test_json_shows_the_band_beside_the_figure(
    capsys: pytest.CaptureFixture[str], case: str, figure: str, short_by: int | None, bounded: bool
) -> None:
    main(["config", str(CORPUS / case), "--drive", "a4988", "--format", "json"])
    doc = json.loads(capsys.readouterr().out)
    fig = doc["axes"][0][figure]
    assert (fig["short_by"], fig["short_bounded"]) == (short_by, bounded)
    assert bool(fig["short_why"]) == (short_by != 0)
    main(["config", str(CORPUS / case), "--drive", "a4988"])
    text = capsys.readouterr().out
    assert "? = the firmware may fall short of it" in text
