"""grbl 1.1 and grblHAL: a ``$$`` settings dump.

Read (reference ``firmware-timing.md`` §1–2): ``$0`` step pulse (µs; integer on grbl, float on
grblHAL), ``$2``/``$3`` step/dir invert masks (bit 0 = X), ``$29`` grblHAL's pulse delay (µs,
applied on a direction change), ``$100…`` steps/mm and ``$110…`` max rates (mm/min). Lines may
carry grbl 0.9's `` (description)`` and spaces around ``=``; a file holding several dumps (a
user's notes) is read up to the first repeated setting, the rest named in the notes.

Guarantees: the pulse is ≈ ``$0`` (grbl calibrates an interrupt-overhead offset on a 0.5 µs timer;
grblHAL rounds per driver) — status ``uncertain``. DIR is written a few CPU cycles before STEP
(setup ≈ 0) unless grblHAL's ``$29`` is set; hold after the leading edge ≥ one step tick ≥ the
pulse. The max step rate of an axis is ``$10n × $11n / 60``; grbl does not enforce its 30 kHz.
"""

from __future__ import annotations

import os
import re
from fractions import Fraction

from wavecheck.errors import ConfigError
from wavecheck.firmware._text import number, read_text, where
from wavecheck.firmware.model import FirmwareConfig, GeneratorGuarantee, Guaranteed, Role

__all__ = ["looks_like", "read"]

_LINE = re.compile(r"^\s*\$(\d+)\s*=\s*([-+0-9.eE]+)\s*(?:\((.*)\))?\s*$")
_AXES = "XYZABC"


def looks_like(text: str) -> bool:
    """A ``$$`` dump: a ``$0=`` line and at least two more ``$n=`` lines."""
    lines = [m for m in (_LINE.match(x) for x in text.splitlines()) if m]
    return len(lines) >= 3 and any(m.group(1) == "0" for m in lines)


def _settings(path: str, text: str) -> tuple[dict[int, tuple[Fraction, str, int]], list[str]]:
    found: dict[int, tuple[Fraction, str, int]] = {}
    notes: list[str] = []
    for no, line in enumerate(text.splitlines(), 1):
        m = _LINE.match(line)
        if not m:
            continue
        n = int(m.group(1))
        if n in found:
            notes.append(
                f"{path}: the dump that starts at line {found[min(found)][2]} is read; a second "
                f"one starts near line {no} and is ignored"
            )
            break
        found[n] = (number(m.group(2), where(path, no), f"${n}"), m.group(2), no)
    return found, notes


def read(path: str | os.PathLike[str]) -> FirmwareConfig:
    """Read a ``$$`` dump (see the module doc)."""
    text = read_text(path)
    settings, notes = _settings(str(path), text)
    if 0 not in settings:
        raise ConfigError(f"{path}: no $0 (step pulse) line: not a grbl $$ dump")
    hal = 29 in settings or settings[0][0].denominator != 1 or any(n > 132 for n in settings)
    name = "grblHAL" if hal else "grbl"
    us0, raw0, line0 = settings[0]
    at0 = where(path, line0)

    def mask(n: int) -> int:
        return int(settings[n][0]) if n in settings else 0

    step_mask, dir_mask = mask(2), mask(3)
    pulse = Guaranteed(
        us0 * 1000,
        "$0",
        at0,
        "us",
        "uncertain",
        "grbl: Timer0 at 0.5 us, loaded with $0 - 2 us for interrupt overhead (calibrated on a "
        "scope, not enforced)"
        if not hal
        else "grblHAL: rounding and latency allowance are driver-specific (STM32F4xx rounds up)",
    )
    if hal and settings.get(29, (Fraction(0),))[0] > 0:
        us29, _, line29 = settings[29]
        setup = Guaranteed(
            us29 * 1000,
            "$29",
            where(path, line29),
            "us",
            "uncertain",
            "grblHAL applies $29 only when DIR changes, less the driver's latency allowance",
        )
    else:
        setup = Guaranteed(
            Fraction(0),
            "$29" if hal else "STEP_PULSE_DELAY",
            "firmware default",
            "us",
            "default",
            "DIR is written a few CPU cycles before STEP in the same interrupt: no setup time is "
            "guaranteed" + ("" if hal else " (STEP_PULSE_DELAY is compile-time, not in $$)"),
        )
    axes = []
    for bit, axis in enumerate(_AXES):
        spm, rate = settings.get(100 + bit), settings.get(110 + bit)
        if spm is None:
            continue
        info = {"steps/mm": f"{spm[1]} (${100 + bit}, {where(path, spm[2])})"}
        if rate is not None:
            info["max rate"] = f"{rate[1]} mm/min (${110 + bit}, {where(path, rate[2])})"
            hz = spm[0] * rate[0] / 60
            max_rate = Guaranteed(
                hz,
                f"${100 + bit} x ${110 + bit} / 60",
                where(path, rate[2]),
                "mm/min",
                "derived",
                "grbl claims up to 30 kHz but does not enforce it",
            )
            idle_value = Fraction(10**9) / hz - pulse.value if hz > 0 and pulse.value else None
        else:
            max_rate = Guaranteed(None, f"${110 + bit}", "", "mm/min", "unknown", "not in the dump")
            idle_value = None
        idle = Guaranteed(
            idle_value if idle_value is None or idle_value > 0 else Fraction(0),
            f"${110 + bit}",
            max_rate.where,
            "mm/min",
            "uncertain" if idle_value else "unknown",
            "1 / (max step rate) - pulse: the step interrupt spaces steps (Bresenham, AMASS)",
        )
        axes.append(
            GeneratorGuarantee(
                axis=axis,
                pulse=pulse,
                idle=idle,
                dir_setup=setup,
                dir_hold=Guaranteed(
                    pulse.value,
                    "$0",
                    at0,
                    "us",
                    "uncertain",
                    "DIR changes at the next step tick, at least one pulse after the leading edge",
                ),
                max_rate=max_rate,
                pulse_level=0 if step_mask >> bit & 1 else 1,
                dir_hold_trailing=Guaranteed(
                    Fraction(0),
                    "$0",
                    at0,
                    "us",
                    "uncertain",
                    "the next tick may follow the end of the pulse at once",
                ),
                dir_inverted=bool(dir_mask >> bit & 1),
                info=info,
            )
        )
    if not axes:
        raise ConfigError(f"{path}: no $100.. (steps/mm) lines: no axis to check")
    known = {0, 2, 3, 29, *range(100, 106), *range(110, 116)}
    other = [f"${n}" for n in sorted(settings) if n not in known]
    return FirmwareConfig(
        firmware="grbl",
        path=str(path),
        axes=tuple(axes),
        files=(str(path),),
        unsupported=(f"not timing settings, not read: {' '.join(other)}",) if other else (),
        notes=(
            f"{name}: $0 and $29 apply to every axis; $2/$3 bit 0 = X, 1 = Y, 2 = Z",
            *notes,
        ),
        fixer=_fixer(hal),
    )


def _fixer(hal: bool):  # type: ignore[no-untyped-def]
    def us(ns: Fraction) -> str:
        v = ns / 1000
        if hal:
            return f"{float(-(-v * 10 // 1) / 10):g}"
        return str(-(-v // 1))

    def fix(axis: GeneratorGuarantee, role: Role, need: Fraction) -> str:
        bit = _AXES.index(axis.axis) if axis.axis in _AXES else 0
        if role in ("pulse", "dir_hold"):
            low = " (grbl refuses values below 3)" if not hal and need < 3000 else ""
            return f"set `$0` to at least {us(need)} us{low}"
        if role == "dir_setup":
            if hal:
                return f"set `$29` to at least {us(need)} us (drivers that support it)"
            return (
                f"grbl cannot delay DIR from $$: compile STEP_PULSE_DELAY {us(need)} (us) into "
                "config.h, or invert STEP with `$2` so the drive counts the trailing edge"
            )
        spm = axis.info.get("steps/mm", "").split(" ")[0]
        if role == "idle" and axis.pulse.value is not None:
            need = Fraction(10**9) / (axis.pulse.value + need)
        if spm:
            mm_min = need * 60 / Fraction(spm)
            return f"lower `${110 + bit}` to at most {float(mm_min):.6g} mm/min"
        return f"lower `${110 + bit}`"

    return fix
