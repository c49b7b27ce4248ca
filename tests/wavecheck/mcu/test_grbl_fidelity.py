"""grbl 1.1h on the simulated ATmega328P, run as a user runs it (``wavecheck simulate grbl``),
each figure measured on the VCD with this folder's own reader and derived apart: cycle counts
from grbl's disassembly (avr-objdump) and its source (``grbl/stepper.c``)."""

from __future__ import annotations

import json
from fractions import Fraction
from pathlib import Path

import pytest

from tests.wavecheck.mcu.conftest import delay_config_h
from tests.wavecheck.mcu.helpers import (
    GRBL_SRC,
    SIMAVR_SRC,
    cycles,
    function_code,
    high_widths,
    rising,
    vcd_changes,
)
from wavecheck.cli import main

#: grbl simulated end to end (make test-all and CI run it; make test leaves it out)
pytestmark = pytest.mark.slow

#: G1 X10 and back along X (G90).
THERE_AND_BACK = "G1 X10 F500\nG1 X0\n"
#: Five X reversals at speed: X is the axis with more than half the steps of the dominant Y, so
#: its step comes on the first interrupt of each block (AMASS level 0 at > 8 kHz).
ZIGZAG = "G91\n" + "G1 X1 Y1.5 F6000\nG1 X-1 Y1.5\n" * 3
FAST = "$100=400\n$101=400\n$110=6000\n$111=6000\n$120=1000\n$121=1000\n$11=0.2\n"


def simulate(
    tmp: Path, settings: str, gcode: str, drive: str, *extra: str, name: str = "run"
) -> tuple[int, Path, dict]:
    s, g = tmp / f"{name}.txt", tmp / f"{name}.nc"
    s.write_text(settings)
    g.write_text(gcode)
    vcd, report = tmp / f"{name}.vcd", tmp / f"{name}.json"
    code = main(
        ["simulate", "grbl", "--settings", str(s), "--gcode", str(g), "--vcd", str(vcd)]
        + ["--drive", drive, "--grbl-src", str(GRBL_SRC), "--simavr-src", str(SIMAVR_SRC)]
        + ["--format", "json", "-o", str(report), *extra]
    )
    return code, vcd, json.loads(report.read_text()) if report.exists() else {}


def pulse_bounds(elf: Path, pulse_us: int) -> tuple[int, int]:
    """The step pulse in cycles, from the code: Timer1's handler (__vector_11) writes STEP_PORT
    (the second OUT to PORTD, 0x0b; stepper.c:336), then TCNT0 (0x26) = step_pulse_time
    = -((($0 - 2) * 16) >> 3) (stepper.c:241) and TCCR0B (0x25) = clk/8 (stepper.c:344-345).
    The first count comes 1..8 cycles later (free-running prescaler), the overflow after
    256 - TCNT0 counts; 4 cycles of interrupt response, the vector's JMP (3), and Timer0's
    overflow handler (__vector_16) up to its OUT to PORTD (stepper.c:492)."""
    compa = function_code(elf, "__vector_11")
    outs = [k for k, (m, o) in enumerate(compa) if m == "out" and o.startswith("0x0b")]
    start = next(k for k, (m, o) in enumerate(compa) if m == "out" and o.startswith("0x25"))
    a = cycles(compa[outs[1] : start])
    ovf = function_code(elf, "__vector_16")
    p = cycles(ovf[: next(k for k, (m, o) in enumerate(ovf) if m == "out")])
    counts = 256 - ((-(((pulse_us - 2) * 16) >> 3)) & 0xFF)
    low = a + 1 + 8 * (counts - 1) + 4 + 3 + p
    return low, low + 7


def test_dir_is_written_six_cycles_before_step_in_the_code(grbl: Path):
    compa = function_code(grbl, "__vector_11")
    outs = [k for k, (m, o) in enumerate(compa) if m == "out" and o.startswith("0x0b")]
    assert cycles(compa[outs[0] : outs[1]]) == 6  # DIRECTION_PORT (stepper.c:324) → STEP_PORT


@pytest.mark.parametrize(
    "pulse_us, cycles_issue, us_issue",
    [(3, (39, 46), None), (10, None, (Fraction("9.44"), Fraction("9.94")))],
)
def test_step_pulse_width(grbl, tmp_path, pulse_us, cycles_issue, us_issue):
    low, high = pulse_bounds(grbl, pulse_us)
    code, vcd, report = simulate(tmp_path, f"$0={pulse_us}\n" + FAST, ZIGZAG, "a4988")
    assert code == 0
    widths = high_widths(vcd_changes(vcd)[0]["X_STEP"])
    assert len(widths) == 2400 == report["steps"]["count"]
    # one more cycle: the overflow may fall in the first cycle of a 2-cycle instruction
    assert low <= min(widths) and max(widths) <= high + 1, (low, high, sorted(set(widths)))
    if cycles_issue:  # $0=3: 39–46 cycles
        assert (low, high) == cycles_issue
        assert set(widths) <= set(range(39, 47))
    if us_issue:  # $0=10: 9.44–9.94 us, as the issue rounds them (151 cycles = 9.4375 us)
        shortest, longest = (round(Fraction(w, 16), 2) for w in (min(widths), max(widths)))
        assert us_issue[0] <= shortest and longest <= us_issue[1]


def test_there_and_back_makes_every_step(grbl, tmp_path):
    code, vcd, report = simulate(
        tmp_path, "$100=250\n$110=500\n$120=10\n", THERE_AND_BACK, "drv8825"
    )
    assert code == 0
    changes = vcd_changes(vcd)[0]
    assert len(rising(changes["X_STEP"])) == 5000  # 10 mm x 250 steps/mm, twice
    assert report["steps"]["count"] == 5000 and report["steps"]["final_position"] == 0
    assert rising(changes["Y_STEP"]) == [] and rising(changes["Z_STEP"]) == []


def _dir_setups(vcd: Path) -> list[int]:
    changes = vcd_changes(vcd)[0]
    steps = rising(changes["X_STEP"])
    out = []
    for t, _ in changes["X_DIR"][1:]:
        nxt = [s for s in steps if s >= t]
        if nxt:
            out.append(nxt[0] - t)
    return out


def test_reversal_at_speed_fails_a_drv8825_and_passes_an_a4988(grbl, tmp_path):
    code, vcd, report = simulate(tmp_path, "$0=10\n" + FAST, ZIGZAG, "drv8825", name="drv")
    assert _dir_setups(vcd) == [6] * 5  # 375 ns at each of the 5 reversals
    assert code == 1
    rule = next(r for r in report["rules"] if r["id"] == "dir_setup")
    assert (rule["verdict"], rule["violations"], rule["limit_ns"]) == ("fail", 5, 650)
    code, _, report = simulate(tmp_path, "$0=10\n" + FAST, ZIGZAG, "a4988", name="a4988")
    assert code == 0 and report["verdict"] == "pass"


def test_step_pulse_delay_build_gives_the_dir_setup(tmp_path):
    config_h = tmp_path / "config.h"
    config_h.write_bytes(delay_config_h())
    code, vcd, report = simulate(
        tmp_path, "$0=10\n" + FAST, ZIGZAG, "drv8825", "--config-h", str(config_h)
    )
    setups = _dir_setups(vcd)
    assert len(setups) == 5 and min(setups) >= 10 * 16  # STEP_PULSE_DELAY 10 us (config.h:425)
    rule = next(r for r in report["rules"] if r["id"] == "dir_setup")
    assert rule["verdict"] == "pass"
    assert code == 0


def test_a_rerun_gives_a_byte_identical_vcd(grbl, tmp_path):
    runs = [
        simulate(tmp_path, "$0=3\n" + FAST, ZIGZAG, "a4988", name=f"run{k}")[1].read_bytes()
        for k in range(2)
    ]
    assert runs[0] == runs[1] and len(runs[0]) > 10_000
