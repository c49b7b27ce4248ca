"""Klipper: ``printer.cfg`` (reference ``firmware-timing.md`` §3).

Read per ``[stepper_*]``/``[extruder*]`` section: ``step_pin``/``dir_pin`` (a leading ``!``
inverts), ``step_pulse_duration`` (s), ``microsteps``, ``rotation_distance``,
``full_steps_per_rotation`` (default 200), ``gear_ratio``; ``[printer] max_velocity`` and
``max_z_velocity`` (mm/s); a ``[tmc2130|2208|2209|2240|2660|5160 NAME]`` section with
``uart_pin`` or ``cs_pin`` for the same stepper.

Klipper's own rules: the default pulse is 2 µs, or 100 ns with both-edge stepping requested
when a TMC section drives the stepper over UART/SPI; an explicit ``step_pulse_duration``
always wins. Both edges are used only for a pulse ≤ 500 ns on an MCU that is not AVR. On the
full step path (ARM, single edge) pulse, space, DIR setup and DIR hold (from the leading edge)
are each ≥ the duration; on the AVR fast path (pulse ≤ 2.5 µs) the pulse is instruction time
and on the both-edge fast path the MCU enforces no minimum: those figures are ``uncertain`` or
unknown. The MCU is taken as AVR when the file's comments name an ATmega/AVR.
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass, field
from fractions import Fraction

from wavecheck.errors import ConfigError
from wavecheck.firmware._text import number, read_text, where
from wavecheck.firmware.model import (
    FirmwareConfig,
    GeneratorGuarantee,
    Guaranteed,
    Role,
    unknown,
)

__all__ = ["TMC_SECTIONS", "looks_like", "read"]

#: TMC sections that switch a stepper to 100 ns and both-edge stepping (klippy/extras/tmc.py).
TMC_SECTIONS = ("tmc2130", "tmc2208", "tmc2209", "tmc2240", "tmc2660", "tmc5160")
_DEFAULT_NS = Fraction(2000)
_TMC_NS = Fraction(100)
_BOTH_EDGE_MAX_NS = 500
_AVR_FAST_NS = 2500
_SECTION = re.compile(r"^\[([^\]]+)\]\s*(?:[#;].*)?$")
_KEY = re.compile(r"^([A-Za-z0-9_]+)\s*[:=]\s*(.*?)\s*(?:[#;].*)?$")


@dataclass
class _Section:
    name: str
    line: int
    keys: dict[str, tuple[str, int]] = field(default_factory=dict)


def looks_like(text: str) -> bool:
    """A Klipper config: a ``[stepper_…]`` or ``[printer]`` section and ``key: value`` lines."""
    return bool(re.search(r"^\[(stepper_\w+|printer)\]", text, re.M)) and bool(
        re.search(r"^\w+\s*:", text, re.M)
    )


def _parse(text: str) -> tuple[dict[str, _Section], bool]:
    sections: dict[str, _Section] = {}
    current: _Section | None = None
    avr = bool(re.search(r"^#.*\b(atmega\w*|AVR)\b", text, re.M | re.I))
    for no, raw in enumerate(text.splitlines(), 1):
        if not raw.strip() or raw.lstrip()[0] in "#;" or raw[0] in " \t":
            continue
        m = _SECTION.match(raw.strip())
        if m:
            name = " ".join(m.group(1).split())
            current = sections.setdefault(name, _Section(name, no))
            continue
        k = _KEY.match(raw)
        if k and current is not None:
            current.keys[k.group(1).lower()] = (k.group(2), no)
    return sections, avr


def _steps_per_mm(path: str, sec: _Section) -> tuple[Fraction | None, str]:
    keys = sec.keys
    if "rotation_distance" not in keys or "microsteps" not in keys:
        return None, ""
    full = number(*_kv(path, keys, "full_steps_per_rotation", "200"), "full_steps_per_rotation")
    micro = number(*_kv(path, keys, "microsteps"), "microsteps")
    dist = number(*_kv(path, keys, "rotation_distance"), "rotation_distance")
    ratio = Fraction(1)
    if "gear_ratio" in keys:
        for pair in keys["gear_ratio"][0].split(","):
            a, _, b = pair.partition(":")
            place = where(path, keys["gear_ratio"][1])
            ratio *= number(a, place, "gear_ratio") / number(b or "1", place, "gear_ratio")
    if dist <= 0:
        raise ConfigError(
            f"{where(path, keys['rotation_distance'][1])}: rotation_distance must be > 0"
        )
    spm = full * micro * ratio / dist
    return (
        spm,
        f"{float(spm):g} (full_steps_per_rotation x microsteps x gear_ratio / rotation_distance, {where(path, keys['rotation_distance'][1])})",
    )


def _kv(
    path: str, keys: dict[str, tuple[str, int]], key: str, default: str | None = None
) -> tuple[str, str]:
    if key in keys:
        return keys[key][0], where(path, keys[key][1])
    assert default is not None
    return default, "firmware default"


def read(path: str | os.PathLike[str]) -> FirmwareConfig:
    """Read a ``printer.cfg`` (see the module doc)."""
    p = str(path)
    sections, avr = _parse(read_text(path))
    printer = sections.get("printer")
    tmc: dict[str, tuple[str, int]] = {}
    for name, sec in sections.items():
        kind, _, target = name.partition(" ")
        if kind in TMC_SECTIONS and target and ("uart_pin" in sec.keys or "cs_pin" in sec.keys):
            tmc[target] = (kind, sec.line)
    axes = []
    for name, sec in sections.items():
        if not (name.startswith("stepper_") or name.startswith("extruder")) or " " in name:
            continue
        if "step_pin" not in sec.keys:
            continue
        axes.append(_axis(p, sec, tmc.get(name), printer, avr))
    if not axes:
        raise ConfigError(f"{path}: no [stepper_*] or [extruder] section with a step_pin")
    mcu = "AVR (named in the file's comments)" if avr else "not AVR (no ATmega/AVR named)"
    return FirmwareConfig(
        firmware="klipper",
        path=p,
        axes=tuple(axes),
        files=(p,),
        notes=(
            f"MCU taken as {mcu}: it decides which step path runs",
            "step_pulse_duration is truncated to MCU clock ticks (100 ns at 72 MHz is 97.2 ns)",
            "Klipper drops a step followed by an opposite step less than 750 us later (host side)",
        ),
        fixer=_fix,
    )


def _axis(
    path: str,
    sec: _Section,
    tmc: tuple[str, int] | None,
    printer: _Section | None,
    avr: bool,
) -> GeneratorGuarantee:
    keys = sec.keys
    step_pin = keys["step_pin"][0]
    dir_pin = keys.get("dir_pin", ("", 0))[0]
    notes: list[str] = []
    if "step_pulse_duration" in keys:
        raw, line = keys["step_pulse_duration"]
        ns = number(raw, where(path, line), "step_pulse_duration") * 10**9
        src = ("step_pulse_duration", where(path, line), "s", "set")
    elif tmc is not None:
        ns = _TMC_NS
        src = (
            "step_pulse_duration",
            f"firmware default ([{tmc[0]} {sec.name}] at {where(path, tmc[1])})",
            "s",
            "default",
        )
    else:
        ns = _DEFAULT_NS
        src = ("step_pulse_duration", "firmware default", "s", "default")
    if ns < 0 or ns > 10**6:
        raise ConfigError(f"{src[1]}: step_pulse_duration must be 0 .. 0.001 s")
    both = tmc is not None and ns <= _BOTH_EDGE_MAX_NS and not avr
    if tmc is not None and not both:
        why = "the MCU is AVR" if avr else f"the pulse {float(ns):g} ns is over 500 ns"
        notes.append(f"{tmc[0]} requests both-edge stepping, refused because {why}")

    def fig(status: str = "", note: str = "") -> Guaranteed:
        return Guaranteed(ns, src[0], src[1], src[2], status or src[3], note)  # type: ignore[arg-type]

    if both:
        pulse = fig(
            "uncertain",
            "both-edge fast path: toggles follow the host schedule; the MCU enforces no minimum",
        )
        idle, setup, hold = pulse, pulse, pulse
        trailing = pulse
        notes.append(
            f"both-edge stepping ({tmc[0] if tmc else ''} dedge): every STEP edge is a step"
        )
    elif avr and ns <= _AVR_FAST_NS:
        pulse = unknown(
            "step_pulse_duration",
            "AVR fast path: both STEP writes in one event, the pulse is instruction time",
            src[1],
        )
        idle = fig("uncertain", "the next step is scheduled at least this long after the last one")
        setup = fig("uncertain")
        hold = unknown(
            "step_pulse_duration",
            "AVR fast path: DIR may toggle between the two STEP edges",
            src[1],
        )
        trailing = None
    else:
        pulse, idle, setup, hold = fig(), fig(), fig(), fig()
        trailing = Guaranteed(
            Fraction(0),
            src[0],
            src[1],
            src[2],
            "derived",
            "DIR toggles right after the trailing edge",
        )
    info: dict[str, str] = {}
    spm, spm_text = _steps_per_mm(path, sec)
    if spm_text:
        info["steps/mm"] = spm_text
    speed_key = "max_z_velocity" if sec.name == "stepper_z" else "max_velocity"
    max_rate = Guaranteed(
        None, "max_velocity", "", "mm/s", "unknown", "Klipper has no step-rate setting"
    )
    if printer is not None and not sec.name.startswith("extruder"):
        found = printer.keys.get(speed_key) or printer.keys.get("max_velocity")
        name = speed_key if speed_key in printer.keys else "max_velocity"
        if found and spm is not None:
            v = number(found[0], where(path, found[1]), name)
            info["max speed"] = f"{found[0]} mm/s ([printer] {name}, {where(path, found[1])})"
            max_rate = Guaranteed(
                v * spm,
                f"{name} x steps/mm",
                where(path, found[1]),
                "mm/s",
                "derived",
                "cartesian kinematics assumed (corexy/delta steppers may run faster)",
            )
    return GeneratorGuarantee(
        axis=sec.name,
        pulse=pulse,
        idle=idle,
        dir_setup=setup,
        dir_hold=hold,
        max_rate=max_rate,
        pulse_level=0 if step_pin.lstrip("^~").startswith("!") else 1,
        both_edges=both,
        dir_hold_trailing=trailing,
        dir_inverted=dir_pin.lstrip("^~").startswith("!"),
        info=info,
        notes=tuple(notes),
    )


def _fix(axis: GeneratorGuarantee, role: Role, need: Fraction) -> str:
    if (
        role == "max_rate"
        or role == "idle"
        and axis.both_edges is False
        and axis.max_rate.known
        and axis.pulse.value is not None
        and axis.pulse.value >= need
    ):
        return f"lower max_velocity in [printer] so that {axis.axis} steps at most {float(need if role == 'max_rate' else Fraction(10**9) / (axis.pulse.value + need)):.6g} steps/s"  # type: ignore[operator]
    s = float(need / 10**9)
    extra = (
        " (over 0.0000005 this turns both-edge stepping off)"
        if axis.both_edges and need > _BOTH_EDGE_MAX_NS
        else ""
    )
    return f"set `step_pulse_duration: {s:.9g}` in [{axis.axis}]{extra}"
