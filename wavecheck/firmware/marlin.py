"""Marlin: ``Configuration.h`` + ``Configuration_adv.h`` (reference ``firmware-timing.md`` §4).

Both files are read through :mod:`.preprocessor` (``#if``/``#else`` branches evaluated, macros
that name macros expanded). Read: ``X_DRIVER_TYPE`` … ``E7_DRIVER_TYPE`` (and ``X2``/``Y2``/
``Z2``–``Z4``), ``MINIMUM_STEPPER_PULSE_NS`` (2.1.3 format) or ``MINIMUM_STEPPER_PULSE`` (µs,
older), ``MAXIMUM_STEPPER_RATE`` (Hz), ``MINIMUM_STEPPER_POST_DIR_DELAY`` (ns; DIR written →
next pulse: the **setup**) and ``MINIMUM_STEPPER_PRE_DIR_DELAY`` (ns; end of the last pulse → DIR
written: the **hold**, so hold from the leading edge = pulse + PRE; 1.1.x had one
``MINIMUM_STEPPER_DIR_DELAY``, the setup), ``EDGE_STEPPING``/``SQUARE_WAVE_STEPPING``,
``STEP_STATE_X LOW`` / ``INVERT_X_STEP_PIN true``, ``INVERT_X_DIR``, ``EXTRUDERS``,
``DISTINCT_E_FACTORS``, ``DEFAULT_AXIS_STEPS_PER_UNIT`` and ``DEFAULT_MAX_FEEDRATE`` (mm/s; C
expressions such as ``4000/3`` evaluated as C does, integer division included; a list that
cannot be evaluated only loses the per-axis rate).

The version comes from ``CONFIGURATION_H_VERSION`` (else from the names the file uses) and
decides Marlin's defaults when a figure is not set (:data:`ERAS`): one value for the whole
machine from the slowest driver type present on any axis. Until 2.1.2 a pulse of 0 µs (the TMC
and LV8729 default, or a user's 0) is "not set", so high = low = 5e8 / rate; from 2.1.3 a
defined ``MINIMUM_STEPPER_PULSE_NS 0`` is 0. Low time = max(1e9 / rate − pulse, pulse) when both
are set. Before 2.1, a driver whose ``X_DRIVER_TYPE`` is not defined is an A4988 (the files say
so), except in 2.0.0, whose ``drivers.h`` matches it to no type: the ``#else`` defaults. The
pulse is a busy-wait on the pulse timer, so it is ``uncertain``: it may be up to 1½ ticks short
(:data:`_PULSE_SHORT`), 1 tick before the 2020 rewrite; the DIR hold from the leading edge
(pulse + PRE) carries the pulse's band. ``EDGE_STEPPING`` on a TMC axis driven over UART/SPI (not
``_STANDALONE``) makes every STEP edge a step.

A figure that depends on a branch the files cannot decide is the smallest over the branches
(the largest for the max rate), and the note names the branch.

Spacing, the steps of one interrupt and each axis's rate: :mod:`.marlin_spacing`.
Hangprinter's fourth anchor D is a stepper on the first free E socket.
"""

from __future__ import annotations

import itertools
import os
import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from fractions import Fraction
from pathlib import Path

from wavecheck.errors import ConfigError
from wavecheck.firmware._text import read_text
from wavecheck.firmware.guarantee import (
    FirmwareConfig,
    FixRole,
    GeneratorGuarantee,
    Guaranteed,
    not_enforced,
    uncertain,
    unknown,
)
from wavecheck.firmware.marlin_spacing import (
    LINEAR,
    Figures,
    Sustained,
    axis_idle,
    coupled,
    driver_rate,
    multistepping,
    outrun,
    sustained_rate,
)
from wavecheck.firmware.preprocessor import Definition, Headers, Num, evaluate
from wavecheck.units import shown

__all__ = ["ERAS", "Era", "Table", "looks_like", "read"]

_Row = tuple[tuple[str, ...], int]


@dataclass(frozen=True)
class Table:
    """Marlin's per-driver defaults: ordered rows, the first whose driver type is present wins
    (``TMC`` stands for every Trinamic type), then the ``…_else`` value (None: not defined)."""

    pulse_ns: tuple[_Row, ...]
    pulse_else: int | None
    dir_ns: tuple[_Row, ...]
    dir_else: int
    rate_hz: tuple[_Row, ...]
    rate_else: int | None


@dataclass(frozen=True)
class Era:
    """The Marlin versions that share one way of reading the timing settings."""

    name: str
    first: tuple[int, ...]
    """The first version of the era (``(2, 1, 3)``)."""
    tables: tuple[Table, ...]
    """The default tables of the era's releases; a figure is the smallest over them (the rate
    the largest) when they differ."""
    zero_is_unset: bool
    """``#if MINIMUM_STEPPER_PULSE && …`` (≤ 2.1.2) rather than ``defined()`` (2.1.3)."""
    single_dir_delay: bool
    """1.1.x: one ``MINIMUM_STEPPER_DIR_DELAY`` (the setup), no PRE delay."""
    source: str
    old_pulse_code: bool = False
    """The pulse loop before the 2020 rewrite (``Stepper::stepper_pulse_phase_isr``): the high
    time is waited only ``#if MINIMUM_STEPPER_PULSE`` (see :data:`_OLD_PULSE`), so a 0 µs
    pulse is not enforced; the rate only spaces pulses of one interrupt."""
    untyped_is_none: bool = False
    """``drivers.h`` tests ``defined(A##_DRIVER_TYPE)`` and nothing defines a fallback type, so
    a stepper without ``…_DRIVER_TYPE`` matches no driver: the ``#else`` defaults apply."""


_T213 = Table(
    pulse_ns=((("TB6560",), 30000), (("TB6600",), 3000), (("DRV8825",), 2000),
              (("A4988", "A5984"), 1000), (("LV8729",), 500), (("TMC",), 100)),
    pulse_else=None,
    dir_ns=((("TB6560",), 15000), (("TB6600",), 1500), (("DRV8825",), 650), (("LV8729",), 500),
            (("A5984",), 400), (("A4988",), 200), (("TMC",), 100)),
    dir_else=0,
    rate_hz=((("TB6560",), 15000), (("TB6600",), 150000), (("DRV8825",), 250000),
             (("A4988", "A5984"), 500000), (("LV8729",), 1000000), (("TMC",), 5000000)),
    rate_else=None,
)  # fmt: skip
_T2022 = Table(
    pulse_ns=((("TB6560",), 30000), (("TB6600",), 3000), (("DRV8825",), 2000),
              (("A4988", "A5984"), 1000), (("TMC",), 0), (("LV8729",), 0)),
    pulse_else=2000,
    dir_ns=((("TB6560",), 15000), (("TB6600",), 1500), (("DRV8825",), 650), (("LV8729",), 500),
            (("A5984",), 400), (("A4988",), 200), (("TMC",), 70)),
    dir_else=0,
    rate_hz=((("TB6560",), 15000), (("TB6600",), 150000), (("DRV8825",), 250000),
             (("A4988",), 500000), (("LV8729",), 1000000), (("TMC",), 5000000)),
    rate_else=250000,
)  # fmt: skip
#: 2.0.9.x as its own Configuration_adv.h documents the defaults (e.g. 2097/Creality/Ender-3/
#: BigTreeTech_SKR_Mini_E3_1.2 adv lines 2210-2246: TMC DIR 20 ns, TMC rate 5 MHz): the 2022
#: table with the TMC DIR delay still 20 ns. The release's own Conditionals are not in the
#: searched corpus, so this combination is kept beside the two that are.
_T2021 = Table(
    pulse_ns=_T2022.pulse_ns, pulse_else=_T2022.pulse_else,
    dir_ns=(*_T2022.dir_ns[:-1], (("TMC",), 20)), dir_else=_T2022.dir_else,
    rate_hz=_T2022.rate_hz, rate_else=_T2022.rate_else,
)  # fmt: skip
_T2019 = Table(
    pulse_ns=((("TB6560",), 30000), (("TB6600",), 3000), (("DRV8825",), 2000),
              (("A4988", "A5984"), 1000), (("LV8729",), 0), (("TMC",), 0)),
    pulse_else=2000,
    dir_ns=((("TB6560",), 15000), (("TB6600",), 1500), (("DRV8825",), 650), (("LV8729",), 500),
            (("A5984",), 400), (("A4988",), 200), (("TMC",), 20)),
    dir_else=0,
    rate_hz=((("TB6560",), 15000), (("TB6600",), 150000), (("LV8729",), 200000),
             (("DRV8825",), 250000), (("TMC",), 400000), (("A4988",), 500000)),
    rate_else=250000,
)  # fmt: skip
#: The pulse loop of 1.1.9 and 2.0.0 (MarlinFirmware's ``stepper_pulse_phase_isr`` before the
#: 2020 rewrite, as indexed: ``#if MINIMUM_STEPPER_PULSE`` / ``while (HAL_timer_get_count(…) <
#: pulse_end)`` before ``PULSE_STOP``; ``pulse_end += added_step_ticks`` then the same wait
#: before the next pulse of the interrupt only, ``if (events_to_do)``).
_OLD_PULSE = ("stepper_pulse_phase_isr (1.1.9/2.0.0): the high time is waited only "
              "#if MINIMUM_STEPPER_PULSE; with 0 the pulse is as long as the code between "
              "PULSE_START and PULSE_STOP")  # fmt: skip
#: The 1.1.x driver test: MarlinFirmware/Marlin:Marlin/drivers.h:43 @ 268245c6 (1.1.x layout,
#: the driver list of 1.1.9's Configuration.h) ``_AXIS_DRIVER_TYPE(A,T) (
#: defined(A##_DRIVER_TYPE) && (A##_DRIVER_TYPE == T) )``; 2.0.0: Marlin/src/core/drivers.h:51
#: @ ae1cc796, the same test. The ``#ifndef X_DRIVER_TYPE / #define X_DRIVER_TYPE A4988``
#: fallback ("Fallback Stepper Driver types", Conditionals_LCD.h) came with later 2.0.x.
_UNTYPED_SOURCE = ("Marlin/drivers.h:43 @ 268245c6 (1.1.x) and Marlin/src/core/drivers.h:51 "
                   "@ ae1cc796 (2.0.0) test defined(A##_DRIVER_TYPE)")  # fmt: skip
#: The slowest pulse timer of Marlin's HALs: AVR's Timer1 at F_CPU / 8 = 2 MHz on a 16 MHz
#: board (Marlin/src/HAL/AVR/timers.h:35 HAL_TIMER_RATE ((F_CPU) / 8), :49 STEPPER_TIMER_RATE,
#: :53 PULSE_TIMER_RATE @ 3312295; 2.5 MHz at 20 MHz), the STM32 HALs' STEPPER_TIMER_RATE
#: 2000000. The file does not name the board's HAL, so one tick is taken as 500 ns.
_PULSE_TICK_NS = Fraction(500)
#: How far the pulse may fall short of the setting. 2020 rewrite (2.0.x after 2.0.5, 2.1.x,
#: Marlin/src/module/stepper.cpp): PULSE_HIGH_TICK_COUNT is NS_TO_PULSE_TIMER_TICKS(pulse −
#: TIMER_SETUP_NS), rounded to the *nearest* tick ((NS + NS_PER_PULSE_TIMER_TICK / 2) /
#: NS_PER_PULSE_TIMER_TICK: ½ tick), and AWAIT_TIMED_PULSE waits until the free-running counter
#: has advanced that many ticks since START_TIMED_PULSE read it, at any phase of a tick (one tick
#: more); the TIMER_SETUP_NS taken off is spent between the STEP write and the counter read.
#: Before (1.1.9, 2.0.0: stepper_pulse_phase_isr): MIN_PULSE_TICKS = whole µs ×
#: PULSE_TIMER_TICKS_PER_US, no rounding, the same counter phase: one tick.
_PULSE_SHORT = {
    False: (
        Fraction(3, 2) * _PULSE_TICK_NS,
        "1.5 ticks of a 2 MHz pulse timer: NS_TO_PULSE_TIMER_TICKS rounds to the nearest tick "
        "and AWAIT_TIMED_PULSE counts whole ticks from any phase (Marlin/src/module/stepper.cpp; "
        "HAL/AVR/timers.h:35 F_CPU / 8)",
    ),
    True: (
        _PULSE_TICK_NS,
        "1 tick of a 2 MHz pulse timer: the wait counts whole ticks of the pulse timer from any "
        "phase (stepper_pulse_phase_isr, MIN_PULSE_TICKS; HAL/AVR/timers.h:35 F_CPU / 8)",
    ),
}
#: How far the low time may fall short, waited by the same timer. 2020 rewrite: START_LOW_PULSE
#: after PULSE_STOP, AWAIT_LOW_PULSE until PULSE_LOW_TICK_COUNT = NS_TO_PULSE_TIMER_TICKS(
#: _MIN_PULSE_LOW_NS - TIMER_SETUP_NS) ticks have passed: the pulse's rounding and phase, 1.5
#: ticks. Before (1.1.9/2.0.0): ``pulse_end += ADDED_STEP_TICKS`` with ADDED_STEP_TICKS =
#: MIN_STEPPER_PULSE_CYCLES / PULSE_TIMER_PRESCALE - MIN_PULSE_TICKS (stepper.h, integer
#: division: up to 1 tick lost) counted from the previous target, not from the falling edge,
#: at any phase (1 tick): 2 ticks, and a high wait that overruns its target takes from it.
_LOW_SHORT = {
    False: (
        _PULSE_SHORT[False][0],
        "1.5 ticks of a 2 MHz pulse timer: PULSE_LOW_TICK_COUNT is NS_TO_PULSE_TIMER_TICKS "
        "(nearest tick) and AWAIT_LOW_PULSE counts whole ticks from any phase "
        "(Marlin/src/module/stepper.cpp; HAL/AVR/timers.h:35 F_CPU / 8)",
    ),
    True: (
        2 * _PULSE_TICK_NS,
        "2 ticks of a 2 MHz pulse timer: ADDED_STEP_TICKS truncates cycles to ticks and the "
        "wait counts from the high wait's target at any phase (stepper_pulse_phase_isr, "
        "stepper.h ADDED_STEP_TICKS; HAL/AVR/timers.h:35 F_CPU / 8)",
    ),
}
#: Marlin's eras, newest first.
ERAS: tuple[Era, ...] = (
    Era("2.1.3 and later", (2, 1, 3), (_T213,), False, False,
        "Marlin/src/inc/Conditionals-4-adv.h @ 00354a11, 'Driver Timings (in nanoseconds)'"),
    Era("2.0.1 to 2.1.2", (2, 0, 1), (_T2019, _T2021, _T2022), True, False,
        "Conditionals_post.h (2019), 2.0.9.x's documented defaults and Conditionals_adv.h "
        "(2022): the tables of these releases; the smallest figure of them"),
    Era("2.0.0", (2, 0, 0), (_T2019,), True, False,
        "Conditionals_post.h of 2019 (TRINAMICS row: DIR 20 ns, pulse 0 us, 400 kHz; #else: "
        "0 ns, 2 us, 250 kHz), the table 2.0.0's Configuration_adv.h documents",
        old_pulse_code=True, untyped_is_none=True),
    Era("1.1.x", (1, 1, 0), (_T2019,), True, True,
        "Conditionals_post.h (2019) taken for 1.1.x (its #else row: 0 ns, 2 us, 250 kHz = 1 MHz "
        "/ (2 x 2 us) as 1.1.9's Configuration_adv.h says): one DIR delay, the setup",
        old_pulse_code=True, untyped_is_none=True),
)  # fmt: skip
_DRIVER_AXES = (*LINEAR, "X2", "Y2", "Z2", "Z3", "Z4", *(f"E{i}" for i in range(8)))
#: 1.1.9's HANGPRINTER drives four anchor motors A-D (enum.h: ``D_AXIS = 3, E_AXIS = 4``): A-C on
#: the X-Z sockets, D on the first E socket the extruders leave free (1.1.x ``Marlin/pins.h``,
#: HANGPRINTER block: ``D_STEP_PIN _EPIN(E_STEPPERS, STEP)``, as indexed in a 1.1.9-era copy;
#: 119/hangprinter/Configuration.h:988-989 ``#if EXTRUDERS == 1 / INVERT_E1_DIR INVERT_D_DIR``).
_HANGPRINTER_D = "D"
#: Trinamic types driven by STEP/DIR alone: Marlin/src/core/drivers.h @ 04e8baa9 lines 97-101
#: leave TMC2100 out of HAS_TRINAMIC_CONFIG (and AXIS_IS_TMC) and 106-111 put it in
#: HAS_TRINAMIC_STANDALONE, like the ``…_STANDALONE`` types.
_STANDALONE = ("TMC2100", "TMC26X_STANDALONE")
_MAX_COMBOS = 4096
_GIGA = Fraction(10**9)


def looks_like(text: str) -> bool:
    """A Marlin configuration header."""
    return bool(
        re.search(
            r"#define\s+(CONFIGURATION(_ADV)?_H_VERSION|X_DRIVER_TYPE|MINIMUM_STEPPER_PULSE)", text
        )
    )


def _pair(path: Path) -> list[Path]:
    folder = path if path.is_dir() else path.parent
    files = [folder / "Configuration.h", folder / "Configuration_adv.h"]
    found = [f for f in files if f.is_file()]
    if path.is_file() and path not in found:
        found.insert(0, path)
    if not found:
        raise ConfigError(f"{path}: no Configuration.h / Configuration_adv.h here")
    return found


@dataclass(frozen=True)
class _Opt:
    """One possible value of a setting: the number (None: not defined), where, and the
    undecidable branch it depends on."""

    value: Fraction | None
    where: str
    depends: tuple[str, ...]


def _options(h: Headers, name: str, unit: str, scale: int = 1) -> list[_Opt]:
    """Every value ``name`` may end with (a setting not mentioned: one ``None`` option)."""
    out: list[_Opt] = []
    for d in h.candidates(name) or [Definition(name, None, None, "", ())]:
        if d.value is None:
            out.append(_Opt(None, d.where, d.depends))
            continue
        v = evaluate(h, d.value)
        if not isinstance(v, Num):
            raise ConfigError(f"{d.where}: {name} {shown(d.value)} is not a number ({unit})")
        if not 0 <= v.value <= 10**12:
            raise ConfigError(
                f"{d.where}: {name} {shown(d.value)} is out of range (0 .. 1e12 {unit})"
            )
        out.append(_Opt(v.value * scale, d.where, d.depends))
    return out


def _version(h: Headers, texts: str) -> tuple[Era, str]:
    for key in ("CONFIGURATION_H_VERSION", "CONFIGURATION_ADV_H_VERSION"):
        d = h.definition(key)
        if d is not None and re.fullmatch(r"0?\d{5,7}", d.value or ""):
            digits = (d.value or "").lstrip("0")
            digits = digits.zfill(len(digits) + len(digits) % 2)
            parts = tuple(int(digits[i : i + 2]) for i in range(0, len(digits), 2))
            era = next((e for e in ERAS if parts[:3] >= e.first), ERAS[-1])
            version = ".".join(map(str, parts[:2] + tuple(p for p in parts[2:] if p)))
            return era, f"Marlin {version} ({key} {d.value} at {d.where}): {era.name} defaults"
    if "MINIMUM_STEPPER_PULSE_NS" in texts:
        return ERAS[0], "version not given; MINIMUM_STEPPER_PULSE_NS: 2.1.3 and later"
    if "MINIMUM_STEPPER_POST_DIR_DELAY" in texts:
        return ERAS[1], "version not given; POST/PRE DIR delays: 2.0.x to 2.1.2"
    if "MINIMUM_STEPPER_DIR_DELAY" in texts:
        return ERAS[-1], "version not given; one MINIMUM_STEPPER_DIR_DELAY: 1.1.x"
    return ERAS[0], "version not given and no timing names: 2.1.3 defaults assumed"


@dataclass(frozen=True)
class _Driver:
    axis: str
    options: tuple[tuple[str, str, tuple[str, ...]], ...]
    """(driver type, where, depends) for each possible type."""


#: The kind of a stepper whose ``…_DRIVER_TYPE`` is not defined where Marlin matches it to no
#: driver type: every ``HAS_DRIVER(T)`` is false, so the ``#else`` defaults apply.
_UNTYPED = "no driver type"


def _drivers(h: Headers, era: Era, texts: str) -> list[_Driver]:
    assumed = era.name != ERAS[0].name or "A4988 is assumed for unspecified drivers" in texts
    fallback, why = ("A4988", "Marlin's default: A4988 is assumed for unspecified drivers")
    if era.untyped_is_none:
        fallback, why = (_UNTYPED, f"not defined: Marlin {era.name}'s drivers.h tests "
                         f"defined(A##_DRIVER_TYPE), so the #else defaults apply "
                         f"({_UNTYPED_SOURCE})")  # fmt: skip
    extruders = 1
    e = h.definition("EXTRUDERS")
    if e is not None:
        v = evaluate(h, e.value or "")
        if isinstance(v, Num) and 0 <= v.value <= 8:
            extruders = int(v.value)
    # Hangprinter: the D anchor motor takes the socket (and driver type) of E<EXTRUDERS>
    d_socket = f"E{extruders}" if h.enabled("HANGPRINTER") else None
    out = []
    for axis in (*_DRIVER_AXES[:9], *((_HANGPRINTER_D,) if d_socket else ()), *_DRIVER_AXES[9:]):
        if axis == d_socket:
            continue
        socket = d_socket if axis == _HANGPRINTER_D and d_socket else axis
        options = []
        for d in h.candidates(f"{socket}_DRIVER_TYPE"):
            if d.value is None:
                continue
            v = evaluate(h, d.value)
            kind = v if isinstance(v, str) else (d.value.split() or ["?"])[0]
            options.append((kind, d.where, d.depends))
        implied = assumed and (axis in ("X", "Y", "Z", _HANGPRINTER_D, *_extra_steppers(h)) or (
            axis.startswith("E") and int(axis[1:]) < extruders))  # fmt: skip
        if options and any(d.value is None for d in h.candidates(f"{socket}_DRIVER_TYPE")):
            if implied:
                options.append((fallback, f"not defined: {why}", options[0][2]))
        if not options and implied:
            options.append((fallback, why, ()))
        if options:
            out.append(_Driver(axis, tuple(options)))
    return out


def _extra_steppers(h: Headers) -> tuple[str, ...]:
    """The second X/Y and extra Z steppers the options make (DUAL_X_CARRIAGE and
    X_DUAL_STEPPER_DRIVERS: X2; Y_DUAL_STEPPER_DRIVERS: Y2; Z_DUAL_STEPPER_DRIVERS,
    Z_TRIPLE_STEPPER_DRIVERS or NUM_Z_STEPPER_DRIVERS: Z2-Z4), which need a driver type too."""
    out = []
    if h.enabled("DUAL_X_CARRIAGE") or h.enabled("X_DUAL_STEPPER_DRIVERS"):
        out.append("X2")
    if h.enabled("Y_DUAL_STEPPER_DRIVERS"):
        out.append("Y2")
    n = evaluate(h, "NUM_Z_STEPPER_DRIVERS") if h.definition("NUM_Z_STEPPER_DRIVERS") else None
    zs = int(n.value) if isinstance(n, Num) and 1 <= n.value <= 4 else 1
    if h.enabled("Z_TRIPLE_STEPPER_DRIVERS"):
        zs = max(zs, 3)
    elif h.enabled("Z_DUAL_STEPPER_DRIVERS"):
        zs = max(zs, 2)
    out += [f"Z{i}" for i in range(2, zs + 1)]
    return tuple(out)


#: The drivers Marlin 2.0.0's HAS_TRINAMIC counts (HAS_DRIVER of each; not the standalone ones).
_TRINAMIC_200 = {"TMC2130", "TMC2160", "TMC2208", "TMC2209", "TMC2660", "TMC5130", "TMC5160"}


def _derive(h: Headers, drivers: list[_Driver], where: str) -> None:
    """What Marlin's own headers derive from ``Configuration.h`` before ``Configuration_adv.h``
    (``drivers.h``, ``Conditionals``): ``HAS_DRIVER(T)``, ``AXIS_IS_TMC(A)``,
    ``HAS_TRINAMIC_CONFIG``, ``HAS_TRINAMIC_STANDALONE``, ``HAS_MULTI_EXTRUDER``."""
    types = {d.axis: {k for k, _, _ in d.options} for d in drivers}

    def tri(results: list[bool]) -> bool | None:
        return True if all(results) else False if not any(results) else None

    def any_axis(test: Callable[[str], bool]) -> bool | None:
        per_axis = [tri([test(t) for t in ts]) for ts in types.values()]
        if any(p is True for p in per_axis):
            return True
        return False if all(p is False for p in per_axis) else None

    def config(t: str) -> bool:
        return _tmc_config(t)

    h.functions["HAS_DRIVER"] = lambda a: any_axis(lambda t: t == a[0].strip()) if a else None
    h.functions["AXIS_IS_TMC"] = lambda a: (
        tri([config(t) for t in types.get(a[0].strip(), {""})]) if a else None
    )
    derived = {
        "HAS_TRINAMIC_CONFIG": any_axis(config),
        "HAS_TRINAMIC_STANDALONE": any_axis(lambda t: t.startswith("TMC") and not config(t)),
    }
    version = h.definition("CONFIGURATION_H_VERSION")
    if version is not None and (version.value or "").strip() == "020000":
        # Marlin 2.0.0's name for it (src/inc/Conditionals_post.h): HAS_TRINAMIC, the drivers
        # configured over UART/SPI
        derived["HAS_TRINAMIC"] = any_axis(lambda t: t in _TRINAMIC_200)
    ext = h.definition("EXTRUDERS")
    if ext is not None:
        n = evaluate(h, ext.value or "")
        derived["HAS_MULTI_EXTRUDER"] = n.value > 1 if isinstance(n, Num) else None
    for name, value in derived.items():
        if value is not None:
            h.predefine(name, "1" if value else "0", f"derived from the driver types ({where})")


def _tmc_config(kind: str) -> bool:
    """A Trinamic driver Marlin configures over UART/SPI (not a standalone one)."""
    return kind.startswith("TMC") and not kind.endswith("STANDALONE") and kind not in _STANDALONE


def _present(row: tuple[str, ...], types: set[str]) -> bool:
    return any(t.startswith("TMC") if r == "TMC" else t == r for r in row for t in types)


def _first(rows: Sequence[_Row], other: int | None, types: set[str]) -> tuple[int | None, str]:
    for row, value in rows:
        if _present(row, types):
            return value, "/".join(row)
    return other, "none of the listed drivers"


@dataclass(frozen=True)
class _Timing:
    pulse: Fraction | None
    """None: not enforced (or the build fails, when the rate is None too)."""
    low: Fraction | None
    post: Fraction
    pre: Fraction
    rate: Fraction | None
    why: str
    """How the pulse and rate were found (defaults, 0 = unset)."""
    dir_why: str = ""
    """How the DIR delay was found."""


def _timing(era: Era, table: Table, types: set[str], settings: dict[str, _Opt]) -> _Timing | None:
    """One combination of driver types and settings under one table (None: the build fails)."""
    pulse_set = settings["pulse"].value
    rate_set = settings["rate"].value
    why = []
    if pulse_set is None:
        dv, row = _first(table.pulse_ns, table.pulse_else, types)
        pulse = None if dv is None else Fraction(dv)
        why.append(f"pulse: Marlin's default for {row}")
    else:
        pulse = pulse_set
    if rate_set is None:
        rv, row = _first(table.rate_hz, table.rate_else, types)
        rate = None if rv is None else Fraction(rv)
        why.append(f"rate: Marlin's default for {row}")
    else:
        rate = rate_set
    high: Fraction | None
    low: Fraction | None
    have_pulse = pulse is not None and (pulse != 0 or not era.zero_is_unset)
    have_rate = rate is not None and rate > 0
    if have_pulse and have_rate:
        assert pulse is not None and rate is not None
        period = _GIGA / rate
        high, low = pulse, max(period - min(period, pulse), pulse)
    elif have_pulse:
        assert pulse is not None
        high = low = pulse
    elif have_rate and era.old_pulse_code:
        high = low = None  # no wait for the high time; the rate spaces pulse starts only
        why.append(f"pulse 0: not enforced ({_OLD_PULSE})")
    elif have_rate:
        assert rate is not None
        high = low = Fraction(5 * 10**8) / rate
        why.append("pulse 0 or unset: high = low = 5e8 / rate")
    else:
        return None
    post = settings["post"].value
    dir_why = ""
    if post is None:
        dv, row = _first(table.dir_ns, table.dir_else, types)
        post, dir_why = Fraction(dv or 0), f"Marlin's default for {row}"
    pre = settings["pre"].value
    if era.single_dir_delay:
        pre = Fraction(0)
    elif pre is None:
        pre = post
    return _Timing(high, low, post, pre, rate, "; ".join(why), dir_why)


def read(path: str | os.PathLike[str]) -> FirmwareConfig:
    """Read a Marlin configuration (a ``Configuration.h``, its ``_adv`` sibling, or their folder)."""
    files = _pair(Path(path))
    h = Headers()
    texts = [read_text(f) for f in files]
    joined = "\n".join(texts)
    h.feed(str(files[0]), texts[0])
    era, version_note = _version(h, joined)
    drivers = _drivers(h, era, joined)
    _derive(h, drivers, str(files[0]))
    for file, text in zip(files[1:], texts[1:], strict=True):
        h.feed(str(file), text)
    era, version_note = _version(h, joined)
    drivers = _drivers(h, era, joined)
    if not drivers:
        raise ConfigError(
            f"{files[0]}: no X_DRIVER_TYPE … defined (Marlin 2.1 names every stepper's driver): "
            "no stepper to check"
        )
    pulse_name = "MINIMUM_STEPPER_PULSE_NS" if era is ERAS[0] else "MINIMUM_STEPPER_PULSE"
    post_name = (
        "MINIMUM_STEPPER_DIR_DELAY" if era.single_dir_delay else "MINIMUM_STEPPER_POST_DIR_DELAY"
    )
    dims: dict[str, list[_Opt]] = {
        "pulse": _options(h, pulse_name, "ns" if era is ERAS[0] else "us", 1 if era is ERAS[0] else 1000),
        "rate": _options(h, "MAXIMUM_STEPPER_RATE", "Hz"),
        "post": _options(h, post_name, "ns"),
        "pre": _options(h, "MINIMUM_STEPPER_PRE_DIR_DELAY", "ns"),
    }  # fmt: skip
    combos = 1
    for d in drivers:
        combos *= len(d.options)
    for opts in dims.values():
        combos *= len(opts)
    if combos > _MAX_COMBOS:
        raise ConfigError(
            f"{files[0]}: {combos} combinations of undecidable #if branches decide the timing "
            f"(at most {_MAX_COMBOS} are evaluated)"
        )
    results: list[tuple[_Timing, dict[str, _Opt], tuple[str, ...]]] = []
    for types in itertools.product(*(d.options for d in drivers)):
        for values in itertools.product(*dims.values()):
            settings = dict(zip(dims, values, strict=True))
            for table in era.tables:
                t = _timing(era, table, {k for k, _, _ in types}, settings)
                if t is not None:
                    deps = tuple(x for _, _, dep in types for x in dep) + tuple(
                        x for o in values for x in o.depends
                    )
                    results.append((t, settings, deps))
    notes = [
        version_note,
        f"defaults from {era.source}",
        "Marlin's timing is global: one pulse, DIR delay and rate for every axis",
        "EEPROM, M92 and M203 may override steps/unit and feed rates at run time",
        *(f"{e} (an active #error: this configuration would not build)" for e in h.errors),
    ]
    undecided = sorted({x for _, _, deps in results for x in deps})
    if undecided:
        notes.append(
            "figures depend on branches the files cannot decide (the smallest is used): "
            + "; ".join(undecided)
        )
    unknown_types = sorted(
        {k for d in drivers for k, _, _ in d.options
         if k != _UNTYPED and not any(_present(row, {k}) for row, _ in era.tables[0].rate_hz)}
    )  # fmt: skip
    unsupported = [f"driver type {t}: no Marlin default timing is modelled" for t in unknown_types]
    figs = _figures(results, dims, era, pulse_name, post_name)
    infos = {d.axis: {"driver type": " or ".join(f"{k} ({w})" for k, w, _ in d.options)}
             for d in drivers}  # fmt: skip
    asked = {d.axis: sustained_rate(h, d.axis, {x.axis for x in drivers}, infos[d.axis])
             for d in drivers}  # fmt: skip
    sustained = {a: r if r is None or figs.rate.value is None or r.hz < figs.rate.value else None
                 for a, r in asked.items()}  # fmt: skip
    figs = outrun(figs, asked)
    packing = multistepping(h)
    if packing[0] > 1:
        notes.append(f"multi-stepping ({packing[1]}): up to {packing[0]} steps per interrupt, "
                     "spaced by the driver timing, so every axis may step at the driver rate")  # fmt: skip
    known = [r.hz for r in sustained.values() if r is not None]
    fastest = max(known) if known and len(known) == len(sustained) else None
    axes = [_axis(h, d, figs, infos[d.axis], sustained[d.axis], fastest, packing) for d in drivers]
    return FirmwareConfig(
        firmware="marlin",
        path=str(path),
        axes=tuple(axes),
        files=tuple(str(f) for f in files),
        unsupported=tuple(unsupported),
        notes=tuple(notes),
        fixer=_fixer(era is not ERAS[0]),
    )


def _figures(
    results: list[tuple[_Timing, dict[str, _Opt], tuple[str, ...]]],
    dims: dict[str, list[_Opt]],
    era: Era,
    pulse_name: str,
    post_name: str,
) -> Figures:
    if not results:
        none = unknown(pulse_name, "neither a pulse nor a rate is known (Marlin would not build)")
        return Figures(none, none, none, none, none, none)

    def pick(key: Callable[[_Timing], Fraction | None]) -> tuple[_Timing, dict[str, _Opt]]:
        """The combination that gives the smallest figure (the lower bound over branches); a
        combination where the firmware enforces none (None) is the smallest of all."""
        unbounded = [(t, s) for t, s, _ in results if key(t) is None]
        if unbounded:
            return unbounded[0]
        return min(((t, s) for t, s, _ in results), key=lambda ts: key(ts[0]) or Fraction(0))

    def source(name: str, opt: _Opt, why: str) -> tuple[str, str, str]:
        if opt.value is not None:
            return name, opt.where, "set"
        return name, why or "Marlin's default", "default"

    t, s = pick(lambda x: x.pulse)
    name, at, st = source(pulse_name, s["pulse"], t.why)
    if s["pulse"].value is not None and t.pulse != s["pulse"].value:
        at = f"{at}; {t.why}"
    unit = "ns" if era is ERAS[0] else "us"
    if t.pulse:
        short, why = _PULSE_SHORT[era.old_pulse_code]
        pulse = uncertain(t.pulse, name, at, unit, short, why,
                          "a busy-wait on the pulse timer" + (" (Marlin's default)" if st == "default" else ""))  # fmt: skip
    else:
        pulse = not_enforced(name, f"a 0 pulse is no wait ({t.why or at})", at, unit=unit)
    t, s = pick(lambda x: x.low)
    if t.low:
        short, why = _LOW_SHORT[era.old_pulse_code]
        idle = uncertain(t.low, "MAXIMUM_STEPPER_RATE", s["rate"].where or "Marlin default",
                         "Hz", short, why, "max(1e9 / MAXIMUM_STEPPER_RATE - pulse, "
                         "pulse), waited between the steps of one interrupt")  # fmt: skip
    else:
        idle = not_enforced("MAXIMUM_STEPPER_RATE", "the rate spaces pulse starts; the high "
                            f"time is not bounded, so neither is the low time ({_OLD_PULSE})")  # fmt: skip
    t, s = pick(lambda x: x.post)
    name, at, st = source(post_name, s["post"], t.dir_why)
    if t.post:
        setup = Guaranteed(t.post, name, at, "ns", st)  # type: ignore[arg-type]
    else:
        setup = not_enforced(name, f"{name} 0 is no DELAY_NS after the DIR write ({at}); the "
                             "next step waits for the next stepper interrupt, whose time the "
                             "configuration does not bound", at)  # fmt: skip
    t, s = pick(lambda x: x.pre)
    pre_set = s["pre"].value is not None
    pre_name = (
        "MINIMUM_STEPPER_PRE_DIR_DELAY" if not era.single_dir_delay else "(no PRE delay in 1.1.x)"
    )
    pre_at = s["pre"].where if pre_set else "Marlin default (PRE defaults to POST)"
    if t.pre:
        pre = Guaranteed(t.pre, pre_name, pre_at, "ns", "set" if pre_set else "default")
    else:
        pre = not_enforced(pre_name, "no wait between the end of the last pulse and the DIR "
                           "write", pre_at)  # fmt: skip
    t, s = pick(lambda x: (x.pulse or 0) + x.pre or None)
    held = (t.pulse or 0) + t.pre
    hold_note = ("PRE_DIR_DELAY runs after the last pulse has ended: hold from the leading edge "
                 "= pulse + PRE")  # fmt: skip
    if held and t.pulse:  # the pulse's wait is in it, and its band
        short, why = _PULSE_SHORT[era.old_pulse_code]
        hold = uncertain(held, f"{pulse_name} + PRE_DIR_DELAY", pre.where, "ns", min(short, t.pulse),
                         f"the pulse's {why}", hold_note)  # fmt: skip
    elif held:
        hold = Guaranteed(held, f"{pulse_name} + PRE_DIR_DELAY", pre.where, "ns", "derived",
                          hold_note)  # fmt: skip
    else:
        hold = not_enforced(f"{pulse_name} + PRE_DIR_DELAY", f"both are 0: {hold_note}",
                            pre.where)  # fmt: skip
    rated = [(t, s) for t, s, _ in results if t.rate is not None]
    if rated:
        t, s = max(rated, key=lambda ts: ts[0].rate or 0)
        st = "set" if s["rate"].value is not None else "default"
        rate = Guaranteed(t.rate, "MAXIMUM_STEPPER_RATE", s["rate"].where or "Marlin default",
                          "Hz", st)  # type: ignore[arg-type]  # fmt: skip
    else:
        rate = Guaranteed(None, "MAXIMUM_STEPPER_RATE", "", "Hz", "unknown")
    return Figures(pulse, idle, setup, pre, hold, rate)


def _axis(
    h: Headers,
    d: _Driver,
    figs: Figures,
    info: dict[str, str],
    sustained: Sustained | None,
    fastest: Fraction | None,
    packing: tuple[int, str],
) -> GeneratorGuarantee:
    axis = d.axis
    letter = "E" if axis.startswith("E") else axis[0]
    types = {k for k, _, _ in d.options}
    tmc_config = {_tmc_config(t) for t in types}
    edge = next(
        (k for k in ("EDGE_STEPPING", "SQUARE_WAVE_STEPPING") if h.enabled(k) is not False), None
    )
    edge_on = h.enabled(edge) if edge else False
    both = bool(edge_on) and tmc_config == {True}
    notes = []
    if edge and (edge_on is None or (edge_on and len(tmc_config) > 1)):
        notes.append(f"{edge} may make every STEP edge a step (undecidable branch): measure it")
    if both:
        notes.append(f"{edge} with a {'/'.join(sorted(types))} driver: every STEP edge is a step")
    level = 1
    for key in (f"STEP_STATE_{letter}", f"INVERT_{letter}_STEP_PIN"):
        dd = h.definition(key)
        if dd is not None:
            level = 0 if (dd.value or "").strip() in ("LOW", "true", "1") else 1
    inv_def = h.definition(f"INVERT_{axis}_DIR") or h.definition(f"INVERT_{letter}_DIR")
    inv_v = evaluate(h, inv_def.value or "") if inv_def is not None else None
    inv = isinstance(inv_v, Num) and inv_v.value != 0  # true, 1 or a macro naming one
    rate = driver_rate(figs.rate, axis in coupled(h))
    if sustained is not None and (packing[0] == 1 or figs.rate.value is None):
        rate = Guaranteed(sustained.hz, "DEFAULT_AXIS_STEPS_PER_UNIT x DEFAULT_MAX_FEEDRATE",
                          sustained.where, "mm/s", "derived", sustained.how + (
                              f"; one step per interrupt ({packing[1]})"
                              if packing[0] == 1 else ""))  # fmt: skip
    elif sustained is not None:
        # Whether the interrupt ever takes more than one step depends on the leading axis
        # passing the CPU's MAX_STEP_ISR_FREQUENCY_1X (stepper.h), which no configuration
        # states: one step per interrupt (the sustained rate) is the other reading, and a rule
        # whose verdict differs between the two is indeterminate (evaluate.evaluate_pair).
        rate = replace(rate, disputed=sustained.hz,
                       note=f"{rate.note}; {packing[1]}: the steps of one interrupt are "
                       f"spaced by the driver timing, so this axis's {float(sustained.hz):g} Hz "
                       f"({sustained.how}) is only its sustained rate; whether this axis's "
                       "moves reach multi-stepping depends on the CPU (MAX_STEP_ISR_FREQUENCY_1X, "
                       "not in the configuration)")  # fmt: skip
    return GeneratorGuarantee(
        axis=axis,
        pulse=figs.pulse,
        idle=axis_idle(figs, sustained.hz if sustained else None, fastest, packing),
        dir_setup=figs.setup,
        dir_hold=figs.hold,
        max_rate=rate,
        pulse_level=level,
        both_edges=both,
        dir_hold_trailing=figs.pre,
        dir_inverted=inv,
        info=info,
        notes=tuple(notes),
    )


def _fixer(old: bool) -> Callable[[GeneratorGuarantee, FixRole, Fraction], str]:
    def ns(v: Fraction) -> int:
        return int(-(-v // 1))

    def fix(axis: GeneratorGuarantee, role: FixRole, need: Fraction) -> str:
        if role == "pulse":
            if old:
                return f"Marlin: define MINIMUM_STEPPER_PULSE {int(-(-need // 1000))} (us)"
            return f"Marlin: define MINIMUM_STEPPER_PULSE_NS {ns(need)}"
        if role == "idle":
            p = axis.pulse.value or Fraction(0)
            if axis.idle.setting == "DEFAULT_MAX_FEEDRATE":  # the leading axis's schedule decides
                return (
                    f"Marlin: lower DEFAULT_MAX_FEEDRATE so that no axis steps faster than "
                    f"{float(_GIGA / (p + need)):.6g} steps/s ({axis.axis} steps on the leading "
                    "axis's events, one step per interrupt)"
                )
            if need > p:
                # low = 1e9 / rate - pulse, or 5e8 / rate with the pulse 0 or unset: both hold
                rate = min(_GIGA / (p + need), _GIGA / 2 / need)
                return f"Marlin: define MAXIMUM_STEPPER_RATE {int(rate)} (or lower)"
            if old:
                return f"Marlin: define MINIMUM_STEPPER_PULSE {int(-(-need // 1000))} (us)"
            return f"Marlin: define MINIMUM_STEPPER_PULSE_NS {ns(need)}"
        if role == "setup":
            name = "MINIMUM_STEPPER_POST_DIR_DELAY"
            if axis.dir_hold_trailing is not None and "1.1.x" in axis.dir_hold_trailing.setting:
                name = "MINIMUM_STEPPER_DIR_DELAY"
            return f"Marlin: define {name} {ns(need)}"
        no_pre = axis.dir_hold_trailing is not None and "1.1.x" in axis.dir_hold_trailing.setting
        if role == "hold":
            p = axis.pulse.value or Fraction(0)
            if no_pre:  # 1.1.x writes DIR right after the pulse: only the pulse holds it
                return f"Marlin: define MINIMUM_STEPPER_PULSE {int(-(-need // 1000))} (us)"
            return f"Marlin: define MINIMUM_STEPPER_PRE_DIR_DELAY {ns(max(need - p, Fraction(0)))}"
        if role == "trailing_hold":
            if no_pre:
                pin = f"INVERT_{axis.axis[0]}_STEP_PIN"
                return (
                    f"Marlin: define {pin} {'false' if axis.pulse_level == 0 else 'true'} and "
                    f"define MINIMUM_STEPPER_PULSE {int(-(-need // 1000))} (us): 1.1.x has no "
                    "DIR hold after the pulse, so the drive's edge must start a pulse that long"
                )
            return f"Marlin: define MINIMUM_STEPPER_PRE_DIR_DELAY {ns(need)}"
        if axis.max_rate.setting == "MAXIMUM_STEPPER_RATE":
            # multi-stepping spaces an interrupt's steps by the driver timing: a lower feed
            # rate lowers the sustained rate only (stepper.cpp pulse_phase_isr)
            return f"Marlin: define MAXIMUM_STEPPER_RATE {int(need)}"
        return (
            f"Marlin: define MAXIMUM_STEPPER_RATE {int(need)}, or lower DEFAULT_MAX_FEEDRATE for "
            f"{axis.axis} so that it steps at most {float(need):.6g} steps/s"
        )

    return fix
