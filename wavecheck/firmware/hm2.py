"""Mesa hostmot2 stepgen: ``setp hm2_<board>.<n>.stepgen.NN.steplen/stepspace/dirsetup/dirhold``
(ns) in the HAL files of a LinuxCNC configuration (reference ``firmware-timing.md`` §8).

The driver truncates each ns value to clocks of the stepgen clock ``f`` (14-bit registers; at
most 0x3FFF clocks); the firmware holds the pulse and the space N+1 clocks, so
``step_high ≥ (⌊steplen·f⌋+1)/f > steplen`` always: without the clock the set value is the bound.
DIR setup loads N clocks (≈ ⌊dirsetup·f⌋/f, up to one clock short: ``uncertain``).

DIR hold is what the hardware does, not what the man page says ("after a step ends"): the VHDL
(hostmot2 ``kubstepgenz.vhd``, simulated under GHDL with the registers as the hm2 driver writes
them) loads the hold counter when the pulse starts, so DIR may change max(steplen, dirhold) after
the leading edge, max(0, dirhold − steplen) after the trailing edge (steplen 2.01 µs, dirhold
1.02 µs: DIR changed in the clock of STEP's falling edge; dirhold 20 µs, steplen ~4.5 µs: 15.48
µs after it). Without the clock the trailing figure may be up to two clocks short (``uncertain``).
Max rate: 1e9/(steplen + stepspace), and maxvel × |position-scale| when maxvel is set. Unset
parameters start at 0x3FFF clocks.
"""

from __future__ import annotations

import re
from fractions import Fraction

from wavecheck.firmware._linuxcnc_files import LinuxCNCFiles
from wavecheck.firmware._text import number
from wavecheck.firmware.guarantee import (
    FixRole,
    GeneratorGuarantee,
    Guaranteed,
    at_least,
    at_most,
)
from wavecheck.firmware.linuxcnc import joint_of
from wavecheck.linuxcnc.files import resolve_ref

__all__ = ["STEPGEN", "axes", "fix"]

#: An hm2 stepgen parameter: ``hm2_<board>.<n>.stepgen.<NN>.<param>``.
STEPGEN = re.compile(r"^(hm2_[^.\s]+\.\d+)\.stepgen\.(\d+)\.([a-z_-]+)$")
_PARAMS = ("steplen", "stepspace", "dirsetup", "dirhold", "position-scale", "maxvel", "step_type")
_REG_MAX = 0x3FFF
_VHDL = (
    "the hold counter starts with the pulse (hostmot2 kubstepgenz.vhd, as simulated), not after "
    "the step ends as the man page says"
)


def axes(files: LinuxCNCFiles, clock_hz: Fraction | None) -> list[GeneratorGuarantee]:
    """One guarantee per hm2 stepgen that the HAL files set a parameter of."""
    gens: dict[tuple[str, str], dict[str, tuple[Fraction, str]]] = {}
    for name, (raw, at) in files.setp.items():
        m = STEPGEN.match(name)
        if m and m.group(3) in _PARAMS:
            value = resolve_ref(raw, files.ini, at)
            gens.setdefault((m.group(1), m.group(2)), {})[m.group(3)] = (
                number(value, at, name, low=-(10**9), high=10**12),
                at,
            )
    return [
        _axis(board, nn, params, clock_hz, files) for (board, nn), params in sorted(gens.items())
    ]


def _axis(
    board: str,
    nn: str,
    params: dict[str, tuple[Fraction, str]],
    f: Fraction | None,
    files: LinuxCNCFiles,
) -> GeneratorGuarantee:
    def fig(name: str, extra_clock: int, status: str, note: str = "") -> Guaranteed:
        if name not in params:
            if f is None:
                return Guaranteed(None, name, "", "ns", "unknown",
                                  "not set: 0x3FFF clocks at load (clock unknown)")  # fmt: skip
            return Guaranteed(Fraction(_REG_MAX + extra_clock) / f * 10**9, name,
                              "driver default", "ns", "default")  # fmt: skip
        ns, at = params[name]
        if f is None:
            return Guaranteed(ns, name, at, "ns", status, note)  # type: ignore[arg-type]
        reg = min(int(max(ns, Fraction(0)) * f / 10**9), _REG_MAX)
        return Guaranteed(
            Fraction(reg + extra_clock) * 10**9 / f, name, at, "ns",
            "derived" if extra_clock else "uncertain",
            f"{reg} clocks{' + 1' if extra_clock else ''} at {float(f):g} Hz"
            + (f"; {note}" if note else ""),
        )  # fmt: skip

    pulse = fig("steplen", 1, "set")
    idle = fig("stepspace", 1, "set")
    setup = fig("dirsetup", 0, "uncertain", "loads N clocks: up to one clock short")
    hold_raw = fig("dirhold", 0, "uncertain")
    hold, trailing = _hold(pulse, hold_raw, f is not None)
    info: dict[str, str] = {}
    rate = Guaranteed(None, "steplen + stepspace", "", "ns", "unknown")
    if pulse.value is not None and idle.value is not None and pulse.value + idle.value > 0:
        rate = Guaranteed(Fraction(10**9) / (pulse.value + idle.value),
                          "1e9 / (steplen + stepspace)", pulse.where, "ns", "derived")  # fmt: skip
    mv, scale = params.get("maxvel"), params.get("position-scale")
    if scale:
        info["position-scale"] = f"{scale[0]} steps/unit ({scale[1]})"
    if mv and scale and mv[0] > 0:
        info["maxvel"] = f"{float(mv[0]):g} units/s ({mv[1]})"
        hz = mv[0] * abs(scale[0])
        if rate.value is None or hz < rate.value:
            rate = Guaranteed(hz, "maxvel x position-scale", mv[1], "units/s", "derived")
    notes: tuple[str, ...] = ()
    if "step_type" in params and params["step_type"][0] != 0:
        notes = (f"step_type {params['step_type'][0]} ({params['step_type'][1]}): only step/dir "
                 "(0) is modelled",)  # fmt: skip
    joint, letter = joint_of(files, f"{board}.stepgen.{nn}")
    aliases = tuple(
        a
        for a in (f"{board}.stepgen.{nn}", f"joint.{joint}" if joint is not None else "", letter)
        if a
    )
    return GeneratorGuarantee(
        axis=f"stepgen.{nn}",
        pulse=pulse,
        idle=idle,
        dir_setup=setup,
        dir_hold=hold,
        max_rate=rate,
        dir_hold_trailing=trailing,
        info=info,
        notes=notes,
        aliases=aliases,
    )


def _hold(pulse: Guaranteed, hold: Guaranteed, clocked: bool) -> tuple[Guaranteed, Guaranteed]:
    """(from the leading edge, from the trailing edge): the hold counter starts with the pulse
    (kubstepgenz.vhd), so max(steplen, dirhold) and max(0, dirhold - steplen)."""
    if hold.value is None or pulse.value is None:
        return (
            Guaranteed(None, "dirhold", hold.where, "ns", "unknown", hold.note),
            Guaranteed(None, "dirhold", hold.where, "ns", "unknown", hold.note),
        )
    lead = Guaranteed(max(pulse.value, hold.value), "max(steplen, dirhold)", hold.where, "ns",
                      hold.status, f"{_VHDL}; {hold.note}" if hold.note else _VHDL)  # fmt: skip
    short = "" if clocked else "; without the stepgen clock up to two clocks short"
    trail = Guaranteed(max(hold.value - pulse.value, Fraction(0)), "dirhold - steplen",
                       hold.where, "ns", "derived" if clocked else "uncertain",
                       f"{_VHDL}{short}")  # fmt: skip
    return lead, trail


def fix(axis: GeneratorGuarantee, role: FixRole, need: Fraction) -> str:
    """The hm2 ``setp`` line to add so that ``role`` reaches ``need`` (the INI value the HAL
    file names, ``STEPLEN`` …, is the other place to change it)."""
    full = axis.aliases[0] if axis.aliases else f"hm2_….{axis.axis}"
    name = {"pulse": "steplen", "idle": "stepspace", "setup": "dirsetup",
            "hold": "dirhold", "trailing_hold": "dirhold"}.get(role)  # fmt: skip
    if name is None:
        scale = axis.info.get("position-scale", "").split(" ")[0]
        if scale and Fraction(scale):
            return f"add `setp {full}.maxvel {at_most(need / abs(Fraction(scale)))}` (units/s)"
        pulse = axis.pulse.value or Fraction(0)
        return f"add `setp {full}.stepspace {at_least(Fraction(10**9) / need - pulse)}` (ns)"
    if role == "trailing_hold" and axis.pulse.value is not None:
        need += axis.pulse.value  # the hold counter starts with the pulse (kubstepgenz.vhd)
    return f"add `setp {full}.{name} {int(-(-need // 1))}` (ns; the INI's {name.upper()})"
