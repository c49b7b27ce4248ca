"""Mesa hostmot2 stepgen: ``setp hm2_<board>.<n>.stepgen.NN.steplen/stepspace/dirsetup/dirhold``
(ns) in the HAL files of a LinuxCNC configuration (reference ``firmware-timing.md`` §8).

The driver truncates each ns value to clocks of the stepgen clock ``f`` (14-bit registers; at
most 0x3FFF clocks); the firmware holds the pulse and the space N+1 clocks, so
``step_high ≥ (⌊steplen·f⌋+1)/f > steplen`` always: without the clock the set value is the bound.
DIR setup and hold load N clocks (≈ ⌊dirsetup·f⌋/f, up to one clock short: ``uncertain``), and
whether dirhold counts from the pulse's start (the VHDL) or its end (the man page) is disputed, so
the hold from the leading edge is taken as dirhold alone. Max rate: 1e9/(steplen + stepspace),
and maxvel × |position-scale| when maxvel is set. Unset parameters start at 0x3FFF clocks.
"""

from __future__ import annotations

import os
import re
from fractions import Fraction

from wavecheck.errors import ConfigError
from wavecheck.firmware._linuxcnc_files import expand_refs, files_of
from wavecheck.firmware._text import number, read_text, where
from wavecheck.firmware.model import FirmwareConfig, GeneratorGuarantee, Guaranteed, Role
from wavecheck.linuxcnc.files import hal_words, resolve_ref

__all__ = ["looks_like", "read"]

_SETP = re.compile(r"^hm2_[^.]+\.\d+\.stepgen\.(\d+)\.([a-z_-]+)$")
_PARAMS = ("steplen", "stepspace", "dirsetup", "dirhold", "position-scale", "maxvel", "step_type")
_REG_MAX = 0x3FFF


def looks_like(text: str) -> bool:
    """A HAL file with hm2 stepgen parameters, or an INI with a ``[HOSTMOT2]`` section."""
    return bool(
        re.search(r"\bhm2_\S*\.stepgen\.\d+\.", text) or re.search(r"^\s*\[HOSTMOT2\]", text, re.M)
    )


def read(path: str | os.PathLike[str], clock_hz: Fraction | None = None) -> FirmwareConfig:
    """Read the hm2 stepgens of a LinuxCNC INI (its HALFILEs) or of one HAL file."""
    text = read_text(path)
    ini, hals, notes = files_of(path, text)
    gens: dict[str, dict[str, tuple[Fraction, str]]] = {}
    for hal in hals:
        lines = read_text(hal).replace("\\\n", " ").splitlines()
        for no, raw in enumerate(lines, 1):
            line = expand_refs(raw.split("#", 1)[0].strip(), ini)
            words = hal_words(line) if line else []
            if len(words) >= 3 and words[0] == "setp":
                m = _SETP.match(words[1])
                if m and m.group(2) in _PARAMS:
                    at = where(hal, no)
                    value = resolve_ref(words[2], ini, at)
                    gens.setdefault(m.group(1), {})[m.group(2)] = (number(value, at, words[1]), at)
    if not gens:
        raise ConfigError(
            f"{path}: no `setp hm2_….stepgen.NN.*` line in {', '.join(map(str, hals)) or 'it'}"
        )
    f = clock_hz
    axes = []
    for nn, params in sorted(gens.items()):
        axes.append(_axis(nn, params, f))
    clock = "unknown (give it for the exact rounding)" if f is None else f"{float(f):g} Hz"
    return FirmwareConfig(
        firmware="hm2",
        path=str(path),
        axes=tuple(axes),
        files=(str(path), *map(str, hals)),
        notes=(f"stepgen clock {clock}; registers are truncated to whole clocks", *notes),
        fixer=_fix,
    )


def _axis(
    nn: str, params: dict[str, tuple[Fraction, str]], f: Fraction | None
) -> GeneratorGuarantee:
    def fig(name: str, extra_clock: int, status: str, note: str = "") -> Guaranteed:
        if name not in params:
            if f is None:
                return Guaranteed(
                    None,
                    name,
                    "",
                    "ns",
                    "unknown",
                    "not set: 0x3FFF clocks at load (clock unknown)",
                )
            return Guaranteed(
                Fraction(_REG_MAX + extra_clock) / f * 10**9,
                name,
                "driver default",
                "ns",
                "default",
            )
        ns, at = params[name]
        if f is None:
            return Guaranteed(ns, name, at, "ns", status, note)  # type: ignore[arg-type]
        reg = min(int(ns * f / 10**9), _REG_MAX)
        return Guaranteed(
            Fraction(reg + extra_clock) * 10**9 / f,
            name,
            at,
            "ns",
            "derived" if extra_clock else "uncertain",
            f"{reg} clocks{' + 1' if extra_clock else ''} at {float(f):g} Hz"
            + (f"; {note}" if note else ""),
        )

    pulse = fig("steplen", 1, "set")
    idle = fig("stepspace", 1, "set")
    setup = fig("dirsetup", 0, "uncertain", "loads N clocks: up to one clock short")
    hold = fig(
        "dirhold",
        0,
        "uncertain",
        "counted from the pulse's start (VHDL) or its end (man page): disputed",
    )
    info: dict[str, str] = {}
    rate = Guaranteed(None, "steplen + stepspace", "", "ns", "unknown")
    if pulse.value is not None and idle.value is not None and pulse.value + idle.value > 0:
        rate = Guaranteed(
            Fraction(10**9) / (pulse.value + idle.value),
            "1e9 / (steplen + stepspace)",
            pulse.where,
            "ns",
            "derived",
        )
    mv, scale = params.get("maxvel"), params.get("position-scale")
    if scale:
        info["position-scale"] = f"{float(scale[0]):g} steps/unit ({scale[1]})"
    if mv and scale and mv[0] > 0:
        info["maxvel"] = f"{float(mv[0]):g} units/s ({mv[1]})"
        hz = mv[0] * abs(scale[0])
        if rate.value is None or hz < rate.value:
            rate = Guaranteed(hz, "maxvel x position-scale", mv[1], "units/s", "derived")
    notes: tuple[str, ...] = ()
    if "step_type" in params and params["step_type"][0] != 0:
        notes = (
            f"step_type {params['step_type'][0]} ({params['step_type'][1]}): only step/dir (0) is modelled",
        )
    return GeneratorGuarantee(
        axis=f"stepgen.{nn}",
        pulse=pulse,
        idle=idle,
        dir_setup=setup,
        dir_hold=hold,
        max_rate=rate,
        info=info,
        notes=notes,
    )


def _fix(axis: GeneratorGuarantee, role: Role, need: Fraction) -> str:
    name = {
        "pulse": "steplen",
        "idle": "stepspace",
        "dir_setup": "dirsetup",
        "dir_hold": "dirhold",
    }.get(role)
    if name is None:
        return f"lower hm2_….{axis.axis}.maxvel so that it steps at most {float(need):.6g} steps/s"
    return f"set hm2_….{axis.axis}.{name} (the INI's {name.upper()}) to at least {int(-(-need // 1))} ns"
