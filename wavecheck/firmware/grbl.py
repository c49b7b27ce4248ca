"""grbl 1.1, grblHAL and Grbl_ESP32: a ``$$`` settings dump.

Read (reference ``firmware-timing.md`` §1–2): ``$0`` step pulse (µs; integer on grbl, float on
grblHAL), ``$2``/``$3`` step/dir invert masks (bit 0 = X), ``$29`` grblHAL's pulse delay (µs,
applied on a direction change), ``$100…`` steps/mm and ``$110…`` max rates (mm/min). Lines may
carry grbl 0.9's `` (description)`` and spaces around ``=``; a file holding several dumps (a
user's notes) is read up to the first repeated setting, the rest named in the notes.

The flavour decides the defaults and the advice: grblHAL when a grblHAL-only setting is present
(``$14``–``$19``, ``$28``, ``$29``, ``$33``+, a fractional ``$0``); Grbl_ESP32 when the file
names the ESP32 or has settings for more than three axes without them; grbl otherwise. A dump
without ``$0`` uses the flavour's default, marked as such (grbl 10 µs, grblHAL 5 µs; Grbl_ESP32's
default is machine-specific: unknown).

Guarantees: grbl 1.1's pulse is at least ``$0`` − 562.5 ns (Timer0 loaded with ``$0`` − 2 µs
for the interrupt overhead, 62.5–562.5 ns short of ``$0`` by the clk/8 prescaler's phase:
``stepper.c`` 241, 344-345, and cycle-true runs), so a low time computed from it may be 500 ns
shorter; grblHAL times it per driver and Grbl_ESP32 with the RMT, I2S or software engine built
in, which a dump does not name, so theirs is ≈ ``$0`` with no bound below (``uncertain``: never a
PASS). DIR is written a
few CPU cycles before STEP (setup ≈ 0) unless grblHAL's ``$29`` is set (Grbl_ESP32 keeps its DIR
delay outside the numbered settings: unknown). The max step rate of an axis is
``$10n × $11n / 60`` (the planner limits each axis to it); grbl does not enforce its 30 kHz.

Spacing (stepper.c 413-440, 1017-1027): every step lands on a tick of the interrupt, whose rate
is the move's dominant axis's step rate (at most the fastest axis's max rate), doubled up to 3
times by AMASS only below 8 kHz (ticks then ≥ 62.5 µs). An axis whose max rate is R, in a machine
whose fastest axis steps at up to F, steps at least 1 / min(2R, F) apart: Bresenham puts its steps
floor(dominant / its rate) ticks apart, which tends to one tick of a dominant just under twice its
rate (so its low time is that less the pulse, not 1/R − pulse). DIR changes at the tick after a
block's last step (the new block's DIR is written at the next interrupt, 323-324, 358-375): the
hold after the leading edge is one tick, min(1 / F, 62.5 µs), whatever ``$0`` is. Both are times
between interrupts, which other interrupts may delay (serial, pin change, the pulse reset): no
source bounds that, so the low time and the DIR hold are ``uncertain`` with no bound (never a
PASS).
"""

from __future__ import annotations

import os
import re
from collections.abc import Callable
from fractions import Fraction

from wavecheck.errors import ConfigError
from wavecheck.firmware._text import number, read_text, where
from wavecheck.firmware.guarantee import (
    FirmwareConfig,
    FixRole,
    GeneratorGuarantee,
    Guaranteed,
    at_most,
    not_enforced,
    uncertain,
    unknown,
)

__all__ = ["FLAVOURS", "bresenham_spacing", "looks_like", "read"]

_LINE = re.compile(r"^\s*\$(\d{1,4})\s*=\s*(\S+)\s*(?:\((.*)\))?\s*$")
_AXES = "XYZABC"
#: Settings only grblHAL has (grbl 1.1 and Grbl_ESP32 number none of them).
_HAL_ONLY = {14, 15, 16, 17, 18, 19, 28, 29, *range(33, 100)}
#: The default ``$0`` of each flavour when the dump has none (µs): grbl's defaults.h, grblHAL's
#: config.h since build 20250328 (earlier builds 10), Grbl_ESP32: per machine file (None).
FLAVOURS: dict[str, Fraction | None] = {
    "grbl": Fraction(10),
    "grblHAL": Fraction(5),
    "Grbl_ESP32": None,
}
_US = 1000
#: grbl 1.1h's pulse is 62.5-562.5 ns (1-9 cycles at 16 MHz) shorter than $0: stepper.c:241
#: loads Timer0 with ($0 - 2) us of clk/8 counts for the interrupt overhead, 344-345 start it
#: after STEP is written, and the free-running clk/8 prescaler makes the first count come 1-8
#: cycles later; measured on a cycle-true simulator: 151-159 cycles at $0=10, 39-46 at $0=3
#: (../shared/firmware-src/README.md). The bound is the shortest: $0 - 9 cycles.
_GRBL_SHORT_NS = Fraction(1125, 2)
_GRBL_PULSE = (
    "grbl 1.1h: $0 - 2 us of Timer0 counts plus the interrupt overhead, 62.5-562.5 ns short of "
    "$0 by the clk/8 prescaler's phase (stepper.c:241, 344-345): at least $0 - 562.5 ns"
)
#: The shortest interrupt tick under AMASS (stepper.c:50, 1021-1026): it doubles the interrupt rate
#: only when the step takes AMASS_LEVEL1 = F_CPU / 8000 cycles (125 us) or more, so a tick is
#: then at least 62.5 us.
_AMASS_TICK_NS = Fraction(62500)


def bresenham_spacing(rate: Fraction, fastest: Fraction) -> Fraction:
    """The shortest time (ns) between two steps of an axis whose max rate is ``rate`` (Hz) when
    the dominant axis of a move steps at up to ``fastest`` Hz (grbl's Bresenham, and FluidNC's,
    its heir): floor(dominant / rate) ticks, which tends to one tick of a dominant just under
    twice the rate: 1 / min(2 x rate, fastest)."""
    return Fraction(10**9) / min(2 * rate, max(fastest, rate))


_PULSE_NOTES = {
    "grbl": "grbl: Timer0 at 0.5 us, loaded with $0 - 2 us for interrupt overhead (calibrated on "
    "a scope, not enforced)",
    "grblHAL": "grblHAL: rounding and latency allowance are driver-specific (STM32F4xx rounds up)",
    "Grbl_ESP32": "Grbl_ESP32: made by the RMT, I2S or software engine, chosen at build time",
}
#: Why the pulse of a grblHAL or Grbl_ESP32 dump has no bound below ``$0`` (the dump does not
#: say which driver or engine made it). grblHAL: each driver times it its own way (the ESP32
#: driver truncates 4 × $0 to whole 0.25 us RMT ticks, ``rmtItem[0].duration1 =
#: (uint32_t)(4.0f * pulse_microseconds)``; the STM32 drivers subtract a latency allowance).
#: Grbl_ESP32: RMT is exact (Grbl_Esp32/src/Motors/StandardStepper.cpp:54 clk_div 20, :69
#: duration1 = 4 × $0 @ 0004468a), but the I2S stream engine pushes $0 / I2S_OUT_USEC_PER_PULSE
#: samples (integer division) and the software one waits whole us of esp_timer from a read at any
#: phase (Grbl_Esp32/stepper.cpp, ``#ifndef USE_RMT_STEPS``).
_NO_BOUND = {
    "grblHAL": "grblHAL times the pulse per driver (truncated to RMT ticks on ESP32, less a "
    "latency allowance on STM32): the dump does not name the driver",
    "Grbl_ESP32": "Grbl_ESP32's I2S stream engine truncates $0 to whole samples and its software "
    "engine counts whole us of esp_timer (Grbl_Esp32/stepper.cpp, #ifndef USE_RMT_STEPS); only "
    "RMT is exact (Motors/StandardStepper.cpp:69): the dump does not say which was built",
}
#: Why the times between interrupts are no bound: STEP and DIR are written at the start of the
#: stepper interrupt (grbl 1.1h stepper.c:319-336), which the serial interrupts (serial.c:107,
#: 143), the limit and control pin-change interrupts (limits.c:110, system.c:64) and the pulse
#: reset (stepper.c:489) may each delay, by their run time, which no source bounds: two steps, or
#: a step and the next DIR write, may come closer than one tick.
_TICK_JITTER = (
    "STEP and DIR are written at the start of the stepper interrupt (stepper.c:319-336), which "
    "the serial, pin-change and pulse-reset interrupts (serial.c:107, 143; limits.c:110; "
    "system.c:64; stepper.c:489) may delay by their run time, which no source bounds"
)


def looks_like(text: str) -> bool:
    """A ``$$`` dump: at least three ``$n=value`` lines, one of them a pulse, steps/mm or max
    rate setting."""
    found = [m.group(1) for m in (_LINE.match(x) for x in text.splitlines()) if m]
    return len(found) >= 3 and any(n in ("0", *map(str, range(100, 116))) for n in found)


def _settings(path: str, text: str) -> tuple[dict[int, tuple[Fraction, str, int]], list[str]]:
    found: dict[int, tuple[Fraction, str, int]] = {}
    notes: list[str] = []
    for no, line in enumerate(text.splitlines(), 1):
        m = _LINE.match(line)
        if not m:
            continue
        n = int(m.group(1))
        if n in found:
            first = min(found.values(), key=lambda v: v[2])[2]
            notes.append(
                f"{path}: the dump that starts at line {first} is read; a second one starts near "
                f"line {no} and is ignored"
            )
            break
        found[n] = (Fraction(0), m.group(2), no)
    for n in (0, 2, 3, 29, *range(100, 106), *range(110, 116)):  # the settings read
        if n in found:
            raw, no = found[n][1:]
            found[n] = (number(raw, where(path, no), f"${n}"), raw, no)
    return found, notes


def _flavour(text: str, settings: dict[int, tuple[Fraction, str, int]]) -> str:
    if any(n in _HAL_ONLY for n in settings) or (0 in settings and settings[0][0].denominator != 1):
        return "grblHAL"
    if re.search(r"grbl.?esp32|\besp32\b", text, re.I) or any(
        n in settings for n in (103, 104, 105, 113, 114, 115)
    ):
        return "Grbl_ESP32"
    return "grbl"


def read(path: str | os.PathLike[str]) -> FirmwareConfig:
    """Read a ``$$`` dump (see the module doc)."""
    p = str(path)
    text = read_text(path)
    settings, notes = _settings(p, text)
    if not settings:
        raise ConfigError(f"{p}: no $n=value line: not a grbl $$ dump")
    flavour = _flavour(text, settings)
    pulse = _pulse(p, flavour, settings)

    def mask(n: int) -> int:
        if n not in settings:
            return 0
        value, raw, line = settings[n]
        number(raw, where(p, line), f"${n}", low=0, high=255)
        return int(value)

    step_mask, dir_mask = mask(2), mask(3)
    setup = _setup(p, flavour, settings)
    rates = {
        bit: settings[100 + bit][0] * settings[110 + bit][0] / 60
        for bit in range(len(_AXES))
        if 100 + bit in settings and 110 + bit in settings
    }
    with_steps = [bit for bit in range(len(_AXES)) if 100 + bit in settings]
    fastest = max(rates.values()) if rates and all(b in rates for b in with_steps) else None
    axes = []
    for bit, axis in enumerate(_AXES):
        spm = settings.get(100 + bit)
        if spm is None:
            continue
        axes.append(_axis(p, bit, axis, spm, settings.get(110 + bit), pulse, setup,
                          step_mask, dir_mask, fastest))  # fmt: skip
    if not axes:
        raise ConfigError(f"{p}: no $100.. (steps/mm) lines: no axis to check")
    known = {0, 2, 3, 29, *range(100, 106), *range(110, 116)}
    other = [f"${n}" for n in sorted(settings) if n not in known]
    return FirmwareConfig(
        firmware="grbl",
        path=p,
        axes=tuple(axes),
        files=(p,),
        unsupported=(f"not timing settings, not read: {' '.join(other)}",) if other else (),
        notes=(
            f"{flavour} (read from the settings present); "
            + ("$0 and $29 apply" if flavour == "grblHAL" else "$0 applies")
            + " to every axis; $2/$3 bit 0 = X, 1 = Y, 2 = Z",
            *notes,
        ),
        fixer=_fixer(flavour, {bit: (settings[100 + bit][0], hz) for bit, hz in rates.items()}),
    )


def _pulse(path: str, flavour: str, settings: dict[int, tuple[Fraction, str, int]]) -> Guaranteed:
    if 0 not in settings:
        default = FLAVOURS[flavour]
        if default is None:
            return unknown("$0", f"{flavour}: no $0 in the dump and the default is per machine")
        note = f"{flavour}'s default $0 (the dump has no $0 line): {default} us"
        if flavour == "grbl":
            return Guaranteed(default * _US - _GRBL_SHORT_NS, "$0", "firmware default", "us",
                              "default", f"{note}; {_GRBL_PULSE}")  # fmt: skip
        return Guaranteed(default * _US, "$0", "firmware default", "us", "default", note,
                          short_by=None, short_why=_NO_BOUND[flavour])  # fmt: skip
    us0, raw0, line0 = settings[0]
    at = where(path, line0)
    number(raw0, at, "$0 (step pulse)", low=0, high=255, unit="us")
    if flavour == "grbl":
        return Guaranteed(us0 * _US - _GRBL_SHORT_NS, "$0", at, "us", "derived", _GRBL_PULSE)
    return uncertain(us0 * _US, "$0", at, "us", None, _NO_BOUND[flavour], _PULSE_NOTES[flavour])


def _setup(path: str, flavour: str, settings: dict[int, tuple[Fraction, str, int]]) -> Guaranteed:
    if flavour == "grblHAL" and settings.get(29, (Fraction(0),))[0] > 0:
        us29, raw29, line29 = settings[29]
        at = where(path, line29)
        number(raw29, at, "$29 (pulse delay)", low=0, high=255, unit="us")
        return uncertain(us29 * _US, "$29", at, "us", None,
                         "grblHAL's drivers time $29 each their own way, less a latency "
                         "allowance: the dump does not name the driver",
                         "grblHAL applies $29 only when DIR changes")  # fmt: skip
    if flavour == "Grbl_ESP32":
        return unknown(
            "direction delay",
            "Grbl_ESP32 keeps its DIR delay outside the numbered $ settings (compile-time or a "
            "named setting): not in this dump",
        )
    # grbl 1.1h stepper.c:323-333: DIR is written, then STEP, in the same interrupt, with no
    # delay unless STEP_PULSE_DELAY is compiled in: the setup is the instructions between the two
    # port writes (6 cycles, 375 ns at 16 MHz, in the disassembly and under `wavecheck simulate
    # grbl`), which no setting keeps: neither 0 s nor a guarantee.
    return not_enforced(
        "$29" if flavour == "grblHAL" else "STEP_PULSE_DELAY",
        "DIR is written a few CPU cycles before STEP in the same interrupt (grbl 1.1h "
        "stepper.c:323-333; 6 cycles, 375 ns at 16 MHz, under `wavecheck simulate grbl`)"
        + ("" if flavour == "grblHAL" else "; STEP_PULSE_DELAY (compile-time, not in $$) "
           "would enforce a delay"),
        "firmware default",
    )  # fmt: skip


def _axis(
    path: str,
    bit: int,
    axis: str,
    spm: tuple[Fraction, str, int],
    rate: tuple[Fraction, str, int] | None,
    pulse: Guaranteed,
    setup: Guaranteed,
    step_mask: int,
    dir_mask: int,
    fastest: Fraction | None,
) -> GeneratorGuarantee:
    spm_at = where(path, spm[2])
    number(spm[1], spm_at, f"${100 + bit} (steps/mm)", low=0, high=10**7)
    info = {"steps/mm": f"{spm[1]} (${100 + bit}, {spm_at})", "$2": f"{step_mask} (step invert)"}
    if rate is not None:
        rate_at = where(path, rate[2])
        number(rate[1], rate_at, f"${110 + bit} (max rate)", low=0, high=10**9, unit="mm/min")
        info["max rate"] = f"{rate[1]} mm/min (${110 + bit}, {rate_at})"
        hz = spm[0] * rate[0] / 60
        max_rate = Guaranteed(hz, f"${100 + bit} x ${110 + bit} / 60", rate_at, "mm/min",
                              "derived", "grbl claims up to 30 kHz but does not enforce it")  # fmt: skip
        spacing = bresenham_spacing(hz, fastest) if hz > 0 and fastest else None
        gap = spacing - pulse.value if spacing is not None and pulse.value else None
    else:
        max_rate = Guaranteed(None, f"${110 + bit}", "", "mm/min", "unknown", "not in the dump")
        gap = None
    spacing_note = (
        "1 / min(2 x this axis's max rate, the fastest axis's) - pulse: Bresenham puts its steps "
        "on the dominant axis's ticks (stepper.c:413-440)"
    )
    if gap is None:
        idle = unknown(f"${110 + bit}", "an axis's max rate is not in the dump: the interrupt's "
                       "tick is not bounded", max_rate.where)  # fmt: skip
    else:  # the interrupts' jitter, and grblHAL's and Grbl_ESP32's pulse, have no bound
        idle = uncertain(max(gap, Fraction(0)), f"${110 + bit}", max_rate.where, "mm/min", None,
                         _TICK_JITTER, spacing_note)  # fmt: skip
    tick = min(Fraction(10**9) / fastest, _AMASS_TICK_NS) if fastest else None
    return GeneratorGuarantee(
        axis=axis,
        pulse=pulse,
        idle=idle,
        dir_setup=setup,
        # the step and the next block's DIR are written at the start of interrupts one tick
        # apart, each entered late by what other interrupts run first: no bound below the tick
        dir_hold=(
            uncertain(tick, "$11n", max_rate.where, "mm/min", None, _TICK_JITTER, _HOLD_NOTE)
            if tick is not None
            else unknown("$11n", _HOLD_NOTE, max_rate.where)
        ),
        max_rate=max_rate,
        pulse_level=0 if step_mask >> bit & 1 else 1,
        dir_hold_trailing=Guaranteed(  # 0: no figure can fall below it
            Fraction(0),
            "$0",
            pulse.where,
            "us",
            "derived",
            "the next tick may follow the end of the pulse at once",
        ),  # fmt: skip
        dir_inverted=bool(dir_mask >> bit & 1),
        info=info,
    )


_HOLD_NOTE = (
    "DIR changes one interrupt tick after a block's last step: min(1 / the fastest axis's max "
    "rate, 62.5 us of AMASS) (stepper.c:323-324, 358-375, 1017-1027)"
)


def _fixer(
    flavour: str, rates: dict[int, tuple[Fraction, Fraction]]
) -> Callable[[GeneratorGuarantee, FixRole, Fraction], str]:
    """The fixes; ``rates``: bit -> (steps/mm, max rate Hz) of each axis with both."""
    hal = flavour == "grblHAL"
    short = _GRBL_SHORT_NS if flavour == "grbl" else Fraction(0)

    def us(ns: Fraction) -> str:
        v = ns / _US
        if hal:
            return f"{float(-(-v * 10 // 1) / 10):g}"
        return str(-(-v // 1))

    def fix(axis: GeneratorGuarantee, role: FixRole, need: Fraction) -> str:
        bit = _AXES.index(axis.axis) if axis.axis in _AXES else 0
        if role == "pulse":
            value = max(need + short, Fraction(3000) if flavour == "grbl" else Fraction(0))
            return f"set `$0={us(value)}` (us)"
        if role == "hold":
            if need > _AMASS_TICK_NS:
                return (
                    "grbl tops out at one AMASS tick (62.5 us) of DIR hold after a step's "
                    f"leading edge: this drive needs {float(need) / _US:g} us"
                )
            top = Fraction(10**9) / need  # every axis at most this many steps/s
            edits = [
                f"`${110 + b}={at_most(top * 60 / spm)}`"
                for b, (spm, hz) in sorted(rates.items())
                if hz > top and spm > 0
            ]
            return f"set {' '.join(edits)} (mm/min): DIR changes one interrupt tick after a step"
        if role == "trailing_hold":
            mask = int(axis.info.get("$2", "0").split(" ")[0]) ^ (1 << bit)
            return (
                f"set `$2={mask}` and `$0={us(max(need + short, Fraction(3000)))}`: grbl may "
                f"change DIR right after a pulse, so invert {axis.axis}'s STEP to make the "
                "drive's active edge start the pulse, which grbl holds DIR through"
            )
        if role == "setup":
            if hal:
                return f"set `$29={us(need)}` (us; drivers that support it)"
            if flavour == "Grbl_ESP32":
                return (
                    f"set Grbl_ESP32's direction delay to at least {us(need)} us (a named or "
                    "compile-time setting, not a $ number)"
                )
            return (
                f"grbl cannot delay DIR from $$: compile STEP_PULSE_DELAY {us(need)} (us) into "
                "config.h, or invert STEP with `$2` so the drive counts the trailing edge"
            )
        spm = axis.info.get("steps/mm", "").split(" ")[0]
        if role == "idle" and axis.pulse.value is not None:
            # twice this axis's rate under 1 / (pulse + low): no dominant can crowd its steps
            need = Fraction(10**9) / (axis.pulse.value + need) / 2
        if spm and Fraction(spm) > 0:
            return f"set `${110 + bit}={at_most(need * 60 / Fraction(spm))}` (mm/min)"
        return f"lower `${110 + bit}`"

    return fix
