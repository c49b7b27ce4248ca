"""Klipper (84104bb) for an ATmega644P at 16 MHz on the simulated MCU, run as a user runs it
(``wavecheck simulate klipper``), each figure measured on the VCD with this folder's own reader
and derived apart: from the G-code and printer.cfg (steps), from the disassembly (avr-objdump) and
Klipper's source (pulse widths, the DIR change)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from tests.wavecheck.mcu.helpers import (
    KLIPPER_SRC,
    REPO,
    SIMAVR_SRC,
    function_code,
    high_widths,
    rising,
    vcd_changes,
)
from wavecheck.cli import main

#: Klipper built and simulated end to end (make test-all and CI run it; make test leaves it out)
pytestmark = pytest.mark.slow

DOCS = REPO / "docs" / "klipper"
CONFIG = DOCS / "printer.cfg"
#: 600 moves of 0.8 mm along X, each a reversal; printer.cfg: 16 microsteps x 200 / 40 mm
STEPS_PER_MM = 16 * 200 // 40
ZIGZAG_STEPS = 600 * 8 * STEPS_PER_MM // 10


def simulate(tmp: Path, gcode: Path, drive: str, *extra: str, name: str = "run"):
    vcd, report = tmp / f"{name}.vcd", tmp / f"{name}.json"
    code = main(
        ["simulate", "klipper", "--config", str(CONFIG), "--gcode", str(gcode), "--vcd", str(vcd)]
        + ["--drive", drive, "--klipper-src", str(KLIPPER_SRC), "--simavr-src", str(SIMAVR_SRC)]
        + ["--format", "json", "-o", str(report), *extra]
    )
    return code, vcd, json.loads(report.read_text()) if report.exists() else {}


@pytest.fixture(scope="module")
def zigzag(klipper_build, klippy, runner, tmp_path_factory):
    """The zigzag simulated once for the module: exit code, VCD, report (Gecko G202)."""
    tmp = tmp_path_factory.mktemp("zigzag")
    return simulate(tmp, DOCS / "zigzag.gcode", "gecko-g202")


#: Cycles of the instructions of Klipper's step path (Atmel AVR Instruction Set Manual, AVRe+
#: core of the ATmega644P; a branch taken costs 2).
CYCLES = {"st": 2, "ldd": 2, "std": 2, "sbiw": 2, "brne": 2, "add": 1, "adc": 1}


def step_pulse_cycles(elf: Path) -> int:
    """The step pulse from the code: the timer interrupt (__vector_13, TIMER1_COMPA) runs the
    stepper's event inline (CONFIG_INLINE_STEPPER_HACK); stepper_event_avr (src/stepper.c:158-176)
    toggles the step pin (an ST to the PIN register: gpio_out_toggle_noirq), counts, adds the
    interval to the wake time and toggles it again. From the first ST through the instructions
    before the second, the count not being 0: the BRNE over the RJMP to stepper_load_next is
    taken (2 cycles) and the RJMP skipped."""
    code = function_code(elf, "__vector_13")
    toggles = [k for k, (m, o) in enumerate(code) if m == "st" and o.startswith("Z,")]
    k, total = toggles[0], 0
    while k < toggles[1]:
        mnemonic, operands = code[k]
        total += CYCLES[mnemonic]
        k += 2 if (mnemonic, operands) == ("brne", ".+2") else 1
    assert code[toggles[0] + 4 : toggles[0] + 6] == [("brne", ".+2"), ("rjmp", ".+416")]
    return total


def test_the_step_pulse_is_42_cycles_in_the_code_and_klipper_asks_40(klipper_build):
    elf, _ = klipper_build
    assert step_pulse_cycles(elf) == 42
    # src/stepper.c: "#define AVR_STEP_TICKS 40 // minimum instructions between step gpio pulses"
    source = (KLIPPER_SRC / "src" / "stepper.c").read_text()
    assert "#define AVR_STEP_TICKS 40" in source


def test_every_step_arrives_and_the_pulses_are_the_codes(zigzag, klipper_build):
    code, vcd, report = zigzag
    changes, _ = vcd_changes(vcd)
    assert len(rising(changes["X_STEP"])) == ZIGZAG_STEPS == 38_400
    widths = high_widths(changes["X_STEP"])
    short = step_pulse_cycles(klipper_build[0])
    assert min(widths) == short == 42  # 2.625 us
    assert report["steps"]["count"] == 38_400  # the engine's count agrees


def test_the_last_pulse_of_each_queued_move_is_long_and_dir_changes_inside_it(zigzag):
    _, vcd, _ = zigzag
    changes, _ = vcd_changes(vcd)
    step, direction = changes["X_STEP"], changes["X_DIR"]
    rises = rising(step)
    widths = high_widths(step)
    # stepper_event_avr calls stepper_load_next between its two toggles when the move's count
    # is done (src/stepper.c:173-174), and stepper_load_next toggles DIR there when the next
    # move reverses (stepper.c:125-127); after the job's last step the queue is empty and
    # stepper_load_next returns at once (stepper.c:65-69)
    assert widths[-1] == 107
    long = [w for w in widths[:-1] if w != 42]
    assert min(long) == 248 and max(long) == 270  # 15.5 .. 16.875 us
    dir_times = [t for t, _ in direction[1:]]
    assert len(dir_times) == 600  # one change per move: set before the first, then 599 reversals
    dir_times = dir_times[1:]
    highs = list(zip(rises, [r + w for r, w in zip(rises, widths, strict=True)], strict=True))
    inside = [any(a < t < b for a, b in highs) for t in dir_times]
    assert all(inside)


def test_a_falling_edge_drive_fails_and_counts_two_steps_off(zigzag):
    code, _, report = zigzag
    assert code == 1
    text = json.dumps(report)
    assert '"step_high"' in text
    steps = report["steps"]
    # the job ends where it began, but at each reversal the G202 takes the move's last step
    # (DIR already changed at its falling edge) the other way: 300 out, 299 back
    assert steps["count"] == 38_400 and steps["final_position"] == 2


def test_a_rising_edge_drive_counts_right_and_passes(klipper_build, klippy, runner, tmp_path):
    code, _, report = simulate(tmp_path, DOCS / "zigzag.gcode", "drv8825")
    assert code == 0 and report["steps"]["final_position"] == 0


def test_a_rerun_gives_the_same_vcd(zigzag, tmp_path):
    _, first, _ = zigzag
    code, again, _ = simulate(tmp_path, DOCS / "zigzag.gcode", "gecko-g202", name="again")
    assert code == 1 and again.read_bytes() == first.read_bytes()


def test_the_atmega2560_build(klippy, runner, tmp_path, capsys):
    """The same job on an ATmega2560 build (--kconfig): every step, the same 42-cycle pulse
    (the step path has no call), and the long pulses 2 cycles longer than the 644P's: with its
    3-byte PC, CALL and RET to stepper_load_next take 5 cycles each, not 4 (AVR Instruction Set
    Manual, CALL and RET)."""
    cfg = DOCS / "printer-mega2560.cfg"
    vcd, report = tmp_path / "mega.vcd", tmp_path / "mega.json"
    code = main(
        ["simulate", "klipper", "--config", str(cfg), "--gcode", str(DOCS / "zigzag.gcode")]
        + ["--kconfig", str(DOCS / "mega2560.config"), "--vcd", str(vcd), "--drive", "drv8825"]
        + ["--klipper-src", str(KLIPPER_SRC), "--simavr-src", str(SIMAVR_SRC)]
        + ["--format", "json", "-o", str(report)]
    )
    assert code == 0
    err = capsys.readouterr().err
    assert "atmega2560" in err and "the MCU has 645 move-queue slots" in err  # docs: 645
    changes, _ = vcd_changes(vcd)
    widths = high_widths(changes["X_STEP"])
    assert len(widths) == ZIGZAG_STEPS and min(widths) == 42
    long = [w for w in widths[:-1] if w != 42]
    assert min(long) == 248 + 2 and max(long) == 270 + 2


def test_one_move_there_and_back(klippy, klipper_build, runner, tmp_path):
    """G1 X110 and back: 2 x 10 mm x 80 steps/mm; one reversal, so the G202 ends 2 steps off."""
    code, vcd, report = simulate(tmp_path, DOCS / "there-and-back.gcode", "gecko-g202")
    changes, _ = vcd_changes(vcd)
    assert len(rising(changes["X_STEP"])) == 2 * 10 * STEPS_PER_MM == 1600
    assert code == 1 and report["steps"]["final_position"] == 2
