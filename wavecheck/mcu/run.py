"""Run a firmware ELF on the patched simavr (``wavecheck-avr``, a separate GPL process).

What goes in: the ELF, the MCU and its clock, the pins to record, the lines to send over the UART
after the banner. What comes out: the VCD (written as the simulation goes, renamed into place only
when the run ends well) and every line the firmware printed, with its cycle.
"""

from __future__ import annotations

import os
import struct
import subprocess
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

from wavecheck.errors import ConfigError, UsageError
from wavecheck.output import atomic_path

__all__ = ["MCUS", "Mcu", "Printed", "SimRun", "check_elf", "simulate"]


@dataclass(frozen=True)
class Mcu:
    """An AVR the simulation runs: simavr's core name, the ELF ``e_flags`` architecture
    (avr-gcc's ``-mmcu`` family) and the flash size, for refusing an ELF built for another."""

    core: str
    arch: int
    flash_bytes: int


#: avr-libc's families: avr5 for the ATmega328P/644P, avr6 for the ATmega2560 (ELF e_flags & 0x7f).
MCUS = {
    "atmega328p": Mcu("atmega328p", 5, 32 * 1024),
    "atmega644p": Mcu("atmega644p", 5, 64 * 1024),
    "atmega2560": Mcu("atmega2560", 6, 256 * 1024),
}
_EM_AVR = 83
_PT_LOAD = 1
#: Lines of firmware output kept (a firmware that prints forever is bounded by the cycle limit
#: and this).
_MAX_LINES = 100_000


@dataclass(frozen=True)
class Printed:
    """A line the firmware printed on its UART and the cycle its newline arrived at."""

    cycle: int
    text: str


@dataclass(frozen=True)
class SimRun:
    """The outcome of one simulation: how it ended (``done``, ``limit``, ``nobanner``,
    ``alarm``; in block mode ``noanswer``, ``stop``, ``nak``), at which cycle of the MCU's
    clock, and what the firmware printed (lines, or in block mode its blocks in hex)."""

    end: str
    end_cycle: int
    printed: tuple[Printed, ...]
    clock_hz: int


def check_elf(path: Path, mcu: str) -> None:
    """Refuse a file that is not a 32-bit little-endian AVR ELF for ``mcu``'s family, or that
    does not fit its flash.

    Raises:
        UsageError: with the file, what it is and what was expected.
    """
    want = MCUS[mcu]
    try:
        data = path.read_bytes()
    except OSError as err:
        raise UsageError(f"{path}: cannot read the ELF: {err.strerror}") from None
    if data[:4] != b"\x7fELF" or len(data) < 52 or data[4] != 1 or data[5] != 1:
        raise UsageError(f"{path}: not a 32-bit little-endian ELF (an AVR firmware is one)")
    (machine,) = struct.unpack_from("<H", data, 18)
    (flags,) = struct.unpack_from("<I", data, 36)
    if machine != _EM_AVR:
        raise UsageError(
            f"{path}: an ELF for machine {machine}, not an AVR ({_EM_AVR}): build it with avr-gcc"
        )
    if flags & 0x7F != want.arch:
        raise UsageError(
            f"{path}: built for the avr{flags & 0x7F} family, but the {mcu} is avr{want.arch}: "
            f"build it with -mmcu={mcu}"
        )
    phoff, _, _, _, phentsize, phnum = struct.unpack_from("<IIHHHH", data, 28)
    flash = 0
    for k in range(phnum):
        off = phoff + k * phentsize
        if off + 32 > len(data):
            raise UsageError(f"{path}: program header {k} lies past the end of the file")
        ptype, _, _, paddr, filesz = struct.unpack_from("<IIIII", data, off)
        if ptype == _PT_LOAD and paddr < 0x800000:  # the AVR's flash address space
            flash = max(flash, paddr + filesz)
    if flash > want.flash_bytes:
        raise UsageError(
            f"{path}: {flash} bytes of flash, more than the {mcu}'s {want.flash_bytes}"
        )


def simulate(
    runner: Path,
    elf: Path,
    mcu: str,
    clock_hz: int,
    vcd: str,
    pins: dict[str, str],
    banner: str,
    lines: list[str],
    max_cycles: int,
    tail_cycles: int,
    wall_timeout_s: float,
    accept: Callable[[SimRun], object],
    options: Sequence[str] = (),
) -> SimRun:
    """Run ``elf`` and write the ``pins`` (name → ``PORT.BIT``) to ``vcd``.

    ``accept(run)`` judges the run (raising an error to refuse it) before the VCD is renamed
    into place: a refused run leaves no VCD. ``options`` go to the runner as they are (its
    block mode for Klipper: ``--blocks=ADDR``, ``--start=``, ``--until=``, ``--stop=HEX``).

    Raises:
        ConfigError: the simulation exceeded ``wall_timeout_s``, or the runner refused its input.
    """
    cmd = [str(runner), str(elf), MCUS[mcu].core, str(clock_hz), "", banner]
    cmd += [str(max_cycles), str(tail_cycles)] + [f"{n}={p}" for n, p in pins.items()]
    cmd += list(options)
    with atomic_path(vcd) as tmp:
        cmd[4] = os.fspath(tmp)
        proc = subprocess.Popen(
            cmd,
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        try:
            out, err = proc.communicate("".join(f"{ln}\n" for ln in lines), wall_timeout_s)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.communicate()
            raise ConfigError(
                f"{elf}: the simulation ran over {wall_timeout_s:g} s of wall time "
                "(raise --timeout, or shorten the job)"
            ) from None
        if proc.returncode:
            msg = (err.strip().splitlines() or [f"exit status {proc.returncode}"])[-1]
            raise ConfigError(f"{elf}: the simulator refused it: {msg}")
        printed = []
        end, end_cycle = "crashed", 0
        for raw in out.splitlines()[:_MAX_LINES]:
            head, _, rest = raw.partition(" ")
            if head == "END":
                word, _, cyc = rest.partition(" ")
                end, end_cycle = word, int(cyc)
            elif head.isdigit():
                printed.append(Printed(int(head), rest))
        if end == "crashed":
            raise ConfigError(
                f"{elf}: the simulated MCU stopped (invalid instruction or sleep with interrupts "
                f"off) at cycle {end_cycle}"
            )
        run = SimRun(end, end_cycle, tuple(printed), clock_hz)
        accept(run)
    return run
