"""Marlin: ``Configuration.h`` + ``Configuration_adv.h`` (reference ``firmware-timing.md`` §4).

Read (the first active ``#define`` of each name; preprocessor conditions are not evaluated):
``X_DRIVER_TYPE`` … ``E7_DRIVER_TYPE``, ``MINIMUM_STEPPER_PULSE_NS`` (2.1.3) or
``MINIMUM_STEPPER_PULSE`` (µs, older), ``MAXIMUM_STEPPER_RATE`` (Hz),
``MINIMUM_STEPPER_POST_DIR_DELAY`` (ns; DIR written → next pulse: the **setup**) and
``MINIMUM_STEPPER_PRE_DIR_DELAY`` (ns; end of the last pulse → DIR written: the **hold**, so
hold from the leading edge = pulse + PRE), ``EDGE_STEPPING``/``SQUARE_WAVE_STEPPING``,
``STEP_STATE_X LOW`` / ``INVERT_X_STEP_PIN true``, ``INVERT_X_DIR``,
``DEFAULT_AXIS_STEPS_PER_UNIT`` and ``DEFAULT_MAX_FEEDRATE`` (mm/s).

Marlin's defaults when a figure is not set (``Conditionals-4-adv.h``): one value for the whole
machine from the slowest driver type on any axis (:data:`DEFAULTS`). Low time =
max(1e9 / MAXIMUM_STEPPER_RATE − pulse, pulse), only pulse set: low = pulse; only the rate:
both 5e8 / rate. Busy-waits are rounded to the nearest pulse-timer tick, so the pulse may be up
to ½ tick short: the pulse is ``uncertain``. ``EDGE_STEPPING`` on a TMC axis driven over
UART/SPI (not ``_STANDALONE``) makes every STEP edge a step.
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path

from wavecheck.errors import ConfigError
from wavecheck.firmware._text import number, read_text, where
from wavecheck.firmware.model import FirmwareConfig, GeneratorGuarantee, Guaranteed, Role

__all__ = ["DEFAULTS", "MarlinDefault", "looks_like", "read"]


@dataclass(frozen=True)
class MarlinDefault:
    """One row of Marlin's per-driver defaults (``Conditionals-4-adv.h`` @ 00354a11)."""

    prefix: str
    pulse_ns: int
    dir_delay_ns: int
    max_rate_hz: int


#: Marlin's defaults by driver type (a type matches a row when it starts with ``prefix``).
DEFAULTS: tuple[MarlinDefault, ...] = (
    MarlinDefault("TB6560", 30000, 15000, 15000),
    MarlinDefault("TB6600", 3000, 1500, 150000),
    MarlinDefault("DRV8825", 2000, 650, 250000),
    MarlinDefault("A4988", 1000, 200, 500000),
    MarlinDefault("A5984", 1000, 400, 500000),
    MarlinDefault("LV8729", 500, 500, 1000000),
    MarlinDefault("TMC", 100, 100, 5000000),
)
_AXES = ("X", "Y", "Z", "I", "J", "K", "U", "V", "W", *(f"E{i}" for i in range(8)))
_DEFINE = re.compile(r"^\s*#define\s+([A-Z0-9_]+)\b(.*)$")


def looks_like(text: str) -> bool:
    """A Marlin configuration header."""
    return bool(
        re.search(
            r"#define\s+(CONFIGURATION(_ADV)?_H_VERSION|X_DRIVER_TYPE|MINIMUM_STEPPER_PULSE)", text
        )
    )


def _defines(path: Path) -> dict[str, tuple[str, str]]:
    out: dict[str, tuple[str, str]] = {}
    for no, line in enumerate(read_text(path).splitlines(), 1):
        m = _DEFINE.match(line)
        if m and m.group(1) not in out:
            value = re.sub(r"/\*.*?\*/", "", m.group(2)).split("//")[0].strip()
            out[m.group(1)] = (value, where(path, no))
    return out


def _pair(path: Path) -> list[Path]:
    folder = path if path.is_dir() else path.parent
    files = [folder / "Configuration.h", folder / "Configuration_adv.h"]
    found = [f for f in files if f.is_file()]
    if path.is_file() and path not in found:
        found.insert(0, path)
    if not found:
        raise ConfigError(f"{path}: no Configuration.h / Configuration_adv.h here")
    return found


def _list(value: str, place: str, what: str) -> list[Fraction]:
    inner = value.strip().lstrip("{").rstrip("}")
    return [number(v, place, what) for v in inner.split(",") if v.strip()]


def read(path: str | os.PathLike[str]) -> FirmwareConfig:
    """Read a Marlin configuration (a ``Configuration.h``, its ``_adv`` sibling, or their folder)."""
    files = _pair(Path(path))
    d: dict[str, tuple[str, str]] = {}
    for file in files:
        for name, entry in _defines(file).items():
            d.setdefault(name, entry)
    drivers = {a: d[f"{a}_DRIVER_TYPE"] for a in _AXES if f"{a}_DRIVER_TYPE" in d}
    if not drivers:
        raise ConfigError(f"{path}: no X_DRIVER_TYPE … defines: not a Marlin Configuration.h")
    notes = [
        "Marlin's timing is global: one pulse, DIR delay and rate for every axis",
        "preprocessor conditions are not evaluated: the first active #define of a name is read",
        "EEPROM, M92 and M203 may override steps/unit and feed rates at run time",
    ]
    rows = [r for r in DEFAULTS if any(t.startswith(r.prefix) for t, _ in drivers.values())]
    unknown_types = sorted(
        {t for t, _ in drivers.values() if not any(t.startswith(r.prefix) for r in DEFAULTS)}
    )
    unsupported = [f"driver type {t}: no Marlin default timing is modelled" for t in unknown_types]
    types = ", ".join(sorted({t for t, _ in drivers.values()}))

    def default(field: str, pick) -> tuple[Fraction, str] | None:  # type: ignore[no-untyped-def]
        if not rows:
            return None
        row = pick(rows, key=lambda r: getattr(r, field))
        return Fraction(getattr(row, field)), f"Marlin default for {row.prefix} (drivers: {types})"

    old = "MINIMUM_STEPPER_PULSE_NS" not in d and "MINIMUM_STEPPER_PULSE" in d
    if "MINIMUM_STEPPER_PULSE_NS" in d:
        v, w = d["MINIMUM_STEPPER_PULSE_NS"]
        pulse = Guaranteed(
            number(v, w, "MINIMUM_STEPPER_PULSE_NS"),
            "MINIMUM_STEPPER_PULSE_NS",
            w,
            "ns",
            "uncertain",
        )
    elif old:
        v, w = d["MINIMUM_STEPPER_PULSE"]
        pulse = Guaranteed(
            number(v, w, "MINIMUM_STEPPER_PULSE") * 1000,
            "MINIMUM_STEPPER_PULSE",
            w,
            "us",
            "uncertain",
        )
    else:
        dv = default("pulse_ns", max)
        pulse = Guaranteed(
            dv[0] if dv else None,
            "MINIMUM_STEPPER_PULSE_NS",
            dv[1] if dv else "",
            "ns",
            "default" if dv else "unknown",
        )
    pulse = Guaranteed(
        pulse.value,
        pulse.setting,
        pulse.where,
        pulse.unit,
        "uncertain" if pulse.value is not None else "unknown",
        "busy-wait rounded to the nearest pulse-timer tick: may be up to 1/2 tick short"
        + ("" if pulse.status != "default" else " (Marlin's default)"),
    )
    if "MAXIMUM_STEPPER_RATE" in d:
        v, w = d["MAXIMUM_STEPPER_RATE"]
        rate = Guaranteed(
            number(v, w, "MAXIMUM_STEPPER_RATE"), "MAXIMUM_STEPPER_RATE", w, "Hz", "set"
        )
    else:
        dv = default("max_rate_hz", min)
        rate = Guaranteed(
            dv[0] if dv else None,
            "MAXIMUM_STEPPER_RATE",
            dv[1] if dv else "",
            "Hz",
            "default" if dv else "unknown",
        )
    idle = _low(pulse, rate)
    delays: dict[str, Guaranteed] = {}
    for key in ("POST", "PRE"):
        name = f"MINIMUM_STEPPER_{key}_DIR_DELAY"
        legacy = "MINIMUM_STEPPER_DIR_DELAY"
        if name in d:
            v, w = d[name]
            delays[key] = Guaranteed(number(v, w, name), name, w, "ns", "set")
        elif legacy in d:
            v, w = d[legacy]
            delays[key] = Guaranteed(number(v, w, legacy), legacy, w, "ns", "set")
    if "PRE" not in delays and "POST" in delays:
        post = delays["POST"]
        delays["PRE"] = Guaranteed(
            post.value,
            "MINIMUM_STEPPER_PRE_DIR_DELAY",
            post.where,
            "ns",
            "default",
            "PRE defaults to the POST value",
        )
    for key in ("POST", "PRE"):
        if key not in delays:
            dv = default("dir_delay_ns", max)
            delays[key] = Guaranteed(
                dv[0] if dv else Fraction(0),
                f"MINIMUM_STEPPER_{key}_DIR_DELAY",
                dv[1] if dv else "firmware default",
                "ns",
                "default",
                ""
                if dv
                else 'no default for these drivers: 0 ("expect at least 10 us, one stepper ISR")',
            )
    setup = delays["POST"]
    pre = delays["PRE"]
    hold = Guaranteed(
        None if pulse.value is None or pre.value is None else pulse.value + pre.value,
        "MINIMUM_STEPPER_PULSE_NS + MINIMUM_STEPPER_PRE_DIR_DELAY",
        pre.where,
        "ns",
        "derived",
        "PRE_DIR_DELAY runs after the last pulse has ended: hold from the leading edge = pulse + PRE",
    )
    edge = next((k for k in ("EDGE_STEPPING", "SQUARE_WAVE_STEPPING") if k in d), None)
    spu = (
        _list(*d["DEFAULT_AXIS_STEPS_PER_UNIT"], "DEFAULT_AXIS_STEPS_PER_UNIT")
        if "DEFAULT_AXIS_STEPS_PER_UNIT" in d
        else []
    )
    feed = (
        _list(*d["DEFAULT_MAX_FEEDRATE"], "DEFAULT_MAX_FEEDRATE")
        if "DEFAULT_MAX_FEEDRATE" in d
        else []
    )
    axes = []
    for i, (axis, (dtype, dwhere)) in enumerate(drivers.items()):
        letter = "E" if axis.startswith("E") else axis
        both = edge is not None and dtype.startswith("TMC") and not dtype.endswith("STANDALONE")
        level = 1
        for key in (f"STEP_STATE_{letter}", f"INVERT_{letter}_STEP_PIN"):
            if key in d:
                level = 0 if d[key][0] in ("LOW", "true") else 1
        inv = d.get(f"INVERT_{axis}_DIR", d.get(f"INVERT_{letter}_DIR", ("false", "")))[0] == "true"
        info = {"driver type": f"{dtype} ({dwhere})"}
        axis_rate = rate
        if spu and feed:
            s, fr = spu[min(i, len(spu) - 1)], feed[min(i, len(feed) - 1)]
            info["steps/unit"] = (
                f"{float(s):g} (DEFAULT_AXIS_STEPS_PER_UNIT, {d['DEFAULT_AXIS_STEPS_PER_UNIT'][1]})"
            )
            info["max feedrate"] = (
                f"{float(fr):g} mm/s (DEFAULT_MAX_FEEDRATE, {d['DEFAULT_MAX_FEEDRATE'][1]})"
            )
            hz = s * fr
            if rate.value is None or hz < rate.value:
                axis_rate = Guaranteed(
                    hz,
                    "DEFAULT_AXIS_STEPS_PER_UNIT x DEFAULT_MAX_FEEDRATE",
                    d["DEFAULT_MAX_FEEDRATE"][1],
                    "mm/s",
                    "derived",
                    f"{float(s):g} steps/unit x {float(fr):g} mm/s",
                )
        axes.append(
            GeneratorGuarantee(
                axis=axis,
                pulse=pulse,
                idle=idle,
                dir_setup=setup,
                dir_hold=hold,
                max_rate=axis_rate,
                pulse_level=level,
                both_edges=both,
                dir_hold_trailing=pre,
                dir_inverted=inv,
                info=info,
                notes=(f"{edge} with a {dtype} driver: every STEP edge is a step",) if both else (),
            )
        )
    return FirmwareConfig(
        firmware="marlin",
        path=str(path),
        axes=tuple(axes),
        files=tuple(str(f) for f in files),
        unsupported=tuple(unsupported),
        notes=tuple(notes),
        fixer=_fixer(old),
    )


def _low(pulse: Guaranteed, rate: Guaranteed) -> Guaranteed:
    p, r = pulse.value, rate.value
    if p is None and r is None:
        return Guaranteed(
            None, "MAXIMUM_STEPPER_RATE", "", "Hz", "unknown", "neither pulse nor rate known"
        )
    if r is None or r <= 0:
        assert p is not None
        return Guaranteed(
            p,
            pulse.setting,
            pulse.where,
            pulse.unit,
            "derived",
            "only the pulse is set: low = pulse",
        )
    if p is None or p == 0:
        return Guaranteed(
            Fraction(5 * 10**8) / r,
            "MAXIMUM_STEPPER_RATE",
            rate.where,
            "Hz",
            "derived",
            "only the rate is set: low = 5e8 / rate",
        )
    return Guaranteed(
        max(Fraction(10**9) / r - p, p),
        "MAXIMUM_STEPPER_RATE",
        rate.where,
        "Hz",
        "derived",
        "max(1e9 / MAXIMUM_STEPPER_RATE - pulse, pulse), enforced between pulses of one interrupt",
    )


def _fixer(old: bool):  # type: ignore[no-untyped-def]
    def ns(v: Fraction) -> int:
        return int(-(-v // 1))

    def fix(axis: GeneratorGuarantee, role: Role, need: Fraction) -> str:
        if role == "pulse":
            if old:
                return f"Marlin: define MINIMUM_STEPPER_PULSE {int(-(-need // 1000))} (us)"
            return f"Marlin: define MINIMUM_STEPPER_PULSE_NS {ns(need)}"
        if role == "idle":
            p = axis.pulse.value or Fraction(0)
            if need > p:
                return f"Marlin: define MAXIMUM_STEPPER_RATE {int(Fraction(10**9) / (p + need))} (or lower)"
            return f"Marlin: define MINIMUM_STEPPER_PULSE_NS {ns(need)}"
        if role == "dir_setup":
            return f"Marlin: define MINIMUM_STEPPER_POST_DIR_DELAY {ns(need)}"
        if role == "dir_hold":
            p = axis.pulse.value or Fraction(0)
            return f"Marlin: define MINIMUM_STEPPER_PRE_DIR_DELAY {ns(max(need - p, Fraction(0)))}"
        return (
            f"Marlin: lower DEFAULT_MAX_FEEDRATE for {axis.axis} so that it steps at most "
            f"{float(need):.6g} steps/s, or define MAXIMUM_STEPPER_RATE {int(need)}"
        )

    return fix
