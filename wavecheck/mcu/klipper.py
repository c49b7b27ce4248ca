"""Klipper on a simulated AVR: its build, its host's batch output made fit for a fresh MCU, its pins.

The host (klippy, run as a separate process in batch mode: ``klippy.py printer.cfg -i job.gcode
-o job.serial -d klipper.dict``) turns the G-code into the message blocks it would send. Facts
from Klipper's source (Klipper3d/klipper 84104bb) that decide how they are fed to the MCU:
- batch mode numbers its blocks from 1 (``klippy/chelper/serialqueue.c:736``, ``send_seq = 1``); a
  freshly reset MCU expects 0 (``src/command.c:16``, ``next_sequence = MESSAGE_DEST``) and
  discards the others: the blocks are numbered anew from 0;
- batch mode assumes the MCU has 500 move-queue slots (``klippy/mcu.py:1036-1038``), but the MCU
  has what its RAM leaves (``src/basecmd.c:170-177``: ``alloc_chunks``), and a command that finds
  no free slot shuts it down (``basecmd.c:88-90``, "Move queue overflow"). Each
  ``queue_step`` (``src/stepper.c:259-262``), ``queue_digital_out``
  (``src/gpiocmds.c:148``) and ``queue_pwm_out`` (``src/pwmcmds.c:86``) takes one; the runner
  sends a block only when the MCU's free list (``basecmd.c:61``, ``move_free_list``) holds as
  many as the block needs;
- nothing is sent in the first 10 ms: Klipper enables its UART's receiver while it starts
  (``src/avr/serial.c:56-62``, ``serial_init``), and simavr drops a byte that comes before;
- the MCU's clock is Timer1 at clk/1 (``src/avr/timer.c:100``), so a clock in a command is a CPU
  cycle; a stepper's first step comes ``interval`` after its last step time (0 after
  ``config_stepper``, or the ``reset_step_clock`` clock), each next one ``interval + k*add`` later
  (``src/stepper.c:63-127,259-285``): the job's last event is known from the blocks.
"""

from __future__ import annotations

import configparser
import os
import re
import subprocess
import sys
import tempfile
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from wavecheck.errors import ConfigError, UsageError
from wavecheck.mcu.klipper_msg import Dictionary, Message, decode_block, pack, split_blocks
from wavecheck.mcu.run import MCUS, SimRun, simulate

__all__ = [
    "BATCH_MOVE_SLOTS",
    "DEFAULT_KCONFIG",
    "Job",
    "Stepper",
    "batch",
    "build",
    "free_list_address",
    "job",
    "outcome",
    "pins",
    "run",
    "steppers",
]

#: The build wavecheck makes when no .config is given: an ATmega644P at 16 MHz, serial on
#: USART0 at 250000 baud (Klipper's defaults for it: src/avr/Kconfig, src/Kconfig).
DEFAULT_KCONFIG = b"CONFIG_MACH_AVR=y\nCONFIG_MACH_atmega644p=y\nCONFIG_AVR_FREQ_16000000=y\n"
#: The move-queue slots klippy's batch mode assumes (klippy/mcu.py:1036-1038).
BATCH_MOVE_SLOTS = 500
#: Commands that take a move-queue slot (see the module's docstring).
MOVE_COMMANDS = frozenset({"queue_step", "queue_digital_out", "queue_pwm_out"})
#: The MCU's shutdown reports (``src/sched.c:310,318``): after them it makes no step.
STOP_RESPONSES = ("shutdown", "is_shutdown")
#: The symbol of the MCU's free-list head (``src/basecmd.c:61``); LTO adds a suffix.
FREE_LIST = "move_free_list"
#: klippy's batch mode under a wrapper that lets its serial queue drain before exit (GPL-3.0).
KLIPPY_BATCH = Path(__file__).resolve().parent / "simavr" / "klippy_batch.py"
#: The line wavecheck adds after the job: klippy logs its answer ("toolhead: X:…",
#: klippy/extras/gcode_move.py:261-290; klippy/gcode.py:250-253 logs what it answers), which
#: shows that it read the job to its end.
SENTINEL = "GET_POSITION"
_SENTINEL_ANSWER = re.compile(r"^toolhead: X:", re.M)
#: klippy batch runs tried before the job is refused for a dropped end.
_KLIPPY_TRIES = 3
#: Hints for the MCU's shutdown reasons (``static_string_id``) a simulation can cause.
_SHUTDOWN_HINTS = {
    "Move queue overflow": ": more moves in flight than the MCU's move queue holds",
    "Timer too close": ": the MCU could not keep up with the step rate",
    "Rescheduled timer in the past": ": the MCU could not keep up with the step rate",
}


@dataclass(frozen=True)
class Stepper:
    """A stepper of printer.cfg: its section and its pins (``PORT.BIT``), the enable's polarity."""

    section: str
    name: str
    step: str
    dir: str
    enable: str | None
    enable_active_low: bool


@dataclass(frozen=True)
class Job:
    """The blocks to send (renumbered, with the move slots each takes) and what they command."""

    blocks: tuple[bytes, ...]
    needs: tuple[int, ...]
    last_event: int  # the MCU clock of the last step or scheduled output
    steps: dict[int, int]  # oid -> steps commanded
    stop_prefixes: tuple[bytes, ...]

    def lines(self) -> list[str]:
        """The runner's input: ``NEED HEX`` per block."""
        return [f"{n} {b.hex()}" for n, b in zip(self.needs, self.blocks, strict=True)]


_PIN = re.compile(r"^[\^~!\s]*(?:(\w+)\s*:\s*)?[\^~!\s]*P([A-L])([0-7])\s*$", re.I)


def _pin(value: str, where: str) -> tuple[str, bool]:
    m = _PIN.match(value)
    if m is None or (m.group(1) or "mcu").lower() != "mcu":
        raise UsageError(
            f"{where}: pin '{value}': expected an AVR pin of the main MCU, e.g. PD7 or !PD6"
        )
    return f"{m.group(2).upper()}.{m.group(3)}", "!" in value


def steppers(config: Path) -> list[Stepper]:
    """The steppers of a Klipper printer.cfg (``[stepper_*]`` and ``[extruder*]`` sections).

    Raises:
        UsageError: unreadable, not INI, no stepper, a pin that is not one of the MCU's.
    """
    parser = configparser.RawConfigParser(
        strict=False, inline_comment_prefixes=("#", ";"), delimiters=(":", "=")
    )
    try:
        parser.read_string(config.read_text(encoding="utf-8"), str(config))
    except OSError as err:
        raise UsageError(f"{config}: cannot read it: {err.strerror}") from None
    except (configparser.Error, UnicodeDecodeError) as err:
        first = str(err).splitlines()[0]
        raise UsageError(f"{config}: not a Klipper config: {first}") from None
    out = []
    for section in parser.sections():
        kind = section.split(" ")[0]
        if not (kind.startswith("stepper_") or kind.startswith("extruder")):
            continue
        if not parser.has_option(section, "step_pin"):
            continue
        where = f"{config} [{section}]"
        step, _ = _pin(parser.get(section, "step_pin"), where)
        direction, _ = _pin(parser.get(section, "dir_pin", fallback=""), where)
        enable, low = None, False
        if parser.has_option(section, "enable_pin"):
            enable, low = _pin(parser.get(section, "enable_pin"), where)
        name = kind.removeprefix("stepper_").replace("extruder", "e").upper()
        out.append(Stepper(section, name, step, direction, enable, low))
    if not out:
        raise UsageError(f"{config}: no [stepper_*] or [extruder] section with a step_pin")
    return out


def batch(
    klippy: Path,
    config: Path,
    gcode: Path,
    dictionary: Path,
    timeout_s: float = 600.0,
    decoder: Dictionary | None = None,
) -> bytes:
    """klippy's batch output for the job (the blocks it would send to the MCU).

    klippy logs to its standard error with each message's level (no ``-l``: klippy/klippy.py
    then sets up Python's logging as it is): a G-code error is a WARNING
    (``klippy/gcode.py:255-262``, ``_respond_error``), a config error an ERROR ("Config error",
    then the traceback). klippy's exit status is not enough: an error raised while the end of
    the input is being read still exits 0. klippy ignores a command it does not know (it logs
    ``Unknown command:"FOO"`` as information); wavecheck refuses the job instead.

    klippy runs under :data:`KLIPPY_BATCH` (GPL, beside the simavr runner), which lets its serial
    queue write what it holds before exit: on a busy machine klippy's batch output lacked the
    end of the job (24,847 of a zigzag's 38,400 steps, 2 runs in about 40) or everything after
    the configuration (3 of 18 runs of a one-move job, 6 at a time), with its log showing the
    whole job and exit status 0. An output is taken only if it reaches klippy's exit: klippy
    logged the answer to :data:`SENTINEL`, added after the job's last line, and (with
    ``decoder``) the output ends with what klippy sends at exit (:func:`_ends_at_exit`). Else
    the run is repeated, at most :data:`_KLIPPY_TRIES` times, each bounded by ``timeout_s`` of
    wall time; outputs that answered the sentinel but lack the exit's commands are taken only
    if every run gave the same bytes (a job that moves nothing switches no motor on, so klippy
    has none to switch off). klippy packs the same commands into other blocks run to run, so
    outputs are compared by their commands.

    Raises:
        ConfigError: klippy refused the config or the G-code (its own words, and the G-code
            line where its words quote it), ran over its time bound, or kept dropping the end.
    """
    try:
        job = gcode.read_bytes()
    except OSError as err:
        raise UsageError(f"{gcode}: cannot read the G-code: {err.strerror}") from None
    with tempfile.TemporaryDirectory(prefix="wavecheck-klippy-") as tmp:
        sent, out = Path(tmp) / "job.gcode", Path(tmp) / "job.serial"
        sent.write_bytes(job + f"\n{SENTINEL}\n".encode())
        cmd = [sys.executable, str(KLIPPY_BATCH), str(klippy.parent), str(config.resolve())]
        cmd += ["-i", str(sent)]
        cmd += ["-o", str(out), "-d", str(dictionary.resolve())]
        seen: dict[bytes, bytes] = {}
        for _ in range(_KLIPPY_TRIES):
            try:
                done = subprocess.run(
                    cmd,
                    capture_output=True,
                    text=True,
                    timeout=timeout_s,
                    env={**os.environ, "PYTHONDONTWRITEBYTECODE": "1"},
                    check=False,
                )
            except subprocess.TimeoutExpired:
                raise ConfigError(
                    f"{gcode}: klippy's batch run took over {timeout_s:g} s of wall time "
                    "(raise --timeout, or shorten the job)"
                ) from None
            problem = _klippy_error(done.stderr, config, gcode)
            if problem is None and done.returncode:
                problem = f"{gcode}: klippy's batch run failed (exit status {done.returncode})"
            if problem is not None:
                raise ConfigError(problem)
            serial = out.read_bytes() if out.exists() else b""
            if _SENTINEL_ANSWER.search(done.stderr):
                if _ends_at_exit(serial, decoder):
                    return serial
                seen[_commands(serial, decoder)] = serial
        if len(seen) == 1:  # the same commands each time: a job that switches nothing on
            return seen.popitem()[1]
    raise ConfigError(
        f"{gcode}: klippy's batch output lacked the end of the job in {_KLIPPY_TRIES} runs "
        f"(no answer to the {SENTINEL} wavecheck adds after the last line, or no output "
        "switched off at its exit after the last step)"
    )


def _commands(serial: bytes, decoder: Dictionary | None) -> bytes:
    """The commands of an output, without their blocks' framing (the output if undecodable)."""
    if decoder is None:
        return serial
    try:
        return b"".join(m.raw for b in split_blocks(serial, "") for m in decode_block(b, decoder))
    except (UsageError, ValueError, IndexError):
        return serial


def _ends_at_exit(serial: bytes, decoder: Dictionary | None) -> bool:
    """Whether klippy's output reaches its exit: at exit klippy switches the steppers' enable
    pins off (klippy/gcode.py:352-361 sends gcode:request_restart; extras/stepper_enable.py:
    125-126 turns the motors off) after the last move, so the last command written is a
    scheduled output at or after the last step. A config with no output to switch leaves
    nothing to check (True)."""
    if decoder is None:
        return True
    try:
        messages = [m for b in split_blocks(serial, "") for m in decode_block(b, decoder)]
    except (UsageError, ValueError, IndexError):
        return False
    if not any(m.name.startswith("config_digital_out") for m in messages):
        return True
    return bool(messages) and messages[-1].name in ("queue_digital_out", "queue_pwm_out")


def _klippy_error(log: str, config: Path, gcode: Path) -> str | None:
    """One line from klippy's log: the config error, the G-code error and its line, or None."""
    lines = log.splitlines()
    if "No module named" in log:
        missing = sorted(set(re.findall(r"No module named '(\w+)'", log)))
        return (
            f"klippy cannot start: no Python module {', '.join(missing)}: "
            "pip install 'wavecheck[klipper]'"
        )
    for k, line in enumerate(lines):
        level, _, said = line.partition(":root:")
        if level == "ERROR" and said.startswith("Config error"):
            detail = next((ln.split("Error: ", 1)[1] for ln in lines[k:] if "Error: " in ln), said)
            return f"{config}: klippy refused the config: {detail}"
        if level in ("WARNING", "ERROR", "CRITICAL"):
            return f"{_where(gcode, said)}: klippy rejected the job: {said}"
        if level == "INFO" and said.startswith("Unknown command:"):
            return f"{_where(gcode, said)}: klippy does not know the command ({said}; it would skip it)"
    return None


def _where(gcode: Path, said: str) -> str:
    """``FILE:LINE`` of the first G-code line that starts with what klippy quotes, else FILE."""
    quoted = re.search(r"""["']([^"']+)["']""", said)
    if quoted:
        word = quoted.group(1).strip().upper()
        for k, raw in enumerate(gcode.read_text(errors="replace").splitlines(), 1):
            if raw.split(";")[0].strip().upper().startswith(word):
                return f"{gcode}:{k}"
    return str(gcode)


def job(serial: bytes, dictionary: Dictionary, where: str) -> Job:
    """The commands of klippy's batch output made ready for a freshly reset MCU: in a canonical
    order, packed anew into blocks numbered from 0, and a ``get_config`` after them.

    klippy interleaves the commands of its queues, and packs them into blocks, as its real-time
    clock goes: two batch runs of one job gave the same commands in other orders and other
    blocks, hence other serial timing and step times 3 cycles apart. Here the timed commands
    between two others (configuration) are ordered by the clock they act at (a move's first
    step, an output's clock; a stepper's direction or clock reset goes with its next move), each
    object's own commands staying in their order, then packed as many to a block as fit: a rerun
    feeds the MCU the same bytes at the same cycles, hence the same VCD.

    Raises:
        UsageError: not a stream of message blocks, a command the dictionary lacks, no step.
    """
    raw = split_blocks(serial, where)
    if not raw:
        raise UsageError(f"{where}: klippy sent nothing to the MCU")
    messages = []
    for k, block in enumerate(raw):
        try:
            messages += decode_block(block, dictionary)
        except (ValueError, IndexError) as err:
            raise UsageError(f"{where}: block {k}: {err}") from None
    next_step: dict[int, int] = {}
    steps: dict[int, int] = {}
    last = 0
    keys: list[int | None] = []
    for m in messages:
        a = m.args
        key: int | None = None
        if m.name == "config_stepper":
            next_step[int(a["oid"])] = 0
            steps.setdefault(int(a["oid"]), 0)
        elif m.name == "reset_step_clock":
            next_step[int(a["oid"])] = int(a["clock"])
            key = -1  # takes its next move's key below
        elif m.name == "set_next_step_dir":
            key = -1
        elif m.name == "queue_step":
            oid, n, iv, add = (int(a[x]) for x in ("oid", "count", "interval", "add"))
            key = next_step.get(oid, 0) + iv
            end = next_step.get(oid, 0) + n * iv + add * n * (n - 1) // 2
            next_step[oid] = end
            steps[oid] = steps.get(oid, 0) + n
            last = max(last, end)
        elif m.name in ("queue_digital_out", "queue_pwm_out"):
            key = int(a["clock"])
            last = max(last, key)
        keys.append(key)
    if not any(steps.values()):
        raise UsageError(
            f"{where}: klippy commands no step: the job moves no stepper (no move, or only "
            "moves to where the machine is)"
        )
    ordered = _canonical(messages, keys)
    # the last block asks the MCU for its configuration: its answer tells its move-queue size
    blocks = pack([m.raw for m in ordered] + [dictionary.encode_id("get_config")])
    needs = []
    for block in blocks:
        needs.append(sum(m.name in MOVE_COMMANDS for m in decode_block(block, dictionary)))
    stops = tuple(dictionary.encode_id(n) for n in STOP_RESPONSES)
    return Job(tuple(blocks), tuple(needs), last, steps, stops)


def _canonical(messages: list[Message], keys: list[int | None]) -> list[Message]:
    """Runs of timed commands (key not None) sorted by (clock, object, own order); a key of -1
    takes the key of its object's next timed command."""
    keys = list(keys)
    following: dict[int, int] = {}
    for k in range(len(messages) - 1, -1, -1):
        if keys[k] is None:
            continue
        oid = int(messages[k].args.get("oid", -1))
        if keys[k] == -1:
            keys[k] = following.get(oid, 0)
        following[oid] = keys[k] or 0
    out: list[Message] = []
    run: list[tuple[int, int, int, Message]] = []
    for k, (m, key) in enumerate(zip(messages, keys, strict=True)):
        if key is None:
            out += [r[3] for r in sorted(run, key=lambda r: r[:3])]
            run = []
            out.append(m)
        else:
            run.append((key, int(m.args.get("oid", -1)), k, m))
    out += [r[3] for r in sorted(run, key=lambda r: r[:3])]
    return out


def build(src: Path, kconfig: bytes | None) -> tuple[Path, Path]:
    """Klipper built from ``src`` with ``kconfig`` (a ``.config``; None: :data:`DEFAULT_KCONFIG`),
    cached: its ``klipper.elf`` and ``klipper.dict``."""
    from wavecheck.mcu.build import build_firmware
    from wavecheck.mcu.klipper_kconfig import GENCONFIG, OLDDEFCONFIG

    replace = {
        ".config": DEFAULT_KCONFIG if kconfig is None else kconfig,
        "lib/kconfiglib/genconfig.py": GENCONFIG,
        "lib/kconfiglib/olddefconfig.py": OLDDEFCONFIG,
    }
    python = f"PYTHON={sys.executable}"
    elf = build_firmware(
        src,
        "src/stepper.c",
        replace,
        [python],
        "out/klipper.elf",
        before=[[python, "olddefconfig"]],
        also=["out/klipper.dict"],
    )
    return elf, elf.parent / "klipper.dict"


def free_list_address(elf: Path) -> int:
    """The data-space address of the MCU's move free-list head, from the ELF's symbols.

    Raises:
        ConfigError: the ELF has no such symbol (stripped, or not Klipper).
    """
    from elftools.elf.elffile import ELFFile
    from elftools.elf.sections import SymbolTableSection

    with elf.open("rb") as f:
        for section in ELFFile(f).iter_sections():
            if not isinstance(section, SymbolTableSection):
                continue
            for sym in section.iter_symbols():
                if sym.name == FREE_LIST or sym.name.startswith(FREE_LIST + "."):
                    return int(sym["st_value"]) & 0xFFFF  # data space is at 0x800000
    raise ConfigError(
        f"{elf}: no symbol {FREE_LIST} (src/basecmd.c): a stripped ELF, or not Klipper; "
        "give the unstripped out/klipper.elf"
    )


def mcu_of(dictionary: Dictionary, where: Path) -> tuple[str, int]:
    """The MCU and clock the build is for (its dictionary's ``MCU`` and ``CLOCK_FREQ``).

    Raises:
        UsageError: an MCU the simulation does not have.
    """
    mcu = str(dictionary.constants.get("MCU", "?"))
    clock = int(dictionary.constants.get("CLOCK_FREQ", 0))
    if mcu not in MCUS or mcu == "atmega328p":
        raise UsageError(
            f"{where}: a Klipper build for {mcu}; the simulation runs the atmega644p and the "
            "atmega2560 (CONFIG_MACH_atmega644p or CONFIG_MACH_atmega2560)"
        )
    return mcu, clock


def pins(chosen: list[Stepper]) -> dict[str, str]:
    """The VCD's signals: ``X_STEP``, ``X_DIR``, ``X_ENABLE`` … → ``PORT.BIT``."""
    out: dict[str, str] = {}
    for s in chosen:
        out[f"{s.name}_STEP"] = s.step
        out[f"{s.name}_DIR"] = s.dir
        if s.enable:
            out[f"{s.name}_ENABLE"] = s.enable
    return out


def run(
    runner: Path,
    elf: Path,
    dictionary: Dictionary,
    sent: Job,
    vcd: str,
    signals: dict[str, str],
    limits: tuple[float, float, float],
    accept: Callable[[SimRun], object],
    *,
    paced: bool = True,
) -> SimRun:
    """Simulate the job (``limits``: simulated time, tail after the last event, wall time, in
    seconds); ``accept`` judges the run before the VCD is kept (:func:`outcome` does).
    ``paced=False`` feeds the blocks as fast as the MCU answers, as if its queue were endless."""
    mcu, clock = mcu_of(dictionary, elf)
    max_s, tail_s, wall_s = limits
    options = [f"--blocks={free_list_address(elf) if paced else 0}", f"--start={clock // 100}"]
    options += [f"--until={sent.last_event}"] + [f"--stop={p.hex()}" for p in sent.stop_prefixes]
    return simulate(
        runner,
        elf,
        mcu,
        clock,
        vcd,
        signals,
        "",
        sent.lines(),
        int(max_s * clock),
        int(tail_s * clock),
        wall_s,
        accept,
        options,
    )


def outcome(run: SimRun, dictionary: Dictionary) -> int:
    """The MCU's move-queue size (its answer to the last block, ``get_config``), after checking
    that the run went through.

    Raises:
        ConfigError: no answer, a nak, a shutdown (with its reason), or the job unfinished.
    """
    move_count = 0
    reasons = dictionary.names("static_string_id")
    shutdown = None
    for p in run.printed:
        try:
            messages = decode_block(bytes.fromhex(p.text), dictionary)
        except (ValueError, IndexError):
            continue
        for m in messages:
            if m.name == "config":
                move_count = int(m.args["move_count"])
            if m.name in STOP_RESPONSES and shutdown is None:
                shutdown = (p.cycle, reasons.get(int(m.args["static_string_id"]), "?"))
    at = f"{run.end_cycle / run.clock_hz:.6f} s"
    if run.end == "noanswer":
        raise ConfigError(
            "the MCU never answered the first message block within the simulated time: not a "
            "Klipper build for this MCU, or another clock or baud rate"
        )
    if shutdown is not None:
        cycle, why = shutdown
        raise ConfigError(
            f"the simulated MCU shut down at {cycle / run.clock_hz:.6f} s: "
            f"'{why}'{_SHUTDOWN_HINTS.get(why, '')}"
        )
    if run.end == "nak":
        raise ConfigError(f"the MCU refused a message block (out of sequence) at {at}")
    if run.end != "done" or not move_count:
        raise ConfigError(
            f"the job did not finish within the simulated time limit ({at}): "
            "raise --max-time, or shorten the job"
        )
    return move_count
