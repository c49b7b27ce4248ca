"""Helpers of the MCU-simulation tests: sources, builds, a VCD reader of their own (not
wavecheck's: the figures are measured independently of the engine), and AVR cycle counting from
the disassembly."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
from collections.abc import Sequence
from fractions import Fraction
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[3]
SRC = REPO.parent / "shared" / "firmware-src"
GRBL_SRC = SRC / "grbl-1.1h"
SIMAVR_SRC = SRC / "simavr"
KLIPPER_SRC = SRC / "klipper"
CLOCK_HZ = 16_000_000


def need_sources(firmware: Path = GRBL_SRC) -> None:
    """Skip locally, fail in CI, when the firmware sources or avr-gcc are missing."""
    missing = [str(p) for p in (firmware, SIMAVR_SRC) if not p.is_dir()]
    missing += [t for t in ("avr-gcc", "avr-objdump", "gcc", "make") if not shutil.which(t)]
    if missing:
        if os.environ.get("CI"):
            pytest.fail(f"missing for the MCU simulation: {missing}")
        pytest.skip(f"missing for the MCU simulation: {missing}")


def build_avr(tmp: Path, name: str, source: str, mcu: str = "atmega328p", **defines: int) -> Path:
    """Compile a one-file AVR program with avr-gcc."""
    c = tmp / f"{name}.c"
    c.write_text(source)
    elf = tmp / f"{name}.elf"
    cmd = ["avr-gcc", f"-mmcu={mcu}", "-Os", f"-DF_CPU={CLOCK_HZ}UL", "-o", str(elf), str(c)]
    cmd += [f"-D{k}={v}" for k, v in defines.items()]
    subprocess.run(cmd, check=True, capture_output=True)
    return elf


def run_avr(
    runner: Path,
    elf: Path,
    vcd: Path,
    pins: Sequence[str],
    *,
    lines: Sequence[str] = (),
    banner: str = "",
    max_cycles: int = 10_000_000,
    tail_cycles: int = 20_000,
) -> list[str]:
    """Run the runner directly; returns its stdout lines."""
    cmd = [str(runner), str(elf), "atmega328p", str(CLOCK_HZ), str(vcd), banner]
    cmd += [str(max_cycles), str(tail_cycles), *pins]
    done = subprocess.run(
        cmd, input="".join(f"{ln}\n" for ln in lines), capture_output=True, text=True, check=True
    )
    return done.stdout.splitlines()


def vcd_changes(path: Path) -> tuple[dict[str, list[tuple[int, int]]], Fraction]:
    """Signal name → [(time in cycles, value)], and the cycle in seconds. Reads the VCD the
    runner writes (one timescale, scalar signals) with nothing of wavecheck's."""
    text = path.read_text()
    unit = re.search(r"\$timescale\s+(\d+)\s*(\w+)\s+\$end", text)
    assert unit
    scale = {"fs": 15, "ps": 12, "ns": 9, "us": 6, "ms": 3, "s": 0}[unit.group(2)]
    tick = Fraction(int(unit.group(1)), 10**scale)
    per_cycle = Fraction(1, CLOCK_HZ) / tick
    assert per_cycle.denominator == 1
    ids = dict(re.findall(r"\$var wire 1 (\S+) (\S+) \$end", text))
    out: dict[str, list[tuple[int, int]]] = {n: [] for n in ids.values()}
    t = 0
    for line in text.split("$enddefinitions $end", 1)[1].splitlines():
        if line.startswith("#"):
            t = int(line[1:])
            assert t % per_cycle.numerator == 0, "a change between two cycles"
        elif line[:1] in ("0", "1") and line[1:] in ids:
            out[ids[line[1:]]].append((t // per_cycle.numerator, int(line[0])))
    return out, Fraction(1, CLOCK_HZ)


def high_widths(changes: list[tuple[int, int]]) -> list[int]:
    """Every high time of a signal, in cycles."""
    out, rise = [], None
    for t, v in changes:
        if v and rise is None:
            rise = t
        elif not v and rise is not None:
            out.append(t - rise)
            rise = None
    return out


def rising(changes: list[tuple[int, int]]) -> list[int]:
    return [
        t
        for (t, v), prev in zip(changes, [(0, 0), *changes[:-1]], strict=True)
        if v and not prev[1]
    ]


#: Cycles of the ATmega328P's instructions that grbl's interrupt handlers use (Atmel AVR
#: Instruction Set Manual, per instruction; the 328P has a 2-byte PC). A branch counts as not taken.
CYCLES = {
    "push": 2, "pop": 2, "in": 1, "out": 1, "eor": 1, "lds": 2, "sts": 2, "andi": 1, "ori": 1,
    "or": 1, "and": 1, "ldi": 1, "mov": 1, "movw": 1, "sei": 1, "cli": 1, "cpse": 1, "nop": 1,
    "jmp": 3, "rjmp": 2,
}  # fmt: skip


def function_code(elf: Path, name: str) -> list[tuple[str, str]]:
    """[(mnemonic, operands)] of a function in the ELF's disassembly (avr-objdump)."""
    dis = subprocess.run(
        ["avr-objdump", "-d", str(elf)], check=True, capture_output=True, text=True
    ).stdout
    body = dis.split(f"<{name}>:\n", 1)[1].split("\n\n", 1)[0]
    out = []
    for line in body.splitlines():
        parts = line.split("\t")
        if len(parts) >= 3:
            out.append((parts[2].strip(), parts[3].split(";")[0].strip() if len(parts) > 3 else ""))
    return out


def cycles(code: list[tuple[str, str]]) -> int:
    """Cycles of a straight run of instructions."""
    return sum(CYCLES[m] for m, _ in code)
