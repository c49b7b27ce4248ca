"""Smoothieware: ``config`` (reference ``firmware-timing.md`` §6).

Read: ``microseconds_per_step_pulse`` (default 1 µs), ``base_stepping_frequency`` (default
100 kHz), ``alpha/beta/gamma/delta…_steps_per_mm``, ``…_max_rate`` (mm/min, default 30000),
``…_step_pin`` and ``…_dir_pin`` (a ``!`` after the pin inverts it), ``arm_solution``. The pulse
is the setting plus interrupt time (≥ the setting); each motor steps at most once per base
tick, so the low time is ≥ one tick − the pulse and the rate ≤ the base frequency (an axis whose
max_rate × steps/mm reaches it is lowered at start-up). DIR is written when a block starts,
≈ one tick before the first pulse (uncertain); DIR hold after the leading edge is only code time
(unknown). On an arm solution other than cartesian the motors are coupled (corexy, delta,
scara…): steps/mm × max_rate does not bound their rate, so only the base frequency does.
"""

from __future__ import annotations

import os
import re
from fractions import Fraction

from wavecheck.errors import ConfigError
from wavecheck.firmware._text import number, read_text, where
from wavecheck.firmware.guarantee import (
    FirmwareConfig,
    GeneratorGuarantee,
    Guaranteed,
    Role,
    unknown,
)

__all__ = ["looks_like", "read"]

_MOTORS = ("alpha", "beta", "gamma", "delta", "epsilon", "zeta")
_CARTESIAN_AXIS = {"alpha": "x", "beta": "y", "gamma": "z"}
_LINE = re.compile(r"^\s*([A-Za-z0-9_.]+)\s+(\S+)")
_COUPLED = {
    "corexy": ("alpha", "beta"),
    "corexz": ("alpha", "beta"),
    "hbot": ("alpha", "beta"),
    "morgan": ("alpha", "beta"),
}


def looks_like(text: str) -> bool:
    """A Smoothieware config: ``alpha_steps_per_mm`` or ``alpha_step_pin`` lines."""
    return bool(re.search(r"^[ \t]*alpha_(steps_per_mm|step_pin)[ \t]", text, re.M))


def read(path: str | os.PathLike[str]) -> FirmwareConfig:
    """Read a Smoothieware ``config`` (see the module doc)."""
    p = str(path)
    keys: dict[str, tuple[str, str]] = {}
    for no, line in enumerate(read_text(path).splitlines(), 1):
        m = _LINE.match(line.split("#")[0])
        if m:
            keys.setdefault(m.group(1), (m.group(2), where(p, no)))

    def get(name: str, default: str, low: int, high: int, unit: str) -> tuple[Fraction, str, str]:
        if name in keys:
            v, at = keys[name]
            return number(v, at, name, low=low, high=high, unit=unit), at, "set"
        return Fraction(default), "firmware default", "default"

    us, us_at, us_st = get("microseconds_per_step_pulse", "1", 0, 10**4, "us")
    f, f_at, _ = get("base_stepping_frequency", "100000", 1, 10**7, "Hz")
    tick = Fraction(10**9) / f
    arm = keys.get("arm_solution", ("cartesian", "firmware default"))
    solution = arm[0].lower()
    coupled: tuple[str, ...] = _COUPLED.get(solution, ()) if solution != "cartesian" else ()
    if solution not in ("cartesian", *_COUPLED):
        coupled = _MOTORS
    pulse = Guaranteed(us * 1000, "microseconds_per_step_pulse", us_at, "us", us_st,  # type: ignore[arg-type]
                       "the pulse is this plus interrupt time (about 3 us at 1 us set)")  # fmt: skip
    idle = Guaranteed(max(tick - us * 1000, Fraction(0)), "base_stepping_frequency", f_at, "Hz",
                      "derived", "one base tick minus the set pulse (a longer real pulse shortens "
                      "it)")  # fmt: skip
    setup = Guaranteed(tick, "base_stepping_frequency", f_at, "Hz", "uncertain",
                       "DIR is written when a block starts, about one tick before its first "
                       "pulse")  # fmt: skip
    axes = []
    for motor in _MOTORS:
        if f"{motor}_step_pin" not in keys and f"{motor}_steps_per_mm" not in keys:
            continue
        axes.append(_axis(motor, keys, get, f, f_at, pulse, idle, setup, motor in coupled, arm))
    if not axes:
        raise ConfigError(f"{p}: no alpha/beta/gamma motor settings (a snippet: nothing to check)")
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
    motor: str, keys, get, f, f_at, pulse, idle, setup, coupled: bool, arm
) -> GeneratorGuarantee:
    step_pin = keys.get(f"{motor}_step_pin", ("", ""))[0]
    dir_pin = keys.get(f"{motor}_dir_pin", ("", ""))[0]
    info: dict[str, str] = {}
    rate = Guaranteed(f, "base_stepping_frequency", f_at, "Hz", "derived",
                      "one step per base tick at most")  # fmt: skip
    if f"{motor}_steps_per_mm" in keys:
        spm, at, _ = get(f"{motor}_steps_per_mm", "0", 0, 10**7, "steps/mm")
        info["steps/mm"] = f"{float(spm):g} ({motor}_steps_per_mm, {at})"
        mr, mr_at, _ = get(f"{motor}_max_rate", "30000", 0, 10**9, "mm/min")
        info["max rate"] = f"{float(mr):g} mm/min ({motor}_max_rate, {mr_at})"
        hz = spm * mr / 60
        if coupled:
            rate = Guaranteed(f, "base_stepping_frequency", f_at, "Hz", "derived",
                              f"arm_solution {arm[0]} couples the motors: only the base "
                              "frequency bounds the rate")  # fmt: skip
        elif hz < f:
            rate = Guaranteed(hz, f"{motor}_steps_per_mm x {motor}_max_rate / 60", mr_at,
                              "mm/min", "derived")  # fmt: skip
    alias = _CARTESIAN_AXIS.get(motor) if arm[0].lower() == "cartesian" else None
    return GeneratorGuarantee(
        axis=motor,
        pulse=pulse,
        idle=idle,
        dir_setup=setup,
        dir_hold=unknown(f"{motor}_dir_pin", "DIR may change while STEP is still high: measure it"),
        max_rate=rate,
        pulse_level=0 if "!" in step_pin else 1,
        dir_inverted="!" in dir_pin,
        info=info,
        aliases=(alias,) if alias else (),
    )


def _fix(axis: GeneratorGuarantee, role: Role, need: Fraction) -> str:
    if role == "pulse":
        return f"set `microseconds_per_step_pulse {-(-need // 1000)}`"
    if role in ("idle", "setup"):
        p = axis.pulse.value or Fraction(0)
        extra = p if role == "idle" else Fraction(0)
        return f"lower `base_stepping_frequency` to at most {int(Fraction(10**9) / (need + extra))}"
    if role == "max_rate":
        return f"lower `{axis.axis}_max_rate` so that it steps at most {float(need):.6g} steps/s"
    return "Smoothieware has no DIR hold setting"
