"""Klipper: ``printer.cfg`` (reference ``firmware-timing.md`` §3; ``docs/Config_Reference.md``).

Every section with a ``step_pin`` is a step generator: ``[stepper_x]``, ``[stepper_z1]``,
``[extruder1]``, ``[extruder_stepper NAME]``, ``[dual_carriage]``, ``[manual_stepper NAME]``,
``[stepper_a]`` … Read per stepper: ``step_pin``/``dir_pin`` (a leading ``!`` inverts; a
``name:`` prefix puts the pin on another MCU), ``step_pulse_duration`` (s), ``microsteps``,
``rotation_distance``, ``full_steps_per_rotation`` (default 200), ``gear_ratio``; a
``[tmc2130|2208|2209|2240|2660|5160 NAME]`` section with ``uart_pin`` or ``cs_pin`` for the same
stepper; ``[printer] kinematics``, ``max_velocity`` and ``max_z_velocity`` (mm/s, default
``max_velocity``). ``[include FILE]`` sections are followed (beside the file, globs allowed).

Klipper's own rules: the default pulse is 2 µs, or 100 ns with both-edge stepping requested
when a TMC section drives the stepper over UART/SPI; an explicit ``step_pulse_duration`` always
wins. Both edges are used only for a pulse ≤ 500 ns on an MCU that is not AVR. On the full step
path (single edge) pulse, space, DIR setup and DIR hold (from the leading edge) are each ≥ the
duration (klipper ``src/stepper.c`` 180-206, 111-121), and DIR changes right after the trailing
edge. Not enforced by the firmware (never a PASS; "measure it"): every figure of the AVR fast
path (pulse ≤ 40 ticks: both STEP writes in one event, ``stepper_event_avr`` 160-176) and of the
optimised both-edge path (``step_pulse_ticks`` ≤ ⌈clock / 8 MHz⌉: ``stepper_event_edge`` 138-151,
DIR toggled right after the last edge; an STM32H7, Linux or BeagleBone PRU build has no such path). The both-edge full path (longer pulses) keeps each edge,
DIR setup and hold ≥ the duration (113-120, 184-195). The duration is truncated to whole MCU
clock ticks (:data:`MCUS`, Klipper's Kconfig clocks).

The MCU of each stepper is read from the chip names in the file's header comments and in its
``[mcu]`` section (its ``serial:`` path names the chip), and from its pins (a port pin numbered
8 or more, ``P1.20`` or ``gpio5`` is no ATmega). When nothing decides it, an AVR is possible and
the figures that depend on it are unknown, with the reason.

The max step rate is ``max_velocity × steps/mm`` only where the stepper moves one cartesian
axis: ``[stepper_z*]`` (``max_z_velocity``) on cartesian, corexy and hybrid-corexy machines,
x/y/dual-carriage steppers on cartesian ones, ``y`` on corexz; a motor of a coupled pair or a
delta tower may step faster, so its rate is unknown.
"""

from __future__ import annotations

import glob
import os
import re
from dataclasses import dataclass, field
from fractions import Fraction
from pathlib import Path

from wavecheck.errors import ConfigError
from wavecheck.firmware._text import is_file, number, read_text, where
from wavecheck.firmware.guarantee import (
    MAX_AXES,
    FirmwareConfig,
    FixRole,
    GeneratorGuarantee,
    Guaranteed,
    at_most,
    not_enforced,
    unknown,
)

__all__ = ["MCUS", "TMC_SECTIONS", "looks_like", "read"]

#: TMC sections that switch a stepper to 100 ns and both-edge stepping (klippy/extras/tmc.py).
TMC_SECTIONS = ("tmc2130", "tmc2208", "tmc2209", "tmc2240", "tmc2660", "tmc5160")
#: Chip name pattern → (AVR?, the clocks Klipper's Kconfig offers for it, Hz; empty: not read).
MCUS: tuple[tuple[str, bool, tuple[int, ...]], ...] = (
    (r"atmega(2560|1280|1281|32u4)|at90usb\d+", True, (16_000_000, 8_000_000)),
    (r"atmega(1284p?|644p?|328p?|168)", True, (16_000_000, 20_000_000, 8_000_000)),
    (r"stm32f0\d\d", False, (48_000_000,)),
    (r"stm32f103|gd32f103", False, (72_000_000, 64_000_000)),
    (r"stm32f207", False, (120_000_000,)),
    (r"stm32f401", False, (84_000_000,)),
    (r"stm32f40[57]", False, (168_000_000,)),
    (r"stm32f446", False, (180_000_000,)),
    (r"stm32h723\w*", False, (520_000_000,)),
    (r"stm32h743\w*", False, (400_000_000,)),
    (r"lpc1768", False, (100_000_000,)),
    (r"lpc1769", False, (120_000_000,)),
    (r"stm32\w+|gd32\w+|lpc17\d\d|sam[a-z]?\d\w*|atsam\w*|rp2040|hc32\w+|"
     r"esp32\w*|beaglebone|linux|raspberry|ar100", False, ()),
)  # fmt: skip
_DEFAULT_NS = Fraction(2000)
_TMC_NS = Fraction(100)
_BOTH_EDGE_MAX_NS = 500
_AVR_FAST_TICKS = 40
_MAX_NS = 10**6  # step_pulse_duration 0 .. 0.001 s
_MAX_INCLUDES = 64
_SECTION = re.compile(r"^\[([^\]]+)\]\s*(?:[#;].*)?$")
_KEY = re.compile(r"^([A-Za-z0-9_]+)\s*[:=]\s*(.*?)\s*(?:\s[#;].*)?$")
_CHIP = re.compile("|".join(f"(?:{m[0]})" for m in MCUS), re.I)
_AXIS_OF = re.compile(r"^stepper_([a-z])\d*$|^(dual_carriage)$")


@dataclass
class _Section:
    name: str
    path: str
    line: int
    keys: dict[str, tuple[str, int]] = field(default_factory=dict)

    def at(self, key: str) -> str:
        return where(self.path, self.keys[key][1])


@dataclass(frozen=True)
class _Mcu:
    """What the file tells of one MCU: AVR (True/False/None = undecided) and its clocks."""

    name: str
    avr: bool | None
    clocks: tuple[int, ...]
    why: str
    chips: tuple[str, ...] = ()
    """The chip names the file gives for it (lower case)."""


#: Section headers only a Klipper file has (lower-case module names; LinuxCNC's are upper-case).
_KLIPPER_SECTION = (
    r"^\[(stepper_\w+|printer|extruder\w*|mcu|gcode_macro|display_glyph|pwm_tool|output_pin"
    r"|bed_mesh|safe_z_home|heater_bed|temperature_sensor|probe|bltouch)\b[^\]\n]*\]"
)


def looks_like(text: str) -> bool:
    """A Klipper config: ``[section]`` headers with ``key: value`` lines, one of them a
    ``[stepper_…]``, ``[printer]``, ``[extruder…]`` or ``[mcu]`` section, or one of the add-on
    sections only Klipper names (``[gcode_macro …]``, ``[display_glyph …]``, ``[pwm_tool …]`` …:
    such a file is Klipper's, and is refused because it has no stepper)."""
    return bool(re.search(_KLIPPER_SECTION, text, re.M)) and bool(
        re.search(r"^\w+[ \t]*:", text, re.M)
    )


def _parse(
    path: Path, sections: dict[str, _Section], header: list[str], seen: set[Path]
) -> list[str]:
    """Sections of ``path`` (and its includes) into ``sections``; returns notes."""
    notes: list[str] = []
    current: _Section | None = None
    text = read_text(path)
    for no, raw in enumerate(text.splitlines(), 1):
        stripped = raw.strip()
        if not stripped:
            continue
        if stripped[0] in "#;":
            if current is None or current.name.split(" ")[0] == "mcu":
                header.append(stripped)
            continue
        if raw[0] in " \t":
            continue  # a continuation line of a multi-line value
        m = _SECTION.match(stripped)
        if m:
            name = " ".join(m.group(1).split())
            if name.startswith("include "):
                notes += _include(path, name[len("include ") :].strip(), sections, header, seen)
                current = None
                continue
            current = sections.setdefault(name, _Section(name, str(path), no))
            continue
        k = _KEY.match(raw)
        if k and current is not None:
            current.keys[k.group(1).lower()] = (k.group(2), no)
    return notes


def _include(
    path: Path, pattern: str, sections: dict[str, _Section], header: list[str], seen: set[Path]
) -> list[str]:
    try:
        found = sorted(
            Path(p) for p in glob.glob(os.path.join(path.parent, pattern))[:_MAX_INCLUDES]
        )
    except (OSError, ValueError):
        found = []
    if not found:
        return [f"{path}: [include {pattern}] matches no file beside it; not read"]
    notes: list[str] = []
    for inc in found:
        if not is_file(inc) or inc.resolve() in seen:
            continue
        if len(seen) >= _MAX_INCLUDES:
            raise ConfigError(f"{path}: more than {_MAX_INCLUDES} included files")
        seen.add(inc.resolve())
        notes += _parse(inc, sections, header, seen)
    return notes


def read(path: str | os.PathLike[str]) -> FirmwareConfig:
    """Read a ``printer.cfg`` (see the module doc)."""
    p = Path(path)
    sections: dict[str, _Section] = {}
    header: list[str] = []
    notes = _parse(p, sections, header, {p.resolve()})
    printer = sections.get("printer")
    tmc: dict[str, _Section] = {}
    for name, sec in sections.items():
        kind, _, target = name.partition(" ")
        if kind in TMC_SECTIONS and target and ("uart_pin" in sec.keys or "cs_pin" in sec.keys):
            tmc[target] = sec
    steppers = [s for s in sections.values() if "step_pin" in s.keys]
    if not steppers:
        missing = [n.split("] ")[0].split("[include ", 1)[1] for n in notes if "matches no" in n]
        if missing:  # the steppers are most likely in the includes that are not there
            raise ConfigError(
                f"{p}: no section with a step_pin, and {len(missing)} [include] "
                f"match no file beside it (first: {missing[0]}): give the folder with the "
                "included files"
            )
        raise ConfigError(
            f"{p}: no section with a step_pin (a Klipper file without steppers: nothing to check)"
        )
    if len(steppers) > MAX_AXES:
        raise ConfigError(f"{p}: {len(steppers)} stepper sections (at most {MAX_AXES} are read)")
    mcus = _mcus(sections, header, steppers)
    kinematics = printer.keys.get("kinematics", ("", 0))[0].lower() if printer else ""
    axes = [_axis(str(p), sec, tmc.get(sec.name), printer, kinematics, mcus) for sec in steppers]
    return FirmwareConfig(
        firmware="klipper",
        path=str(p),
        axes=tuple(axes),
        files=tuple(dict.fromkeys([str(p), *(s.path for s in sections.values())])),
        notes=(
            *(f"MCU {m.name}: {m.why}" for m in mcus.values()),
            f"kinematics {kinematics or 'not given'}"
            + (
                f" ({printer.at('kinematics')})" if printer and "kinematics" in printer.keys else ""
            ),
            "Klipper drops a step followed by an opposite step less than 750 us later (host side)",
            *notes,
        ),
        fixer=_fix,
    )


def _bare(pin: str) -> tuple[bool, str, str]:
    """(inverted, MCU name, pin) of Klipper's ``[^~][!][mcu:]pin``."""
    text = pin.strip().lstrip("^~").strip()
    inverted = text.startswith("!")
    name, sep, rest = text.lstrip("!").partition(":")
    return inverted, (name.strip() if sep else "mcu"), (rest if sep else name).strip()


def _mcu_of(pin: str) -> str:
    return _bare(pin)[1]


def _mcus(
    sections: dict[str, _Section], header: list[str], steppers: list[_Section]
) -> dict[str, _Mcu]:
    out: dict[str, _Mcu] = {}
    names = {_mcu_of(s.keys["step_pin"][0]) for s in steppers}
    for name in sorted(names):
        sec = sections.get("mcu" if name == "mcu" else f"mcu {name}")
        texts = [v for v, _ in sec.keys.values()] if sec else []
        # the file's header comment names the board it is for: the main MCU's, or in a file
        # without an [mcu] section (a CAN toolhead board's sample) the one MCU its steppers use
        if name == "mcu" or ("mcu" not in sections and len(names) == 1):
            texts += header
        chips = {m.group(0).lower() for t in texts for m in _CHIP.finditer(t)}
        found = [
            (c, next(row for row in MCUS if re.fullmatch(row[0], c, re.I)))
            for c in sorted(chips)
            if any(re.fullmatch(row[0], c, re.I) for row in MCUS)
        ]
        pins = [
            _bare(s.keys[k][0])[2]
            for s in steppers
            if _mcu_of(s.keys["step_pin"][0]) == name
            for k in ("step_pin", "dir_pin")
            if k in s.keys
        ]
        not_avr_pin = next((q for q in pins if _not_avr_pin(q)), None)
        if found:
            avrs = {row[1] for _, row in found}
            clocks = tuple(sorted({c for _, row in found for c in row[2]}))
            if not_avr_pin and True in avrs:
                avrs = {False}
            avr = avrs.pop() if len(avrs) == 1 else None
            chip = ", ".join(sorted({c for c, _ in found}))
            why = f"{chip} named in the file" + (
                "" if avr is not None else " (AVR and ARM both named: AVR possible)"
            )
            out[name] = _Mcu(name, avr, clocks if all(row[2] for _, row in found) else (), why,
                             tuple(sorted({c for c, _ in found})))  # fmt: skip
        elif not_avr_pin:
            out[name] = _Mcu(name, False, (), f"no chip named; pin {not_avr_pin} is no ATmega pin")
        else:
            out[name] = _Mcu(
                name, None, (),
                "no chip named and its pins fit an ATmega: AVR possible (figures that depend on "
                "it are unknown)",
            )  # fmt: skip
    return out


def _not_avr_pin(pin: str) -> bool:
    """True for a pin name no ATmega has: a port pin numbered 8 or more, ``P1.20``, ``gpio5``."""
    m = re.fullmatch(r"P([A-Z])(\d{1,3})", pin, re.I)
    if m:
        return int(m.group(2)) >= 8
    return bool(re.fullmatch(r"P\d+\.\d+|gpio\d+(_\d+)?", pin, re.I))


def _steps_per_mm(path: str, sec: _Section) -> tuple[Fraction | None, str]:
    keys = sec.keys
    if "rotation_distance" not in keys or "microsteps" not in keys:
        return None, ""
    full = (
        number(keys["full_steps_per_rotation"][0], sec.at("full_steps_per_rotation"),
               "full_steps_per_rotation", low=1, high=10**6)
        if "full_steps_per_rotation" in keys
        else Fraction(200)
    )  # fmt: skip
    micro = number(keys["microsteps"][0], sec.at("microsteps"), "microsteps", low=1, high=10**6)
    dist = number(keys["rotation_distance"][0], sec.at("rotation_distance"), "rotation_distance",
                  low=0, high=10**9)  # fmt: skip
    if dist == 0:
        raise ConfigError(f"{sec.at('rotation_distance')}: rotation_distance must be > 0")
    ratio = Fraction(1)
    if "gear_ratio" in keys:
        place = sec.at("gear_ratio")
        for pair in keys["gear_ratio"][0].split(",")[:16]:
            a, _, b = pair.partition(":")
            ratio *= number(a, place, "gear_ratio", low=0, high=10**6) / number(
                b or "1", place, "gear_ratio", low=Fraction(1, 10**6), high=10**6
            )
    spm = full * micro * ratio / dist
    text = (
        f"{float(spm):g} (full_steps_per_rotation x microsteps x gear_ratio / rotation_distance, "
        f"{sec.at('rotation_distance')})"
    )
    return spm, text


def _pulse_source(
    path: str, sec: _Section, tmc: _Section | None
) -> tuple[Fraction, tuple[str, str, str, str]]:
    if "step_pulse_duration" in sec.keys:
        at = sec.at("step_pulse_duration")
        raw = sec.keys["step_pulse_duration"][0]
        ns = number(raw, at, "step_pulse_duration", low=0, high=Fraction(1, 1000), unit="s") * 10**9
        return ns, ("step_pulse_duration", at, "s", "set")
    if tmc is not None:
        return _TMC_NS, (
            "step_pulse_duration",
            f"firmware default ([{tmc.name}] at {where(tmc.path, tmc.line)})",
            "s",
            "default",
        )
    return _DEFAULT_NS, ("step_pulse_duration", "firmware default", "s", "default")


def _truncated(ns: Fraction, mcu: _Mcu) -> tuple[Fraction, str, bool]:
    """(the pulse after truncation to MCU ticks, a note, exact?)."""
    if mcu.clocks:
        made = min(Fraction(int(ns * f / 10**9), f) * 10**9 for f in mcu.clocks)
        if made == ns:
            return ns, "", True
        mhz = "/".join(f"{f / 1e6:g}" for f in mcu.clocks)
        return made, f"truncated to whole ticks of the MCU clock ({mhz} MHz)", True
    if (ns / 1000).denominator == 1:
        return ns, "", True  # a whole us is a whole number of ticks of every whole-MHz clock
    return ns, "truncated to whole MCU clock ticks (clock not known: up to one tick shorter)", False


#: The slowest MCU clocks Klipper builds for (its Kconfig): an 8 MHz AVR (src/avr/Kconfig:87),
#: else the 12 MHz RP2040 (src/rp2040/Kconfig:41). ``step_pulse_ticks`` is
#: ``seconds_to_clock(step_pulse_duration)`` (klippy/stepper.py:112) = ``int(time * freq)``
#: (klippy/mcu.py:1141): truncated, less than one tick short.
_SLOWEST_AVR_HZ, _SLOWEST_ARM_HZ = 8_000_000, 12_000_000


def _unknown_clock_short(mcu: _Mcu) -> tuple[Fraction, str]:
    """How far below the set duration the MCU's truncation may put it when its clock is not
    known: one tick of the slowest clock the MCU may have."""
    hz = _SLOWEST_AVR_HZ if mcu.avr is not False else _SLOWEST_ARM_HZ
    where = "src/avr/Kconfig:87" if mcu.avr is not False else "src/rp2040/Kconfig:41"
    why = (
        f"one tick of a {hz / 1e6:g} MHz MCU clock, the slowest this MCU may have ({where}): "
        "step_pulse_ticks = int(duration x clock) (klippy/mcu.py:1141, klippy/stepper.py:112)"
    )
    return Fraction(10**9, hz), why


def _axis(
    path: str,
    sec: _Section,
    tmc: _Section | None,
    printer: _Section | None,
    kinematics: str,
    mcus: dict[str, _Mcu],
) -> GeneratorGuarantee:
    keys = sec.keys
    step_pin = keys["step_pin"][0]
    dir_pin = keys.get("dir_pin", ("", 0))[0]
    mcu = mcus[_mcu_of(step_pin)]
    ns, src = _pulse_source(path, sec, tmc)
    notes: list[str] = []
    both_ok = tmc is not None and ns <= _BOTH_EDGE_MAX_NS
    both = both_ok and mcu.avr is False
    if tmc is not None and not both:
        why = (
            f"the pulse {float(ns):g} ns is over 500 ns"
            if not both_ok
            else ("the MCU is AVR" if mcu.avr else "the MCU may be AVR (not identified)")
        )
        notes.append(f"{tmc.name.split()[0]} requests both-edge stepping, refused because {why}")
    made, trunc, exact = _truncated(ns, mcu)
    status = src[3] if exact and not trunc else ("derived" if exact else "uncertain")
    short, short_why = (Fraction(0), "") if exact else _unknown_clock_short(mcu)

    def fig(st: str = "", note: str = "") -> Guaranteed:
        text = "; ".join(x for x in (note, trunc) if x)
        return Guaranteed(made, src[0], src[1], src[2], (st or status), text,  # type: ignore[arg-type]
                          short_by=short, short_why=short_why)  # fmt: skip

    fast_avr = mcu.avr is not False and (
        any(int(ns * f / 10**9) <= _AVR_FAST_TICKS for f in mcu.clocks)
        if mcu.clocks
        else ns <= 2500
    )
    trailing: Guaranteed | None
    if both:
        notes.append(
            f"both-edge stepping ({tmc.name.split()[0] if tmc else ''} dedge): every STEP edge is a step"
        )
        edge_path = _edge_path(made, mcu)
        if edge_path is False:
            # stepper_event_full with SF_SINGLE_SCHED: edges >= step_pulse_ticks apart
            # (src/stepper.c:184-195), DIR toggled only after that time (113-116) and the next
            # edge >= step_pulse_ticks after it (117-120)
            pulse = fig(note="both-edge full path: each edge >= the duration after the last")
            idle, setup, hold, trailing = pulse, pulse, pulse, pulse
        else:
            when = "" if edge_path else "if the MCU uses the optimised edge path (clock unknown): "
            pulse = not_enforced(
                "step_pulse_duration",
                f"{when}stepper_event_edge toggles STEP at the host's schedule with no minimum "
                "(klipper src/stepper.c:139-150)", src[1])  # fmt: skip
            idle = pulse
            setup = not_enforced(
                "step_pulse_duration",
                f"{when}DIR is toggled in stepper_load_next and the next edge follows at the "
                "host's schedule (src/stepper.c:86-89, 126-127)", src[1])  # fmt: skip
            hold = not_enforced(
                "step_pulse_duration",
                f"{when}DIR is toggled right after the move's last STEP toggle "
                "(src/stepper.c:150 -> stepper_load_next, 126-127)", src[1])  # fmt: skip
            trailing = hold
    elif fast_avr:
        what = "" if mcu.avr else "if the MCU is an AVR (not identified): "
        where_ = src[1]
        pulse = not_enforced(
            "step_pulse_duration",
            f"{what}stepper_event_avr writes both STEP edges in one event and never applies "
            "step_pulse_ticks: the pulse is instruction time (klipper src/stepper.c:163-168, "
            "238-240)", where_)  # fmt: skip
        idle = not_enforced(
            "step_pulse_duration",
            f"{what}the time to the next step is the host's schedule (src/stepper.c:167)",
            where_)  # fmt: skip
        setup = not_enforced(
            "step_pulse_duration",
            f"{what}DIR is toggled in stepper_load_next and the next step follows at the host's "
            "schedule (src/stepper.c:90-94, 126-127)", where_)  # fmt: skip
        hold = not_enforced(
            "step_pulse_duration",
            f"{what}on a move's last step DIR is toggled between the two STEP edges "
            "(src/stepper.c:173-174)", where_)  # fmt: skip
        trailing = hold
    else:
        pulse, idle, setup, hold = fig(), fig(), fig(), fig()
        trailing = Guaranteed(Fraction(0), src[0], src[1], src[2], "derived",
                              "DIR toggles right after the trailing edge "
                              "(src/stepper.c:200-201 -> 111-116)")  # fmt: skip
    info: dict[str, str] = {"mcu": f"{mcu.name} ({mcu.why})"}
    spm, spm_text = _steps_per_mm(path, sec)
    if spm_text:
        info["steps/mm"] = spm_text
    max_rate = _rate(sec, printer, kinematics, spm, info)
    alias = re.sub(
        r"^stepper_|^extruder(?=\d*$)", lambda m: "" if m.group(0) == "stepper_" else "e", sec.name
    )
    return GeneratorGuarantee(
        axis=sec.name,
        pulse=pulse,
        idle=idle,
        dir_setup=setup,
        dir_hold=hold,
        max_rate=max_rate,
        pulse_level=0 if _bare(step_pin)[0] else 1,
        both_edges=both,
        dir_hold_trailing=trailing,
        dir_inverted=_bare(dir_pin)[0],
        info=info,
        notes=tuple(notes),
        aliases=(alias,) if alias != sec.name else (),
    )


def _rate(
    sec: _Section,
    printer: _Section | None,
    kinematics: str,
    spm: Fraction | None,
    info: dict[str, str],
) -> Guaranteed:
    none = Guaranteed(
        None, "max_velocity", "", "mm/s", "unknown", "Klipper has no step-rate setting"
    )
    m = _AXIS_OF.match(sec.name)
    if printer is None or spm is None or m is None:
        return none
    axis = "x" if m.group(2) else m.group(1)
    # the rails set up with cartesian_stepper_alloc (klippy/kinematics/*.py setup_itersolve):
    # hybrid_corexy.py:21-22 and hybrid_corexz.py:21-22 move y and z alone, corexz.py:19 y
    cartesian_axes = {
        "cartesian": "xyz",
        "corexy": "z",
        "hybrid_corexy": "yz",
        "corexz": "y",
        "hybrid_corexz": "yz",
    }.get(kinematics, "")
    if axis not in cartesian_axes:
        what = f"{kinematics or 'unknown'} kinematics"
        return unknown("max_velocity",
                       f"{what}: {sec.name} does not move one cartesian axis alone and may step "
                       "faster than max_velocity x steps/mm")  # fmt: skip
    name = "max_z_velocity" if axis == "z" and "max_z_velocity" in printer.keys else "max_velocity"
    if name not in printer.keys:
        return none
    raw, _ = printer.keys[name]
    at = printer.at(name)
    v = number(raw, at, name, low=0, high=10**6, unit="mm/s")
    default = (
        " (max_z_velocity not set: max_velocity)" if axis == "z" and name == "max_velocity" else ""
    )
    info["max speed"] = f"{raw} mm/s ([printer] {name}, {at}){default}"
    return Guaranteed(v * spm, f"{name} x steps/mm", at, "mm/s", "derived",
                      f"{kinematics}: {sec.name} moves {axis} alone")  # fmt: skip


#: MCUs whose Klipper build has no optimised edge path: HAVE_EDGE_OPTIMIZATION needs
#: CONFIG_WANT_STEPPER_OPTIMIZED_BOTH_EDGE (src/stepper.c:19-21), which needs
#: HAVE_STEPPER_OPTIMIZED_BOTH_EDGE (src/Kconfig:299-304); src/stm32/Kconfig:16 selects it
#: "if !MACH_STM32H7", and src/linux and src/pru (a BeagleBone's) select it not at all. Their
#: both-edge steps run stepper_event_full with SF_SINGLE_SCHED (233-237, 224-227).
_NO_EDGE_PATH = re.compile(r"stm32h7\w*|linux|beaglebone", re.I)


def _edge_path(made: Fraction, mcu: _Mcu) -> bool | None:
    """Does the MCU run both-edge stepping on its optimised edge path (src/stepper.c:233-235:
    step_pulse_ticks <= EDGE_STEP_TICKS = ceil(clock / 8 MHz), line 132)? None: undecided."""
    no_edge = [bool(_NO_EDGE_PATH.fullmatch(c)) for c in mcu.chips]
    if no_edge and all(no_edge):
        return False
    if any(no_edge):
        return None
    if mcu.clocks:
        found = {int(made * f / 10**9) <= -(-f // 8_000_000) for f in mcu.clocks}
        return found.pop() if len(found) == 1 else None
    if made <= 125:
        return True
    return False if made > 250 else None


def _fix(axis: GeneratorGuarantee, role: FixRole, need: Fraction) -> str:
    # whole us: a whole number of ticks of every whole-MHz MCU clock (the host truncates to ticks)
    us: Fraction = max(Fraction(-(-need // 1000)), Fraction(1))
    if role == "trailing_hold":
        return (
            f"invert step_pin in [{axis.axis}] (add or remove its `!`) and set "
            f"`step_pulse_duration: {float(us / 10**6):.9g}` in [{axis.axis}]: Klipper changes DIR "
            "right after the pulse ends, so the drive's active edge must start a pulse that long"
        )
    if role == "max_rate" or (
        role == "idle"
        and not axis.both_edges
        and axis.max_rate.known
        and axis.pulse.value is not None
        and axis.pulse.value >= need
    ):
        rate = need if role == "max_rate" else Fraction(10**9) / ((axis.pulse.value or 0) + need)
        key = axis.max_rate.setting.split(" x ")[0]
        speed = axis.info.get("max speed", "").split(" ")[0]
        if axis.max_rate.value and speed:
            value = Fraction(speed) * rate / axis.max_rate.value
            return f"set `{key}: {at_most(value)}` in [printer] ({axis.axis} then steps at most {float(rate):.6g} steps/s)"
        return (
            f"lower {key} in [printer] so that {axis.axis} steps at most {float(rate):.6g} steps/s"
        )
    extra = (
        " (over 0.0000005 this turns both-edge stepping off)"
        if axis.both_edges and us * 1000 > _BOTH_EDGE_MAX_NS
        else ""
    )
    return f"set `step_pulse_duration: {float(us / 10**6):.9g}` in [{axis.axis}]{extra}"
