"""RepRapFirmware: ``config.g`` (reference ``firmware-timing.md`` §5).

Read: ``M569 P<driver> S<dir> T<a:b:c:d>`` (µs: step high, step low, DIR setup before the
rising edge, DIR hold after the *falling* edge; one value is used for all four, two or three
are refused by the firmware), ``M584`` (axis → drivers; default X0 Y1 Z2 E3), ``M92``
(steps/mm), ``M203`` (mm/min). Timing is global: a driver with any field over 0.2 µs is "slow"
and every slow driver gets the largest value of each field over all slow drivers (rounded up to
step clocks); a driver without T is "fast": the firmware assumes ≥ 0.2 µs high and low and waits
for nothing, so its DIR setup and hold cannot be read from the file. The Duet 3 MB6XD (default
2.5 µs each, worst of all drivers) is not distinguished from the other boards.
"""

from __future__ import annotations

import os
import re
from fractions import Fraction

from wavecheck.firmware._text import number, read_text, where
from wavecheck.firmware.model import FirmwareConfig, GeneratorGuarantee, Guaranteed, Role, unknown

__all__ = ["looks_like", "read"]

_FAST_NS = Fraction(200)
_WORD = re.compile(r"([A-Za-z])\s*(\"[^\"]*\"|[-+0-9.:]+)?")
_FIELDS = ("pulse", "idle", "dir_setup", "dir_hold")


def looks_like(text: str) -> bool:
    """A ``config.g``: ``M569``/``M584``/``M92`` commands at line starts."""
    return len(re.findall(r"^\s*M(569|584|92|350|203)\b", text, re.M)) >= 2


def _words(line: str) -> dict[str, str]:
    code = line.split(";")[0]
    return {m.group(1).upper(): (m.group(2) or "") for m in _WORD.finditer(code)}


def read(path: str | os.PathLike[str]) -> FirmwareConfig:
    """Read a ``config.g`` (see the module doc)."""
    p = str(path)
    axis_drivers: dict[str, list[str]] = {"X": ["0"], "Y": ["1"], "Z": ["2"]}
    timing: dict[str, tuple[list[Fraction], str]] = {}
    spm: dict[str, tuple[Fraction, str]] = {}
    speed: dict[str, tuple[Fraction, str]] = {}
    unsupported: list[str] = []
    for no, line in enumerate(read_text(path).splitlines(), 1):
        w = _words(line)
        at = where(p, no)
        cmd = next(iter(w.items()), ("", ""))
        if cmd[0] != "M":
            continue
        rest = {k: v for k, v in list(w.items())[1:]}
        if cmd[1] == "584":
            for axis, drv in rest.items():
                if axis in "XYZUVWABC" and drv:
                    axis_drivers[axis] = drv.split(":")
        elif cmd[1] == "569" and "P" in rest and "T" in rest:
            fields = [number(v, at, "M569 T") * 1000 for v in rest["T"].split(":")]
            if len(fields) == 1:
                fields *= 4
            if len(fields) != 4:
                unsupported.append(
                    f"{at}: M569 T{rest['T']}: RepRapFirmware refuses 2 or 3 values (bad timing parameter); ignored"
                )
                continue
            timing[rest["P"]] = (fields, at)
        elif cmd[1] in ("92", "203"):
            if "S" in rest and cmd[1] == "92":
                unsupported.append(f"{at}: M92 S (microstepping rescale) is not modelled")
            for axis, v in rest.items():
                if axis in "XYZUVWABC" and v and ":" not in v:
                    (spm if cmd[1] == "92" else speed)[axis] = (
                        number(v, at, f"M{cmd[1]} {axis}"),
                        at,
                    )
    slow = {d: t for d, t in timing.items() if any(f > _FAST_NS for f in t[0])}
    worst: list[Guaranteed] = []
    for i, _role in enumerate(_FIELDS):
        if not slow:
            break
        drv, (fields, at) = max(slow.items(), key=lambda kv: kv[1][0][i])
        worst.append(
            Guaranteed(
                fields[i],
                f"M569 P{drv} T (field {i + 1})",
                at,
                "us",
                "set",
                "largest over all slow drivers; rounded up to step clocks",
            )
        )
    axes = []
    for axis, drivers in axis_drivers.items():
        if axis not in spm and axis not in speed and not any(d in timing for d in drivers):
            continue
        is_slow = any(d in slow for d in drivers)
        if is_slow:
            pulse, idle, setup, hold_t = worst
            hold = Guaranteed(
                pulse.value + hold_t.value,  # type: ignore[operator]
                "M569 T fields 1 + 4",
                hold_t.where,
                "us",
                "derived",
                "hold counts from the falling edge: from the rising edge add the high time",
            )
        else:
            note = "no T: a fast driver; the firmware assumes >= 0.2 us high and low"
            pulse = Guaranteed(_FAST_NS, "M569 T", "firmware default", "us", "uncertain", note)
            idle = pulse
            setup = unknown("M569 T", "fast driver: no DIR setup wait; measure it")
            hold = unknown("M569 T", "fast driver: no DIR hold wait; measure it")
            hold_t = None
        info = {"drivers": ",".join(drivers)}
        rate = Guaranteed(None, "M203", "", "mm/min", "unknown", "no M92/M203 for this axis")
        if axis in spm:
            info["steps/mm"] = f"{float(spm[axis][0]):g} (M92, {spm[axis][1]})"
        if axis in speed:
            info["max speed"] = f"{float(speed[axis][0]):g} mm/min (M203, {speed[axis][1]})"
        if axis in spm and axis in speed:
            rate = Guaranteed(
                spm[axis][0] * speed[axis][0] / 60,
                "M92 x M203 / 60",
                speed[axis][1],
                "mm/min",
                "derived",
            )
        axes.append(
            GeneratorGuarantee(
                axis=axis,
                pulse=pulse,
                idle=idle,
                dir_setup=setup,
                dir_hold=hold,
                max_rate=rate,
                dir_hold_trailing=hold_t,
                info=info,
            )
        )
    return FirmwareConfig(
        firmware="reprapfirmware",
        path=p,
        axes=tuple(axes),
        files=(p,),
        unsupported=tuple(unsupported),
        notes=(
            "M569 T timing is global over all slow drivers (the largest of each field)",
            "step clock 750 kHz on Duet 3 (1.333 us), core/128 on Duet 2: figures are rounded up",
        ),
        fixer=_fix,
    )


def _fix(axis: GeneratorGuarantee, role: Role, need: Fraction) -> str:
    us = float(-(-need // 100)) / 10
    drivers = axis.info.get("drivers", "?").split(",")[0]
    field = {"pulse": 1, "idle": 2, "dir_setup": 3, "dir_hold": 4}.get(role)
    if field == 4 and axis.pulse.value is not None:
        us = float(-(-(need - axis.pulse.value) // 100)) / 10
    if field is None:
        return f"lower M203 {axis.axis} so that it steps at most {float(need):.6g} steps/s"
    return f"M569 P{drivers} T a:b:c:d with field {field} at least {max(us, 0):g} (us)"
