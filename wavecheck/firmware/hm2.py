"""Mesa hostmot2 stepgen: ``setp hm2_<board>.<n>.stepgen.NN.steplen/stepspace/dirsetup/dirhold``
(ns) in the HAL files of a LinuxCNC configuration.

The driver turns each ns value into a 14-bit register of stepgen clocks ``f`` with C doubles,
truncating: ``reg = ns * (f / 1e9)``, at most 0x3FFF (LinuxCNC ``src/hal/drivers/mesa-hostmot2/
stepgen.c`` 348-387 at git f1270d6ed7). The firmware (hostmot2 ``src/kubstepgenz.vhd`` as
published in IgorYeremin/hostmot2-firmware@8a8dcbd; line numbers below are that file's) holds
STEP high N+1 clocks and low N+1 clocks (the pulse counter is loaded at the step, 210-211, and
STEP cleared a clock after it reaches 0, 199-201), so ``step_high ≥ (⌊steplen·f⌋+1)/f >
steplen``: without the clock the set value is the bound. DIR setup loads N clocks (216-219:
⌊dirsetup·f⌋/f, the lower bound; under GHDL the next step came N + 2 clocks after the DIR
change, 300 -> 302).

DIR hold is what the hardware does, not what the man page says ("after a step ends"): the hold
counter is loaded with the pulse (212-213), and DIR may change as soon as it has run out
(215-219, 307), whatever STEP is doing. Run under GHDL (2.0.0, registers as the driver writes
them, 100 MHz, the direction reversed just after a STEP rising edge) it gives: dirhold 102
clocks, steplen 201: DIR changed 103 clocks after the rising edge, while STEP was high (it fell
at 202); dirhold 2000, steplen 450: DIR changed 2001 clocks after the rising edge, 1550 after
the falling one. So the hold is dirhold (+1 clock) from the leading edge and dirhold − steplen
from the trailing edge; when dirhold < steplen DIR can change during the pulse, and a drive that
counts the trailing edge may count that step in the new direction (hold 0, and only steplen −
dirhold from the DIR change to that edge: ``dir_setup_trailing``). Without the clock
(``--hm2-clock``) the figures the truncation can shorten — dirsetup and the trailing ones — may
be up to a clock short, and the clock bounds that: they are ``uncertain`` with no bound (never a
PASS).

Max rate: the driver clamps the velocity to 1e9/(steplen + stepspace) steps/s and to maxvel ×
|position-scale| when maxvel is set (stepgen.c 263-315); the hardware's (N+1)+(M+1) clocks per
step are the lower of the two when the clock is known. Unset parameters start at 0x3FFF clocks
(stepgen.c 1169-1172). A printed fix is a ns value the driver turns into the register needed
(``--hm2-clock``), or the bound itself without the clock.
"""

from __future__ import annotations

import dataclasses
import re
from collections.abc import Callable
from fractions import Fraction

from wavecheck.firmware._text import number
from wavecheck.firmware.guarantee import (
    FixRole,
    GeneratorGuarantee,
    Guaranteed,
    at_least,
    uncertain,
)
from wavecheck.firmware.linuxcnc_stepgen import PARAMETER, maxvel_fix
from wavecheck.linuxcnc.configuration import LinuxCNCFiles
from wavecheck.linuxcnc.files import resolve_ref

__all__ = ["STEPGEN", "axes", "fixer", "ns_for", "register"]

#: An hm2 stepgen parameter: ``hm2_<board>.<n>.stepgen.<NN>.<param>``.
STEPGEN = re.compile(r"^(hm2_[^.\s]+\.\d+)\.stepgen\.(\d+)\.([a-z_-]+)$")
_GPIO_INVERT = re.compile(r"^(hm2_[^.\s]+\.\d+)\.gpio\.(\d+)\.invert_output$")
_PARAMS = ("steplen", "stepspace", "dirsetup", "dirhold", "position-scale", "maxvel", "step_type")
_REG_MAX = 0x3FFF
_VHDL = (
    "the hold counter starts with the pulse and DIR may change when it runs out (hostmot2 "
    "kubstepgenz.vhd 212-219, run under GHDL), not after the step ends as the man page says"
)
#: Without the stepgen clock: the driver truncates each ns value to whole clocks (stepgen.c
#: 381-385), so a figure that loses a register's truncation may be up to one clock short, and
#: the clock (the board's, which the HAL files do not give) bounds that.
_NO_CLOCK = (
    "the driver truncates each value to whole stepgen clocks (stepgen.c 381-385) and the clock "
    "is not known: give --hm2-clock"
)
_DURING = (
    "dirhold < steplen: DIR may change while STEP is high (kubstepgenz.vhd 215-219), so a drive "
    "counting the trailing edge may count that step in the new direction"
)


def register(ns: Fraction, f: Fraction) -> int:
    """The register the hm2 driver writes for ``ns`` at clock ``f``: C doubles, truncated, at
    most 0x3FFF (stepgen.c 381-385)."""
    return min(int(float(max(ns, Fraction(0))) * (float(f) / 1e9)), _REG_MAX)


def ns_for(clocks: int, f: Fraction) -> int:
    """The smallest whole ns the driver turns into ``clocks`` (:func:`register`)."""
    ns = int(-(-Fraction(clocks * 10**9) // f))
    while register(Fraction(ns), f) < clocks:
        ns += 1
    return ns


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
    inverted: dict[str, list[str]] = {}
    for name, (raw, at) in files.setp.items():
        m = _GPIO_INVERT.match(name)
        is_output = files.setp.get(name.replace(".invert_output", ".is_output"), ("0", ""))
        if (
            m
            and _true(resolve_ref(raw, files.ini, at))
            and not _true(is_output[0])  # a plain GPIO output, not a module's
        ):
            inverted.setdefault(m.group(1), []).append(f"gpio.{m.group(2)} ({at})")
    axes_ = [
        _axis(board, nn, params, clock_hz, files) for (board, nn), params in sorted(gens.items())
    ]
    return [_with_inverted_gpio(a, inverted) for a in axes_]


def _true(value: str) -> bool:
    return value.strip().lower() in ("1", "true")


def _with_inverted_gpio(
    axis: GeneratorGuarantee, inverted: dict[str, list[str]]
) -> GeneratorGuarantee:
    """A note on ``axis`` when its board inverts output pins: hostmot2 writes a pin's
    ``invert_output`` to the output-invert register for module outputs too (ioport.c
    hm2_ioport_gpio_export_hal gives "an output for some other module" the parameter,
    hm2_ioport_update sets its bit), so an inverted pin that carries this stepgen's STEP or DIR
    flips it at the pin. Which IO pin a stepgen drives is in the bitfile's pin table, not in
    the HAL files: the polarity above assumes none of them does."""
    board = next((a for a in axis.aliases if a.startswith("hm2_")), "").split(".stepgen.")[0]
    pins = inverted.get(board)
    if not pins:
        return axis
    note = (
        f"{board}: {', '.join(pins)} invert_output set; hostmot2 inverts module outputs too "
        "(ioport.c hm2_ioport_update), and the bitfile's pin table, not the HAL files, says "
        "whether one carries this stepgen's STEP or DIR: the polarity shown assumes not; check "
        "the pin table (hm2 prints it at load) or measure"
    )
    return dataclasses.replace(axis, notes=(*axis.notes, note))


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
            if extra_clock:  # (⌊ns·f⌋ + 1) / f > ns: the set value is the lower bound
                return Guaranteed(ns, name, at, "ns", status, note)  # type: ignore[arg-type]
            return uncertain(ns, name, at, "ns", None, _NO_CLOCK, note)
        reg = register(ns, f)
        return Guaranteed(
            Fraction(reg + extra_clock) * 10**9 / f, name, at, "ns", "derived",
            f"{reg} clocks{' + 1' if extra_clock else ''} at {float(f):g} Hz"
            + (f"; {note}" if note else ""),
        )  # fmt: skip

    pulse = fig("steplen", 1, "set")
    idle = fig("stepspace", 1, "set")
    setup = fig("dirsetup", 0, "derived", "the setup counter loads N clocks (kubstepgenz.vhd "
                "216-219; under GHDL the next step came N + 2 clocks after DIR)")  # fmt: skip
    hold_raw = fig("dirhold", 1, "set")
    hold, trailing = _hold(pulse, hold_raw, f is not None)
    setup_trailing = _setup_trailing(pulse, setup, hold, f is not None)
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
    joint, letter = files.joint_of(f"{board}.stepgen.{nn}")
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
        dir_setup_trailing=setup_trailing,
        info=info,
        notes=notes,
        aliases=aliases,
    )


def _hold(pulse: Guaranteed, hold: Guaranteed, clocked: bool) -> tuple[Guaranteed, Guaranteed]:
    """(from the leading edge, from the trailing edge): the hold counter starts with the pulse
    and runs out dirhold (+1 clock) later (kubstepgenz.vhd 212-219): dirhold, and dirhold -
    steplen, 0 when DIR may change during the pulse."""
    if hold.value is None or pulse.value is None:
        return (
            Guaranteed(None, "dirhold", hold.where, "ns", "unknown", hold.note),
            Guaranteed(None, "dirhold", hold.where, "ns", "unknown", hold.note),
        )
    note = f"{_VHDL}; {hold.note}" if hold.note else _VHDL
    lead = Guaranteed(hold.value, "dirhold", hold.where, "ns", hold.status, note)
    if hold.value < pulse.value:
        return lead, Guaranteed(Fraction(0), "dirhold - steplen", hold.where, "ns", "derived",
                                _DURING)  # fmt: skip
    value = hold.value - pulse.value
    trail = (
        Guaranteed(value, "dirhold - steplen", hold.where, "ns", "derived", _VHDL)
        if clocked  # (M + 1 - (N + 1)) clocks, as GHDL ran it
        else uncertain(value, "dirhold - steplen", hold.where, "ns", None, _NO_CLOCK, _VHDL)
    )
    return lead, trail


def _setup_trailing(
    pulse: Guaranteed, setup: Guaranteed, hold: Guaranteed, clocked: bool
) -> Guaranteed | None:
    """DIR change → the trailing edge when DIR may change during the pulse (dirhold <
    steplen): steplen - dirhold, or dirsetup + steplen when less; None otherwise. In clocks
    ((N + 1) - (M + 1), as GHDL ran it) when the clock is known; without it the registers'
    truncation may take up to a clock off."""
    if pulse.value is None or hold.value is None or setup.value is None:
        return None
    if hold.value >= pulse.value:
        return None
    value = min(pulse.value - hold.value, setup.value + pulse.value)
    if clocked:
        return Guaranteed(value, "steplen - dirhold", hold.where, "ns", "derived", _DURING)
    return uncertain(value, "steplen - dirhold", hold.where, "ns", None, _NO_CLOCK, _DURING)


def fixer(clock_hz: Fraction | None) -> Callable[[GeneratorGuarantee, FixRole, Fraction], str]:
    """How to say which hm2 setting to change: a ``setp`` line to add (the INI value the HAL
    file names, ``STEPLEN`` …, is the other place), with a ns value the driver turns into enough
    clocks at ``clock_hz`` (:func:`register`), the bound itself without the clock."""

    def fix(axis: GeneratorGuarantee, role: FixRole, need: Fraction) -> str:
        full = axis.aliases[0] if axis.aliases else f"hm2_….{axis.axis}"
        if role == "trailing_setup":  # DIR must not change during the pulse
            return _whole_pulse(full, axis, need, clock_hz)
        name = PARAMETER.get(role)
        if name is None:
            clamp = maxvel_fix(full, axis, need)
            if clamp:
                return clamp
            pulse = axis.pulse.value or Fraction(0)
            return f"add `setp {full}.stepspace {at_least(Fraction(10**9) / need - pulse)}` (ns)"
        if clock_hz is None:
            if role == "trailing_hold" and axis.pulse.value is not None:
                need += axis.pulse.value  # the hold counter starts with the pulse
            return f"add `setp {full}.{name} {int(-(-need // 1))}` (ns; the INI's {name.upper()})"
        counts = need * clock_hz / 10**9
        clocks = int(-(-counts // 1))
        if role in ("pulse", "idle", "hold"):  # held N + 1 clocks
            clocks = max(clocks - 1, 0)
        elif role == "trailing_hold":  # (dirhold + 1) - (steplen + 1) clocks
            clocks += int((axis.pulse.value or 0) * clock_hz / 10**9) - 1
        if clocks > _REG_MAX:
            return (f"{name} would need {clocks} clocks at {float(clock_hz):g} Hz, more than the "
                    f"register holds (0x3FFF): the hm2 stepgen cannot make it")  # fmt: skip
        return (f"add `setp {full}.{name} {ns_for(clocks, clock_hz)}` (ns: {clocks} clocks at "
                f"{float(clock_hz):g} Hz; the INI's {name.upper()})")  # fmt: skip

    return fix


def _whole_pulse(full: str, axis: GeneratorGuarantee, need: Fraction, f: Fraction | None) -> str:
    """The ``setp`` lines that keep DIR through the pulse (dirhold >= steplen) and, where the
    dirsetup set falls short, give ``need`` from a DIR change to the trailing edge (dirsetup +
    steplen)."""
    pulse = axis.pulse.value or Fraction(0)
    short = max(need - pulse, Fraction(0))
    if f is None:
        hold, setup = int(-(-pulse // 1)), int(-(-short // 1))
    else:
        hold = ns_for(int(pulse * f / 10**9) - 1, f)  # the pulse is steplen clocks + 1
        setup = ns_for(int(-(-short * f / 10**9 // 1)), f)
    lines = f"`setp {full}.dirhold {hold}`"
    if short > (axis.dir_setup.value or 0):
        lines += f" and `setp {full}.dirsetup {setup}`"
    return (f"add {lines} (ns): DIR then waits for the end of the pulse (kubstepgenz.vhd "
            "212-219), and the trailing edge comes dirsetup + steplen after a DIR change")  # fmt: skip
