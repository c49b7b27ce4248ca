"""RepRapFirmware: ``config.g`` (reference ``firmware-timing.md`` §5).

Read, in file order and through ``M98 P"file.g"`` includes (beside the file, as ``/sys``):
``M569 P<driver> T<a:b:c:d>`` (µs: step high, step low, DIR setup before the rising edge, DIR
hold after the *falling* edge; one value is used for all four, two or three are refused by the
firmware), ``M584`` (axis → drivers, ``E`` for extruders; default X0 Y1 Z2 E3), ``M350``
(microstepping, default 16) and ``M92`` (steps/mm; ``S`` = at that microstepping; a later
``M350`` rescales it, as RRF does), ``M203`` (mm/min). Driver ``1`` and ``0.1`` are the same
main-board driver; ``B.N`` with B > 0 is an expansion board's.

Timing is global: a main-board driver with any field over 0.2 µs is "slow" and every slow driver
gets the largest value of each field over all slow drivers (rounded up to step clocks); a driver
without T is "fast": the firmware assumes ≥ 0.2 µs high and low and waits for nothing, so its DIR
setup and hold cannot be read from the file. On a Duet 3 MB6XD (named in the file's comments)
every driver defaults to 2.5 µs per field and the largest of all drivers applies to all. An
expansion board applies T with its own firmware, on its own step clock, whose rate the file does
not give (``uncertain`` with no bound: never a PASS). Meta-commands (``if``, ``var``,
``{expressions}``) are not evaluated: a value written as an expression is not read (named), and
the motion commands of an ``if``/``elif``/``else``/``while`` block are not read either (the
block is named), since whether they run is not decided by the file.

What the comments state (the configurator's "Configuration file for Duet WiFi (firmware
version 2.03)", "RepRapFirmware v3.5.4") is used where the firmware's rule depends on it: before
1.21 ``T`` is one value for the high and low time and DIR is not held; 2.0x on a Duet 2
WiFi/Ethernet has two default extruders (drivers 3 and 4).
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass, field
from fractions import Fraction
from pathlib import Path

from wavecheck.errors import ConfigError
from wavecheck.firmware._text import is_file, number, read_text, where
from wavecheck.firmware.guarantee import (
    FirmwareConfig,
    FixRole,
    GeneratorGuarantee,
    Guaranteed,
    at_least,
    at_most,
    not_enforced,
    uncertain,
    unknown,
)

__all__ = ["looks_like", "read"]

_FAST_NS = Fraction(200)
_MB6XD_NS = Fraction(2500)
_WORD = re.compile(
    r"([A-Za-z])\s*(\"[^\"]*\"|\{[^}]*\}|[-+]?(?:(?i:nan|inf(?:inity)?)\b|[-+0-9.:eE]+))?"
)
_AXES = "XYZUVWABCD"
#: A meta-command that opens a block: the lines indented under it run only when it says so.
_BLOCK = re.compile(r"^\s*(if|elif|else|while)\b")
#: The M-codes the reader takes figures from (M98 too: an include may hold them).
_MOTION = {"98", "584", "569", "665", "667", "669", "350", "92", "203"}
_MAX_INCLUDES = 64
_US = 1000


def looks_like(text: str) -> bool:
    """A ``config.g``: ``M569``/``M584``/``M92``/``M350``/``M203`` commands, or a file of
    ``M98 P"….g"`` includes."""
    return (
        len(re.findall(r"^[ \t]*M(569|584|92|350|203)\b", text, re.M)) >= 2
        or len(re.findall(r"^[ \t]*M98[ \t]+P\"[^\"\n]+\.g\"", text, re.M)) >= 2
    )


#: A driver without T (or with every field at most 0.2 us) is "fast": DDA::StepDrivers raises
#: its STEP pin, computes the next step times, lowers it, with no wait for any field
#: (Duet3D/RepRapFirmware:src/Movement/DDA.cpp, the branch after ``if ((driversStepping &
#: p.GetSlowDriversBitmap()) != 0)``; on SAME70 a ``__DSB()`` "without this the step pulse can
#: be far too short"). The 0.2 us RRF assumes is not a wait.
_FAST = ("a fast driver (no T over 0.2 us): DDA::StepDrivers raises and lowers STEP with no "
         "wait between, DIR with none before or after")  # fmt: skip
#: What a comment may state: the RepRapFirmware configurator's header ("; Configuration file for
#: Duet WiFi (firmware version 2.03)") or a user's "RepRapFirmware v3.5.4" / "RRF 3.4".
_STATED_VERSION = re.compile(
    r"(?i)(?:firmware\s+version|\bRepRapFirmware|\bRRF)\s*v?(\d{1,2}(?:\.\d{1,3}){0,2})(?![\d.]*\d)"
)
_STATED_BOARD = re.compile(r"(?i)configuration file for\s+(duet[^(;\r\n]*?)\s*(?:\(|$)")
#: Boards whose smart drivers 2.0x counts for its default extruders: the Duet 2 WiFi/Ethernet have
#: five TMC2660 (Platform::Init: numTMC2660Drivers 5 without a DueX, 7 with a DueX2, 10 with a
#: DueX5, which the file does not show: at least 5).
_DUET2 = ("duet wifi", "duet ethernet", "duet 2 wifi", "duet 2 ethernet")
#: 1.21's release notes (WHATS_NEW.md, "Version 1.21"): "New M569 T parameter options to specify
#: step pulse width, step pulse interval, direction setup and direction hold times" and "When
#: using external stepper drivers the DIR signal is no longer changed before the step pulse has
#: ended". Before, GCodes ``case 569`` read ``platform.SetDriverStepTiming(drive,
#: gb.GetFValue())``: one number (GetFValue stops at ``:``), the "minimum pulse width";
#: Platform::SetDriverStepTiming makes the driver slow when it is >= minStepPulseTiming 0.2 us,
#: and DDA::Step waits that many clocks before raising STEP (since it was lowered) and before
#: lowering it: the high and the low time. DIR is updated in step 4 ("update the direction pins
#: where necessary ... We assume that meeting the direction pin hold time is not a problem"),
#: between the two, while STEP is high: no DIR setup or hold is kept. From 1.21 (2.0x: GCodes
#: ``gb.GetFloatArray(timings, numTimings, true)`` then ``numTimings != 4`` -> "bad timing
#: parameter"; GCodeBuffer::GetFloatArray pads one entry to all four, "Special case if there is
#: one entry"; 3.x: ``numTimings == 1`` copied, else 4 required) T is one value or four.
_ONE_T = (1, 21)
_ONE_T_WHY = ("RepRapFirmware before 1.21 reads one M569 T value, the minimum pulse width, for "
              "the high and the low time, and may change DIR while STEP is high (DDA::Step; 1.21 "
              "release notes)")  # fmt: skip
#: Why an axis RRF has (``M584``) is not checked.
_UNREAD = "no M92, M203 or M569 T in the file"
#: Without ``M584 E`` the extruders are the firmware's default, which the file does not decide.
#: Per version, from RepRapFirmware's own code (Duet3D/RepRapFirmware and its 2.0x sources, as
#: indexed): 2.0x ``GCodes::Init``: ``numExtruders = min<size_t>(MaxExtruders,
#: platform.GetNumSmartDrivers() - XYZ_AXES)`` with smart drivers ("don't default dumb drivers
#: to extruders"), ``MaxExtruders`` without (a Duet 2 alone has 5 smart drivers: 2 extruders,
#: on drivers 3 and 4; a DueX adds more); 3.x: ``numExtruders = NumDefaultExtruders``
#: (src/GCodes/GCodes.cpp @ fa22ccf), a constant of the board's Pins file (0 to 3 in the
#: indexed ones); the latest Pins files (Pins_DuetNG.h @ 17a42594, Pins_Duet3_MB6HC.h @
#: 0ab87481) define none. Which of these applies needs the version and board, so only an E0 the
#: file gives M92/M203 values is read (on driver 3, the first after X/Y/Z), with this note.
_DEFAULT_EXTRUDERS = (
    "no M584 E: E0 on driver 3 assumed, other extruders not read; RepRapFirmware's default "
    "extruders depend on its version and board (2.0x: the smart drivers minus 3, 2 on a Duet 2; "
    "3.x: the board's NumDefaultExtruders, 0 to 3 in the Pins files read; later releases: not established): give M584 E… to decide"
)
_DUET2_EXTRUDERS = (
    "no M584 E: {at} states RepRapFirmware {version} on a {board}: GCodes::Init makes "
    "min(MaxExtruders, smart drivers - 3) extruders, and a Duet 2 has 5 smart drivers (a DueX "
    "adds more, which the file does not show): E0 on driver 3 and E1 on driver 4 (Platform::Init "
    "extruderDrivers[extr] = extr + MinAxes)"
)


@dataclass
class _State:
    axis_drivers: dict[str, list[str]] = field(
        default_factory=lambda: {"X": ["0.0"], "Y": ["0.1"], "Z": ["0.2"]}
    )
    extruders: list[str] = field(default_factory=lambda: ["0.3"])
    extruders_given: bool = False  # an M584 E… seen
    timing: dict[str, tuple[list[Fraction], str]] = field(default_factory=dict)
    micro: dict[str, Fraction] = field(default_factory=dict)
    spm: dict[str, tuple[Fraction, str]] = field(default_factory=dict)
    speed: dict[str, tuple[Fraction, str]] = field(default_factory=dict)
    unsupported: list[str] = field(default_factory=list)
    files: list[str] = field(default_factory=list)
    board_6xd: str = ""
    version: tuple[int, ...] | None = None  # the version a comment states, and where
    version_at: str = ""
    board: str = ""  # the board the configurator's header names, and where
    board_at: str = ""
    coupled: dict[str, str] = field(default_factory=dict)  # axis → why its rate is unknown
    backwards: dict[str, bool] = field(default_factory=dict)  # driver → M569 S0


def _words(line: str) -> list[tuple[str, str]]:
    code = line.split(";")[0]
    return [(m.group(1).upper(), m.group(2) or "") for m in _WORD.finditer(code)]


def _driver(text: str) -> str:
    """``1`` → ``0.1`` (the main board), ``1.2`` stays."""
    return text if "." in text else f"0.{text}"


def read(path: str | os.PathLike[str]) -> FirmwareConfig:
    """Read a ``config.g`` (see the module doc)."""
    p = Path(path)
    state = _State()
    _feed(p, p.parent, state, {p.resolve()})
    return _config(str(p), state)


def _feed(path: Path, sys_dir: Path, st: _State, seen: set[Path]) -> None:
    st.files.append(str(path))
    text = read_text(path)
    if not st.board_6xd and re.search(r"\b(MB\s*)?6XD\b", text, re.I):
        st.board_6xd = f"{path} names a Duet 3 MB6XD"
    _stated(path, text, st)
    block: tuple[int, str] | None = None  # (indent, where) of the outermost if/while open
    skipped = ""  # the block whose commands were left out (noted once)
    for no, line in enumerate(text.splitlines(), 1):
        code_part = line.split(";")[0].expandtabs(4)
        if not code_part.strip():
            continue  # blank lines and comments do not end a block
        indent = len(code_part) - len(code_part.lstrip())
        keyword = _BLOCK.match(code_part)
        if (
            block is not None
            and indent <= block[0]
            and not (keyword and keyword.group(1) in ("elif", "else") and indent == block[0])
        ):
            block = None
        if keyword and block is None:
            block = (indent, where(path, no))
            continue
        words = _words(line)
        if not words or words[0][0] != "M":
            continue
        code, rest = words[0][1], words[1:]
        at = where(path, no)
        if block is not None and indent > block[0]:
            if code in _MOTION and skipped != block[1]:
                skipped = block[1]
                st.unsupported.append(
                    f"{at}: M{code} inside the `if`/`while` block of {block[1]}: RepRapFirmware "
                    "runs it only when the condition holds, which the file does not decide; "
                    "the block's motion commands are not read"
                )
            if code in _MOTION:
                continue
        if code == "98":
            _include(path, sys_dir, dict(rest).get("P", ""), at, st, seen)
        elif code == "584":
            for letter, value in rest:
                if value and not value.startswith("{"):
                    drivers = [_driver(d) for d in value.split(":") if d]
                    if letter == "E":
                        st.extruders, st.extruders_given = drivers, True
                    elif letter in _AXES:
                        st.axis_drivers[letter] = drivers
        elif code == "569":
            _m569(dict(rest), at, st)
        elif code in ("665", "667", "669"):
            _kinematics(code, dict(rest), at, st)
        elif code == "350":
            _m350(rest, at, st)
        elif code in ("92", "203"):
            _m92_203(code, rest, at, st)


def _stated(path: Path, text: str, st: _State) -> None:
    """The version and board the comments state (the first of each, in file order)."""
    for no, line in enumerate(text.splitlines(), 1):
        if st.version is not None and st.board:
            return
        comment = line.partition(";")[2]
        if not comment:
            continue
        v = _STATED_VERSION.search(comment)
        if st.version is None and v:
            st.version, st.version_at = (
                tuple(int(x) for x in v.group(1).split(".")),
                where(path, no),
            )
        b = _STATED_BOARD.search(comment)
        if not st.board and b:
            st.board, st.board_at = " ".join(b.group(1).split()), where(path, no)


def _include(path: Path, sys_dir: Path, target: str, at: str, st: _State, seen: set[Path]) -> None:
    name = target.strip('"')
    if not name:
        return
    if name.startswith("{"):
        st.unsupported.append(f"{at}: M98 P{name} names its file by an expression; not read")
        return
    rel = re.sub(r"^(\d+:)?/?(sys/)?", "", name)
    inc = sys_dir / rel
    if not is_file(inc):
        st.unsupported.append(f'{at}: M98 P"{name}" is not beside {path.name}; not read')
        return
    if inc.resolve() in seen or len(seen) >= _MAX_INCLUDES:
        return
    seen.add(inc.resolve())
    _feed(inc, sys_dir, st, seen)


def _m569(words: dict[str, str], at: str, st: _State) -> None:
    s = words.get("S", "")
    if "P" in words and re.fullmatch(r"[01]", s):
        # GCodes ConfigureDriver: platform.SetDirectionValue(drive, S != 0): S0 runs backwards
        for drv in words["P"].split(":"):
            st.backwards[_driver(drv)] = s == "0"
    if "P" not in words or "T" not in words or not words["T"]:
        return
    if words["T"].startswith("{"):
        st.unsupported.append(f"{at}: M569 T{words['T']} is an expression; not read")
        return
    values = words["T"].split(":")
    if st.version is not None and st.version < _ONE_T:
        values = values[:1] * 4  # GetFValue reads the first number: the high and low time
    fields = [number(v, at, "M569 T", low=0, high=10**6, unit="us") * _US for v in values]
    if len(fields) == 1:
        fields *= 4
    if len(fields) != 4:
        st.unsupported.append(
            f"{at}: M569 T{words['T']}: RepRapFirmware refuses 2 or 3 values (bad timing "
            "parameter); ignored"
        )
        return
    for drv in words["P"].split(":"):
        st.timing[_driver(drv)] = (fields, at)


def _kinematics(code: str, words: dict[str, str], at: str, st: _State) -> None:
    """``M665`` (delta), ``M667 S1|2|3`` (CoreXY/XZ/YZ, older firmware) and ``M669 K…``
    (RRF's KinematicsType: 0 cartesian, 1 CoreXY, 2 CoreXZ, 5 CoreXYU, 8 CoreXYUV, the others
    delta, SCARA, polar, Hangprinter…): axes whose motors do not move one axis alone, so
    steps/mm × M203 does not bound their step rate."""
    if code == "665":
        axes, what = "XYZ", "M665 (delta)"
    elif code == "667":
        axes, what = (
            {"1": "XY", "2": "XZ", "3": "YZ"}.get(words.get("S", ""), ""),
            f"M667 S{words.get('S')}",
        )
    else:
        kind = words.get("K", "")
        axes = {"": "", "0": "", "1": "XY", "2": "XZ", "5": "XYU", "8": "XYUV"}.get(kind, "XYZ")
        what = f"M669 K{kind}"
    for a in axes:
        st.coupled[a] = f"{what} at {at}"


#: Microstepping values the smart drivers take (M350 refuses others, see _m350).
_MICROSTEPS = frozenset(Fraction(2**k) for k in range(9))


def _m350(words: list[tuple[str, str]], at: str, st: _State) -> None:
    for letter, value in words:
        if letter not in (*_AXES, "E") or not value or value.startswith("{"):
            continue
        values = value.split(":")
        if letter == "E" and len(values) == 1 and st.extruders_given:
            values *= len(st.extruders)  # GetUnsignedArray(..., doPad=true), as M92 E
        for i, v in enumerate(values):
            key = letter if letter != "E" else f"E{i}"
            new = number(v, at, f"M350 {letter}", low=0, high=10**6)
            if new not in _MICROSTEPS:
                # GCodes M350: ChangeMicrostepping fails, "Drive %c does not support %ux
                # microstepping" is reported and the loop goes on: that drive keeps its setting
                st.unsupported.append(
                    f"{at}: M350 {letter}{v}: RepRapFirmware refuses {v}x microstepping (a "
                    "power of 2 up to 256) and keeps the drive's setting; not applied"
                )
                continue
            old = st.micro.get(key, Fraction(16))
            if key in st.spm:
                spm, first = st.spm[key]
                st.spm[key] = (spm * new / old, f"{first}, rescaled by M350 at {at}")
            st.micro[key] = new


def _m92_203(code: str, words: list[tuple[str, str]], at: str, st: _State) -> None:
    s = dict(words).get("S")
    for letter, value in words:
        if letter not in (*_AXES, "E"):
            continue
        if not value or value.startswith("{"):
            st.unsupported.append(f"{at}: M{code} {letter}{value} is not a number; not read")
            continue
        values = value.split(":")
        if letter == "E" and len(values) == 1 and st.extruders_given:
            # one E value is every extruder's: GCodeBuffer::GetFloatArray(..., doPad=true) fills
            # the array with it (M92 and M203 read E so, GCodes2.cpp / GCodes3.cpp)
            values *= len(st.extruders)
        for i, v in enumerate(values):
            key = letter if letter != "E" else f"E{i}"
            x = number(v, at, f"M{code} {letter}", low=0, high=10**9)
            if code == "92":
                if s and not s.startswith("{"):
                    at_s = number(s, at, "M92 S", low=1, high=256)
                    x = x * st.micro.get(key, Fraction(16)) / at_s
                st.spm[key] = (x, at)
            else:
                st.speed[key] = (x, at)


def _config(path: str, st: _State) -> FirmwareConfig:
    main = {d: t for d, t in st.timing.items() if d.startswith("0.")}
    if st.board_6xd:
        used = {d for ds in st.axis_drivers.values() for d in ds} | set(st.extruders)
        slow = {
            d: main.get(d, ([_MB6XD_NS] * 4, "MB6XD default 2.5 us"))
            for d in used
            if d.startswith("0.")
        }
    elif st.version is not None and st.version < _ONE_T:  # slow from minStepPulseTiming up
        slow = {d: t for d, t in main.items() if t[0][0] >= _FAST_NS}
    else:
        slow = {d: t for d, t in main.items() if any(f > _FAST_NS for f in t[0])}
    duet2 = (st.version is not None and st.version[0] == 2
             and st.board.lower() in _DUET2 and not st.extruders_given)  # fmt: skip
    if duet2:
        st.extruders = ["0.3", "0.4"]
    worst = _worst(slow)
    logical = [*st.axis_drivers.items(), *((f"E{i}", [d]) for i, d in enumerate(st.extruders))]
    axes = []
    unread: dict[str, str] = {}  # axes RRF has that the file gives no figure for → drivers
    for name, drivers in logical:
        configured = name in st.spm or name in st.speed
        if not configured and (name[0] == "E" and not (st.extruders_given or duet2)
                               or name[0] != "E" and not any(d in st.timing for d in drivers)):  # fmt: skip
            if name[0] != "E":
                unread[name] = ":".join(drivers)
            continue  # a default extruder the file gives no M92/M203 for is not assumed
        axes.append(_axis(name, drivers, st, slow, worst))
    if not axes:
        missing = [u for u in st.unsupported if " M98 " in u]
        if missing:
            raise ConfigError(
                f"{missing[0].split(': M98')[0]}: M98 includes only, and {len(missing)} of them "
                f"are not beside {Path(path).name} (first: {missing[0].split('P')[1].split()[0]}"
                "): give the config.g of the full /sys folder"
            )
        raise ConfigError(
            f"{path}: no M569 T, M92 or M203 for any axis in {', '.join(st.files)} "
            "(nothing to check)"
        )
    notes = [
        "M569 T timing is global over all slow drivers (the largest of each field)",
        "step clock 750 kHz on Duet 3 (1.333 us), core/128 on Duet 2: figures are rounded up",
    ]
    if st.board_6xd:
        notes.insert(0, f"{st.board_6xd}: every driver 2.5 us per field unless T says more")
    if duet2:
        version = ".".join(map(str, st.version or ()))
        notes.append(_DUET2_EXTRUDERS.format(at=f"{st.version_at} and {st.board_at}",
                                             version=version, board=st.board))  # fmt: skip
    elif not st.extruders_given and any(k.startswith("E") for k in (*st.spm, *st.speed)):
        stated = ", ".join(
            f"{what} at {at}" for what, at in (
                (f"version {'.'.join(map(str, st.version or ()))}", st.version_at),
                (f"board {st.board}", st.board_at)) if at
        )  # fmt: skip
        notes.append(_DEFAULT_EXTRUDERS + (
            f" (the file states {stated}: the rule is applied only to 2.0x on a Duet 2 "
            "WiFi/Ethernet, as 3.x boards' NumDefaultExtruders differ between releases)"
            if stated else " (the file states neither its version nor its board)"))  # fmt: skip
    if unread and axes:
        named = ", ".join(f"{name} (driver {drivers})" for name, drivers in unread.items())
        notes.append(f"axis {named}: {_UNREAD}, so nothing bounds its rate or timing: not "
                     "checked (measure it)")  # fmt: skip
    if st.version is not None and st.version < _ONE_T:
        notes.append(f"{st.version_at} states version {'.'.join(map(str, st.version))}: "
                     f"{_ONE_T_WHY}")  # fmt: skip
    return FirmwareConfig(
        firmware="reprapfirmware",
        path=path,
        axes=tuple(axes),
        files=tuple(dict.fromkeys(st.files)),
        unsupported=tuple(dict.fromkeys(st.unsupported)),
        notes=tuple(notes),
        fixer=_fix_one_t if st.version is not None and st.version < _ONE_T else _fix,
        unchecked_axes=((_UNREAD, tuple(unread)),) if unread and axes else (),
    )


def _worst(slow: dict[str, tuple[list[Fraction], str]]) -> list[Guaranteed]:
    out = []
    for i in range(4):
        if not slow:
            break
        drv, (fields, at) = max(slow.items(), key=lambda kv: kv[1][0][i])
        note = "largest over all slow drivers; rounded up to step clocks"
        if not fields[i]:
            out.append(_zero(at, i))
            continue
        out.append(Guaranteed(fields[i], f"M569 P{drv} T (field {i + 1})", at, "us", "set", note))
    return out


def _axis(
    name: str,
    drivers: list[str],
    st: _State,
    slow: dict[str, tuple[list[Fraction], str]],
    worst: list[Guaranteed],
) -> GeneratorGuarantee:
    expansion = [d for d in drivers if not d.startswith("0.")]
    hold_t: Guaranteed | None
    if expansion and all(d in st.timing for d in expansion) and not any(d in slow for d in drivers):
        fields, at = st.timing[expansion[0]]
        note = f"expansion board driver {expansion[0]}: its own firmware applies T"
        pulse, idle, setup, hold_t = (
            uncertain(f, "M569 T", at, "us", None, _EXPANSION, note) if f else _zero(at, i)
            for i, f in enumerate(fields)
        )
        hold = _hold(pulse, hold_t)
    elif any(d in slow for d in drivers) and worst and st.version and st.version < _ONE_T:
        pulse, idle = worst[0], worst[1]
        setup = not_enforced("M569 T", f"no DIR setup wait: {_ONE_T_WHY}", st.version_at)
        hold = not_enforced("M569 T", f"no DIR hold wait: {_ONE_T_WHY}", st.version_at)
        hold_t = hold
    elif any(d in slow for d in drivers) and worst:
        pulse, idle, setup, hold_t = worst
        hold = _hold(pulse, hold_t)
    else:
        why = _FAST
        if expansion:
            why = (f"expansion board driver {expansion[0]} without T: its own firmware's "
                   "timing, not in this file")  # fmt: skip
        pulse = not_enforced("M569 T", why, "firmware default", unit="us")
        idle = pulse
        setup = not_enforced("M569 T", f"no DIR setup wait: {why}", "firmware default")
        hold = not_enforced("M569 T", f"no DIR hold wait: {why}", "firmware default")
        hold_t = None
    info = {"drivers": ",".join(d.removeprefix("0.") for d in drivers)}
    rate = Guaranteed(None, "M203", "", "mm/min", "unknown", "no M92/M203 for this axis")
    if name in st.spm:
        info["steps/mm"] = f"{float(st.spm[name][0]):g} (M92, {st.spm[name][1]})"
    if name in st.speed:
        info["max speed"] = f"{float(st.speed[name][0]):g} mm/min (M203, {st.speed[name][1]})"
    if name[0] == "E" and name[1:].isdigit() and int(name[1:]) > 0:
        # M203 E sets the extruders in order: a fix must repeat the ones before this one
        before = [st.speed.get(f"E{i}", (None, ""))[0] for i in range(int(name[1:]))]
        if all(v is not None for v in before):
            info["M203 E before"] = ":".join(at_most(v) for v in before if v is not None)
    if name in st.coupled:
        rate = unknown("M203", f"kinematics {st.coupled[name]} couple {name} with other axes: "
                       "its motor may step faster than M92 x M203 / 60")  # fmt: skip
    elif name in st.spm and name in st.speed:
        hz = st.spm[name][0] * st.speed[name][0] / 60
        rate = Guaranteed(hz, "M92 x M203 / 60", st.speed[name][1], "mm/min", "derived")
    return GeneratorGuarantee(
        axis=name,
        pulse=pulse,
        idle=idle,
        dir_setup=setup,
        dir_hold=hold,
        max_rate=rate,
        dir_hold_trailing=hold_t,
        dir_inverted=st.backwards.get(drivers[0], False),
        info=info,
        aliases=("E",) if name == "E0" else (),
        notes=_mixed_direction(drivers, st),
    )


def _mixed_direction(drivers: list[str], st: _State) -> tuple[str, ...]:
    """A note when an axis's drivers run in different directions (M569 S per driver, e.g. a
    gantry's second Y motor mounted mirrored): DIR is inverted on some of them only, and the
    axis's DIR polarity shown is its first driver's."""
    back = [d.removeprefix("0.") for d in drivers if st.backwards.get(d, False)]
    if not back or len(back) == len(drivers):
        return ()
    return (
        f"M569 S0 (backwards) on driver {', '.join(back)} only: DIR is inverted there and not on "
        f"the axis's other drivers; the DIR polarity shown is driver "
        f"{drivers[0].removeprefix('0.')}'s",
    )


#: Duet3Expansion's Platform::SetDriverStepTiming (as indexed) waits only for fields over 0.2 us,
#: rounds them up to its step clocks (``+ 0.99``) and waits on a free-running step-clock counter
#: read at any phase (``GetTimerTicks() - DDA::lastStepLowTime < clocks``): up to one step clock
#: short, and the board's step clock rate is not in the file.
_EXPANSION = (
    "the expansion board waits whole ticks of its own step clock, whose rate the file does not "
    "give, from a counter read at any phase, and ignores fields of 0.2 us or less "
    "(Duet3Expansion Platform::SetDriverStepTiming)"
)


def _zero(at: str, field_no: int) -> Guaranteed:
    """A T field of 0: RRF waits 0 clocks for it (not enforced)."""
    return not_enforced(f"M569 T (field {field_no + 1})", "a 0 us field is no wait", at,
                        unit="us")  # fmt: skip


def _hold(pulse: Guaranteed, hold_t: Guaranteed) -> Guaranteed:
    """DIR changes only after STEP went low (DDA::StepDrivers lowers the pins before the
    direction is updated) and after field 4 from that: from the rising edge, field 1 + 4."""
    note = "hold counts from the falling edge: from the rising edge add the high time"
    total = (pulse.value or Fraction(0)) + (hold_t.value or Fraction(0))
    if not total:
        return not_enforced("M569 T fields 1 + 4", "both 0: no wait", hold_t.where)
    if pulse.banded or hold_t.banded:  # an expansion board's fields: their band carries over
        return uncertain(total, "M569 T fields 1 + 4", hold_t.where, "us", None, _EXPANSION, note)
    return Guaranteed(total, "M569 T fields 1 + 4", hold_t.where, "us", "derived", note)


def _fix(axis: GeneratorGuarantee, role: FixRole, need: Fraction) -> str:
    drivers = [d for d in axis.info.get("drivers", "").split(",") if d]
    field_no = {"pulse": 0, "idle": 1, "setup": 2, "trailing_hold": 3, "hold": 3}.get(role)
    if field_no is None or not drivers:
        spm = axis.info.get("steps/mm", "").split(" ")[0]
        if spm and Fraction(spm) > 0:
            value = at_most(need * 60 / Fraction(spm))
            if axis.axis[0] == "E" and axis.axis != "E0":
                before = axis.info.get("M203 E before")
                if before is None:
                    return f"lower M203 E for {axis.axis} to at most {value} mm/min"
                return f"add `M203 E{before}:{value}` (mm/min, {axis.axis} last)"
            return f"add `M203 {axis.axis[0] if axis.axis == 'E0' else axis.axis}{value}` (mm/min)"
        return f"lower M203 {axis.axis} so that it steps at most {float(need):.6g} steps/s"
    trailing = axis.dir_hold_trailing
    current = [axis.pulse.value, axis.idle.value, axis.dir_setup.value,
               trailing.value if trailing is not None else None]  # fmt: skip
    fields = [v or Fraction(0) for v in current]
    if role == "hold":
        need -= fields[0]  # field 4 counts from the falling edge
    fields[field_no] = max(fields[field_no], need)
    t = ":".join(at_least(f / 1000) for f in fields)
    return "add " + " and ".join(f"`M569 P{d} T{t}`" for d in drivers) + " (us)"


def _fix_one_t(axis: GeneratorGuarantee, role: FixRole, need: Fraction) -> str:
    """Before 1.21 T is one value, the high and the low time both (see :data:`_ONE_T_WHY`)."""
    drivers = [d for d in axis.info.get("drivers", "").split(",") if d]
    if role not in ("pulse", "idle") or not drivers:
        return _fix(axis, role, need)
    t = at_least(max(need, axis.pulse.value or Fraction(0)) / 1000)
    return (
        "add "
        + " and ".join(f"`M569 P{d} T{t}`" for d in drivers)
        + (" (us; before 1.21 one value sets the high and the low time)")
    )
