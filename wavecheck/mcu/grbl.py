"""grbl 1.1 on a simulated ATmega328P: its pins, its build, its serial protocol.

Facts from grbl 1.1h's source (gnea/grbl bfb67f0):
- pins (``grbl/cpu_map.h:37-56``, CPU_MAP_ATMEGA328P): STEP X/Y/Z on PD2/PD3/PD4, DIR on
  PD5/PD6/PD7, STEPPERS_DISABLE on PB0 (high = disabled unless ``$4=1``);
- the clock: 16 MHz (``Makefile``: ``CLOCK = 16000000``), the UART at 115200 baud
  (``grbl/config.h:42``);
- the banner ``\\r\\nGrbl 1.1h ['$' for help]\\r\\n`` (``grbl/report.c:172``), printed after the
  serial input was flushed at reset: nothing may be sent before it;
- every line is answered ``ok`` or ``error:N`` (``grbl/report.c:116-118``), N one of the
  ``STATUS_*`` codes of ``grbl/report.h``; a blank line is answered ``ok`` (``protocol.c:93-95``);
- ``$20=1`` (soft limits) is refused while ``$22`` (homing) is 0 (``settings.c:264-266``);
- ``G4`` waits for the planner to empty before it dwells (``motion_control.c``, ``mc_dwell`` calls
  ``protocol_buffer_synchronize``): its ``ok`` comes after the last step of the moves before it.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

from wavecheck.errors import ConfigError, UsageError
from wavecheck.mcu.run import Printed, SimRun

__all__ = [
    "BANNER",
    "CLOCK_HZ",
    "ENABLE_PIN",
    "MCU",
    "PINS",
    "Job",
    "Line",
    "job",
    "replies",
    "settings_dump",
    "status_names",
]

MCU = "atmega328p"
CLOCK_HZ = 16_000_000
BANNER = "Grbl "
#: Signal name in the VCD → ``PORT.BIT`` (grbl/cpu_map.h:37-56).
PINS = {
    "X_STEP": "D.2",
    "Y_STEP": "D.3",
    "Z_STEP": "D.4",
    "X_DIR": "D.5",
    "Y_DIR": "D.6",
    "Z_DIR": "D.7",
    "STEPPERS_DISABLE": "B.0",
}
ENABLE_PIN = "STEPPERS_DISABLE"
#: The line sent last: its ``ok`` comes when every step before it was made.
SYNC = "G4 P0"
#: The longest line sent (the runner reads its input in 4096-byte lines).
_MAX_SENT = 4000
_STATUS = re.compile(r"#define\s+STATUS_(\w+)\s+(\d+)")
_SETTING = re.compile(r"^\$(\d+)=(\S+)$")
_ALARM = re.compile(r"#define\s+EXEC_ALARM_(\w+)\s+(\d+)")
#: The hint of an alarm the simulation's missing switches cause (by the first word of its name).
_ALARM_HINTS = {
    "soft": ": the simulated machine is not homed and starts at machine position 0; run with "
    "$20=0, or keep the job inside the soft limits",
    "hard": ": the simulated limit inputs are unconnected; run with $21=0",
    "homing": ": the simulation has no limit switches to home on; run with $22=0 and no $H",
}


@dataclass(frozen=True)
class Line:
    """A line to send and where it came from (``None`` for the ones wavecheck adds)."""

    text: str
    path: str | None
    lineno: int


@dataclass(frozen=True)
class Job:
    """The lines sent after the banner: the settings, ``$$``, the G-code, the sync line."""

    lines: tuple[Line, ...]
    dump_index: int  # the position of ``$$`` in ``lines``


def _read(path: Path, what: str) -> list[tuple[int, str]]:
    try:
        text = path.read_bytes().decode("utf-8")
    except OSError as err:
        raise UsageError(f"{path}: cannot read the {what}: {err.strerror}") from None
    except UnicodeDecodeError as err:
        raise UsageError(f"{path}: byte {err.start}: the {what} is not UTF-8 text") from None
    out = []
    for k, raw in enumerate(text.splitlines(), 1):
        line = raw.strip()
        if len(line) > _MAX_SENT:
            raise UsageError(
                f"{path}:{k}: a line of {len(line)} characters, more than wavecheck sends "
                f"({_MAX_SENT}); grbl's own limit is LINE_BUFFER_SIZE (80, protocol.h:32)"
            )
        if line and line != "%":  # a blank line is answered ok and changes nothing
            out.append((k, line))
    return out


def job(settings: Path | None, gcode: Path) -> Job:
    """The lines for one run: each ``$N=V`` of ``settings``, ``$$``, the G-code, ``G4 P0``."""
    lines: list[Line] = []
    if settings is not None:
        for k, text in _read(settings, "settings"):
            if text.startswith(("(", ";")):
                continue
            if not text.startswith("$"):
                raise UsageError(
                    f"{settings}:{k}: '{text}' is not a grbl setting ($N=V); G-code goes in --gcode"
                )
            lines.append(Line(text, str(settings), k))
    lines = _homing_first(lines)
    dump = len(lines)
    lines.append(Line("$$", None, 0))
    lines += [Line(text, str(gcode), k) for k, text in _read(gcode, "G-code")]
    if not any(ln.path == str(gcode) for ln in lines):
        raise UsageError(f"{gcode}: no G-code line in it")
    lines.append(Line(SYNC, None, 0))
    return Job(tuple(lines), dump)


def _homing_first(lines: list[Line]) -> list[Line]:
    """A ``$$`` dump lists ``$20`` (soft limits) before ``$22`` (homing), but grbl refuses
    ``$20=1`` while homing is off (``settings.c:264-266``, error:10): send ``$22`` first, so that
    the dump sets the state it shows."""
    homing = [ln for ln in lines if ln.text.replace(" ", "").startswith("$22=")]
    return homing + [ln for ln in lines if ln not in homing] if homing else lines


def status_names(grbl_src: Path | None) -> tuple[dict[int, str], dict[int, str]]:
    """``error:N`` → its name in ``grbl/report.h`` (``gcode unsupported command``) and
    ``ALARM:N`` → its name in ``grbl/system.h`` (``soft limit``), if the source is at hand."""
    if grbl_src is None:
        return {}, {}
    out: list[dict[int, str]] = []
    for header, pattern in (("report.h", _STATUS), ("system.h", _ALARM)):
        try:
            text = (grbl_src / "grbl" / header).read_text(encoding="utf-8", errors="replace")
        except OSError:
            text = ""
        out.append({int(n): k.lower().replace("_", " ") for k, n in pattern.findall(text)})
    return out[0], out[1]


def replies(
    run: SimRun, sent: Job, names: dict[int, str], alarms: dict[int, str]
) -> list[tuple[Line, Printed]]:
    """Pair each line sent with grbl's answer.

    Raises:
        ConfigError: no banner, an ``ALARM``, a line grbl rejected (naming its file and line), or
            the job did not finish.
    """
    if run.end == "nobanner":
        raise ConfigError(
            f"no grbl banner ('{BANNER.strip()} …') within the simulated time: not a grbl "
            "firmware for this MCU, or another clock or baud rate"
        )
    answers = [p for p in _after_banner(run) if p.text.startswith(("ok", "error"))]
    pairs = list(zip(sent.lines, answers, strict=False))
    alarm = next((p for p in _after_banner(run) if p.text.startswith("ALARM")), None)
    if alarm is not None:
        code = alarm.text.partition(":")[2]
        name = alarms.get(int(code), "") if code.isdigit() else ""
        line = sent.lines[len(pairs)] if len(pairs) < len(sent.lines) else sent.lines[-1]
        where = f"{line.path}:{line.lineno}" if line.path else "wavecheck's own line"
        hint = _ALARM_HINTS.get(name.split(" ")[0], "")
        raise ConfigError(
            f"{where}: grbl raised {alarm.text}{f' ({name})' if name else ''} at "
            f"{alarm.cycle / run.clock_hz:.6f} s, running '{line.text}' or a line before it{hint}"
        )
    for line, answer in pairs:
        if answer.text.startswith("error"):
            code = answer.text.partition(":")[2]
            name = names.get(int(code), "") if code.isdigit() else ""
            where = f"{line.path}:{line.lineno}" if line.path else "wavecheck's own line"
            raise ConfigError(
                f"{where}: grbl rejected '{line.text}': {answer.text}"
                + (f" ({name})" if name else "")
            )
    if run.end != "done" or len(pairs) < len(sent.lines):
        last = pairs[-1][0] if pairs else None
        at = f"; the last line answered: {last.path}:{last.lineno}" if last and last.path else ""
        raise ConfigError(
            f"the job did not finish within the simulated time limit ({run.end_cycle / run.clock_hz:g} s)"
            f"{at}: raise --max-time, or shorten the job"
        )
    return pairs


def settings_dump(run: SimRun, sent: Job) -> list[str]:
    """The ``$N=V`` lines grbl printed in answer to ``$$``."""
    printed = _after_banner(run)
    answers = [k for k, p in enumerate(printed) if p.text.startswith(("ok", "error"))]
    end = answers[sent.dump_index]
    start = answers[sent.dump_index - 1] + 1 if sent.dump_index else 0
    return [p.text for p in printed[start:end] if _SETTING.match(p.text)]


def _after_banner(run: SimRun) -> tuple[Printed, ...]:
    """The lines after the banner (before it, a fresh EEPROM makes grbl print ``error:7`` and
    its default settings: ``settings.c``, ``settings_init``)."""
    k = next((k for k, p in enumerate(run.printed) if p.text.startswith(BANNER)), None)
    return () if k is None else run.printed[k + 1 :]
