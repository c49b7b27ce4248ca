"""Smoothieware: ``config`` (reference ``firmware-timing.md`` §6).

Read: ``microseconds_per_step_pulse`` (default 1 µs), ``base_stepping_frequency`` (default
100 kHz) (Kernel.cpp), ``alpha/beta/gamma/delta/epsilon/zeta_steps_per_mm`` (default 2560 for
gamma, 80 for the others) and ``…_max_rate`` (mm/min, default 30000) (Robot::load_config),
``…_step_pin`` and ``…_dir_pin`` (a ``!`` after the pin inverts it; a pin no build reads,
``nc`` or ``xx``, is none: :data:`_PIN`), ``arm_solution``, and
each enabled ``extruder.NAME`` module (``step_pin``, ``dir_pin``, ``steps_per_mm`` default 1,
``max_speed`` mm/s default 1000: Extruder.cpp ``config_load`` makes a stepper motor of it) and the
old single-extruder syntax (``extruder_module_enable true`` with ``extruder_step_pin``,
``extruder_steps_per_mm``, ``extruder_max_speed``: ExtruderMaker makes one Extruder of them). A key
given twice keeps its last value (ConfigCache ``replace_or_push_back``).

StepTicker: the pulse is the setting plus interrupt time (≥ the setting); each motor steps at most
once per base tick, so the rate is ≤ the base frequency and the low time about one tick − the
pulse (not enforced: the real pulse is longer by ISR time). Robot.cpp ``append_milestone`` clamps
every actuator to its own ``max_rate`` (any arm solution, deltas included), so a motor's rate is
≤ min(base frequency, steps/mm × max_rate); where steps/mm × max_rate exceeds the base frequency,
Robot::check_max_actuator_speeds first lowers max_rate to floor(base / steps/mm) mm/s (extruders
excepted). The motors after gamma need their step and dir pins and are taken in order, the first
one missing ending them (Robot::load_config). DIR is written when a block starts, about one tick before the first pulse (not
enforced: there is no DIR delay); DIR hold after the leading edge is only code time (unknown).
"""

from __future__ import annotations

import math
import os
import re
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
    unknown,
)

__all__ = ["looks_like", "read"]

_MOTORS = ("alpha", "beta", "gamma", "delta", "epsilon", "zeta")
_CARTESIAN_AXIS = {"alpha": "x", "beta": "y", "gamma": "z"}
_LINE = re.compile(r"^\s*([A-Za-z0-9_.]+)\s+(\S+)")
_EXTRUDER = re.compile(r"extruder\.(\w+)\.step_pin")
#: A pin some Smoothieware build's ``Pin::from_string`` accepts: a port, ``.``, a pin index below
#: 32. The LPC1769 build (Smoothieware/Smoothieware src/libs/Pin.cpp @ 1fd8a13) reads port and
#: index with ``strtol`` (port ≤ 4, index < 32), the STM32 ports also a port letter ``a``-``i``;
#: any other text ("nc", "xx") ends in "from_string failed": ``valid = false``, which
#: ``Robot::load_config`` (``connected()``) reads as no pin. A pin only some builds accept
#: (``5.1``, ``B.3``) is kept: which build runs is not in the file.
_PIN = re.compile(r"\s*(?:[+-]?\d+|[A-Ia-i])\.\s*([+-]?\d+)")


def _connected(pin: str) -> bool:
    """Whether some Smoothieware build reads ``pin`` as a pin (:data:`_PIN`)."""
    m = _PIN.match(pin)
    return m is not None and int(m.group(1)) < 32


def looks_like(text: str) -> bool:
    """A Smoothieware config: a motor's ``…_steps_per_mm`` or ``…_step_pin`` line (``alpha``
    … ``zeta``, ``extruder.NAME.``), space-separated."""
    return bool(
        re.search(
            r"^[ \t]*((alpha|beta|gamma|delta|epsilon|zeta)_|extruder\.\w+\.)"
            r"(steps_per_mm|step_pin)[ \t]",
            text,
            re.M,
        )
    )


def read(path: str | os.PathLike[str]) -> FirmwareConfig:
    """Read a Smoothieware ``config`` (see the module doc)."""
    p = str(path)
    keys: dict[str, tuple[str, str]] = {}
    for no, line in enumerate(read_text(path).splitlines(), 1):
        m = _LINE.match(line.split("#")[0])
        if m:
            keys[m.group(1)] = (m.group(2), where(p, no))  # the last one wins

    def get(name: str, default: str, low: int, high: int, unit: str) -> tuple[Fraction, str, str]:
        if name in keys:
            v, at = keys[name]
            return number(v, at, name, low=low, high=high, unit=unit), at, "set"
        return Fraction(default), "firmware default", "default"

    us, us_at, us_st = get("microseconds_per_step_pulse", "1", 0, 10**4, "us")
    f, f_at, _ = get("base_stepping_frequency", "100000", 1, 10**7, "Hz")
    tick = Fraction(10**9) / f
    arm = keys.get("arm_solution", ("cartesian", "firmware default"))
    pulse = Guaranteed(us * 1000, "microseconds_per_step_pulse", us_at, "us", us_st,  # type: ignore[arg-type]
                       "the pulse is this plus interrupt time (about 3 us at 1 us set)")  # fmt: skip
    idle = not_enforced(
        "base_stepping_frequency",
        "StepTicker::step_tick steps a motor at most once per base tick and starts the unstep "
        "timer only after every motor's step, so the real pulse is the setting plus ISR time and "
        "the low time one tick minus that: at most one tick minus the set pulse",
        f_at, max(tick - us * 1000, Fraction(0)), "Hz",
    )  # fmt: skip
    setup = not_enforced(
        "base_stepping_frequency",
        "StepTicker::start_next_block writes DIR at the end of the tick that finished the last "
        "block (or just before the first tick's steps); the first step comes a tick or more "
        "later, less the ISR's own time: about one base tick, no DIR delay setting",
        f_at, tick, "Hz",
    )  # fmt: skip
    axes: list[GeneratorGuarantee] = []
    for motor in _MOTORS:
        pin = _connected(keys.get(f"{motor}_step_pin", ("nc", ""))[0])
        if motor not in _CARTESIAN_AXIS and any(a.axis == "gamma" for a in axes):
            # Robot::load_config: after gamma, a motor needs its step and dir pins and the
            # motors are taken in order, the first one missing ending them
            if not (pin and _connected(keys.get(f"{motor}_dir_pin", ("nc", ""))[0])):
                break
        elif not pin and (motor not in _CARTESIAN_AXIS or f"{motor}_steps_per_mm" not in keys):
            continue
        axes.append(_axis(motor, f"{motor}_", "max_rate", keys, get, f, f_at, pulse, idle, setup,
                          arm))  # fmt: skip
    if keys.get("extruder_module_enable", ("false", ""))[0].lower() in ("true", "1"):
        # the old single-extruder syntax: ExtruderMaker makes one Extruder of the
        # extruder_* keys (steps/mm default 1, extruder_max_speed mm/s default 1000)
        if _connected(keys.get("extruder_step_pin", ("nc", ""))[0]):
            axes.append(_axis("extruder", "extruder_", "max_speed", keys, get, f, f_at, pulse,
                              idle, setup, arm))  # fmt: skip
    for name in dict.fromkeys(m.group(1) for k in keys if (m := _EXTRUDER.fullmatch(k))):
        base = f"extruder.{name}."
        if keys.get(base + "enable", ("false", ""))[0].lower() not in ("true", "1"):
            continue  # ExtruderMaker loads only enabled modules
        if not _connected(keys[base + "step_pin"][0]):
            continue
        axes.append(_axis(f"extruder.{name}", base, "max_speed", keys, get, f, f_at, pulse, idle,
                          setup, arm))  # fmt: skip
    if not axes:
        raise ConfigError(
            f"{p}: no motor with a step pin (alpha … zeta, extruder.NAME): a snippet, nothing "
            "to check"
        )
    return FirmwareConfig(
        firmware="smoothieware",
        path=p,
        axes=tuple(axes),
        files=(p,),
        notes=(
            "microseconds_per_step_pulse and base_stepping_frequency apply to every motor",
            "the pulse timer counts in 4 / core clock steps (40 ns at 100 MHz)",
            f"arm_solution {arm[0]} ({arm[1]})",
        ),
        fixer=_fix,
    )


def _axis(  # type: ignore[no-untyped-def]
    motor: str, prefix: str, rate_key: str, keys, get, f, f_at, pulse, idle, setup, arm
) -> GeneratorGuarantee:
    step_pin = keys.get(f"{prefix}step_pin", ("", ""))[0]
    dir_pin = keys.get(f"{prefix}dir_pin", ("", ""))[0]
    info: dict[str, str] = {}
    rate = Guaranteed(f, "base_stepping_frequency", f_at, "Hz", "derived",
                      "one step per base tick at most")  # fmt: skip
    extruder = rate_key == "max_speed"
    # Robot::load_config: steps_per_mm defaults to 2560 for gamma, 80 for the others; the
    # extruder module's to 1 (Extruder::config_load)
    spm_default = "1" if extruder else ("2560" if motor == "gamma" else "80")
    spm, at, _ = get(f"{prefix}steps_per_mm", spm_default, 0, 10**7, "steps/mm")
    raw = keys.get(f"{prefix}steps_per_mm", (spm_default, ""))[0]
    info["steps/mm"] = f"{raw} ({prefix}steps_per_mm, {at})"
    default, unit, per_s = ("1000", "mm/s", 1) if extruder else ("30000", "mm/min", 60)
    mr, mr_at, _ = get(f"{prefix}{rate_key}", default, 0, 10**9, unit)
    info["max rate"] = f"{float(mr):g} {unit} ({prefix}{rate_key}, {mr_at})"
    mm_s = mr / per_s
    note = "Robot.cpp append_milestone clamps each actuator to its max rate"
    if not extruder and spm > 0 and spm * mm_s > f:
        # Robot::check_max_actuator_speeds: max_rate = floorf(base / steps_per_mm) mm/s
        mm_s = Fraction(math.floor(f / spm))
        note = (f"Robot::check_max_actuator_speeds lowers max_rate to floor(base frequency / "
                f"steps_per_mm) = {mm_s} mm/s; append_milestone clamps the actuator to it")  # fmt: skip
    hz = spm * mm_s
    if hz < f:
        rate = Guaranteed(hz, f"{prefix}steps_per_mm x {prefix}{rate_key}", mr_at, unit,
                          "derived", note)  # fmt: skip
    alias = _CARTESIAN_AXIS.get(motor) if arm[0].lower() == "cartesian" else None
    if extruder:
        alias = "e" if motor in ("extruder", "extruder.hotend") else None
    return GeneratorGuarantee(
        axis=motor,
        pulse=pulse,
        idle=idle,
        dir_setup=setup,
        dir_hold=unknown(f"{prefix}dir_pin", "DIR may change while STEP is still high: measure it"),
        max_rate=rate,
        pulse_level=0 if "!" in step_pin else 1,
        dir_inverted="!" in dir_pin,
        info=info,
        aliases=(alias,) if alias else (),
    )


def _fix(axis: GeneratorGuarantee, role: FixRole, need: Fraction) -> str:
    if role == "pulse":
        return f"set `microseconds_per_step_pulse {-(-need // 1000)}`"
    if role in ("idle", "setup"):
        p = axis.pulse.value or Fraction(0)
        extra = p if role == "idle" else Fraction(0)
        return f"set `base_stepping_frequency {int(Fraction(10**9) / (need + extra))}` (or lower)"
    if role == "max_rate":
        spm = axis.info.get("steps/mm", "").split(" ")[0]
        extruder = axis.axis.startswith("extruder.")
        key = f"{axis.axis}.max_speed" if extruder else f"{axis.axis}_max_rate"
        if axis.axis == "extruder":  # the old single-extruder syntax
            key, extruder = "extruder_max_speed", True
        if spm and Fraction(spm) > 0:
            value = need / Fraction(spm) * (1 if extruder else 60)
            return f"set `{key} {at_most(value)}` ({'mm/s' if extruder else 'mm/min'})"
        return f"lower `{key}` so that it steps at most {float(need):.6g} steps/s"
    return "Smoothieware has no DIR hold setting"
