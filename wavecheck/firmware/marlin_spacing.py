"""Marlin's step spacing: the stepper interrupt's schedule, multi-stepping, and each axis's rate
and low time (:mod:`.marlin` reads the files and the timing figures).

Spacing (stepper.cpp ``pulse_phase_isr``/``isr``, stepper.h ``calc_timer_interval``, 1.1.9 to
2.1.x): the interrupt runs every axis's Bresenham on the leading axis's step events and, above
the CPU's one-step-per-interrupt rate (not in the files), takes up to 128 of them per interrupt
(``MULTISTEPPING_LIMIT``; ``DISABLE_MULTI_STEPPING`` or a limit of 1: one), waiting only the
low time between them. So any axis may step at the driver rate: its max rate is that, and
steps/unit × feedrate is only its sustained rate. Between interrupts nothing is waited: the
timer set from the leading axis's rate spaces a slow axis's steps ≥ 1 / min(2 × its rate, the
fastest axis's) (as grbl's), less the pulse: the low time is the smaller of the two.
"""

from __future__ import annotations

from collections.abc import Collection
from dataclasses import dataclass
from fractions import Fraction

from wavecheck.firmware.grbl import bresenham_spacing
from wavecheck.firmware.guarantee import Guaranteed, not_enforced, uncertain, unknown
from wavecheck.firmware.preprocessor import Headers, Num, evaluate

__all__ = [
    "LINEAR",
    "Figures",
    "Sustained",
    "axis_idle",
    "coupled",
    "driver_rate",
    "multistepping",
    "outrun",
    "sustained_rate",
]

#: The linear axes, in the order Marlin's per-axis arrays list them.
LINEAR = ("X", "Y", "Z", "I", "J", "K", "U", "V", "W")
_KINEMATIC = {
    "COREXY": "XY", "COREYX": "XY", "MARKFORGED_XY": "XY", "MARKFORGED_YX": "XY",
    "COREXZ": "XZ", "COREZX": "XZ", "COREYZ": "YZ", "COREZY": "YZ",
    # SCARA arms, polar and polargraph couple X and Y; Z passes through (scara.cpp
    # inverse_kinematics: delta.set(DEGREES(THETA), DEGREES(THETA + PSI), raw.z))
    "DELTA": "XYZ", "MORGAN_SCARA": "XY", "MP_SCARA": "XY", "AXEL_TPARA": "XYZ",
    "POLARGRAPH": "XY", "POLAR": "XY", "HANGPRINTER": "XYZD",
}  # fmt: skip
_GIGA = Fraction(10**9)


@dataclass(frozen=True)
class Figures:
    """The machine's timing figures (Marlin's are global): the pulse, the low time, DIR setup,
    the PRE delay, the hold from the leading edge, the driver rate."""

    pulse: Guaranteed
    idle: Guaranteed
    setup: Guaranteed
    pre: Guaranteed
    hold: Guaranteed
    rate: Guaranteed


def _array(h: Headers, name: str) -> tuple[list[Fraction], str] | None:
    d = h.definition(name)
    if d is None or d.value is None:
        return None
    inner = d.value.strip()
    if not (inner.startswith("{") and inner.endswith("}")):
        expanded = " ".join(t for _, t in h.expand(inner))
        inner = expanded.strip()
        if not (inner.startswith("{") and inner.endswith("}")):
            return None
    values = []
    for part in _split_top(inner[1:-1]):
        v = evaluate(h, part)
        if not isinstance(v, Num) or not 0 <= v.value <= 10**9:
            return None
        values.append(v.value)
    return (values, d.where) if values else None


def _split_top(text: str) -> list[str]:
    parts: list[str] = []
    cur: list[str] = []
    depth = 0
    for ch in text:
        if ch in "({":
            depth += 1
        elif ch in ")}":
            depth -= 1
        if ch == "," and depth == 0:
            parts.append("".join(cur))
            cur = []
        else:
            cur.append(ch)
    if "".join(cur).strip():
        parts.append("".join(cur))
    return parts


def multistepping(h: Headers) -> tuple[int, str]:
    """How many steps one stepper interrupt may take, and the setting that says so.

    ``Stepper::calc_timer_interval`` (stepper.h, 2.0.x; ``calc_multistep_timer_interval`` in
    2.1.x) doubles the steps per interrupt while the leading axis's rate is above the CPU's
    ``MAX_STEP_ISR_FREQUENCY_<n>X`` estimates (not in the configuration), up to 128, or
    ``MULTISTEPPING_LIMIT`` (2.1.x; Conditionals_adv.h "Multi-Stepping Limit": 128 when not
    defined); ``DISABLE_MULTI_STEPPING`` (2.0.x and 1.1.9) keeps one step per interrupt."""
    if h.enabled("DISABLE_MULTI_STEPPING") is True:
        d = h.definition("DISABLE_MULTI_STEPPING")
        return 1, f"DISABLE_MULTI_STEPPING at {d.where if d else '?'}"
    d = h.definition("MULTISTEPPING_LIMIT")
    if d is not None:
        v = evaluate(h, d.value or "")
        if isinstance(v, Num) and v.value in (1, 2, 4, 8, 16, 32, 64, 128):
            return int(v.value), f"MULTISTEPPING_LIMIT {int(v.value)} at {d.where}"
    return 128, "Marlin's default: up to 128 steps per interrupt"


#: Marlin's stepper interrupt (MarlinFirmware/Marlin Marlin/src/module/stepper.cpp, 1.1.9 to
#: 2.1.x as indexed): ``pulse_phase_isr`` runs the Bresenham of every axis on each of the
#: leading axis's step events; between the events of one interrupt it waits the low time
#: (``AWAIT_LOW_PULSE``, skipped for the first step: ``firstStep``); ``isr()`` schedules the
#: next interrupt from the leading axis's rate and runs the pulse phase again at once when that
#: time has already passed ("Advance pulses if not enough time to wait for the next ISR").
_ISR = ("stepper.cpp pulse_phase_isr: the low time is waited only between the steps of one "
        "interrupt (AWAIT_LOW_PULSE after the first); an interrupt's first step waits for the "
        "timer, set from the leading axis's rate (isr(): at once when that time has passed)")  # fmt: skip


def axis_idle(
    figs: Figures, rate: Fraction | None, fastest: Fraction | None, packing: tuple[int, str]
) -> Guaranteed:
    """The low time of one axis: the waited figure between the steps of one interrupt (when
    it may take more than one), and between interrupts the leading axis's schedule, on whose
    events this axis steps: 1 / min(2 x its rate, the fastest axis's) apart at the least, as in
    grbl (:func:`wavecheck.firmware.grbl.bresenham_spacing`), less the pulse."""
    waited = figs.idle if packing[0] > 1 else None
    pulse = figs.pulse.value
    if rate is None or fastest is None or pulse is None or figs.pulse.status == "not_enforced":
        if waited is not None:
            return waited
        return unknown("MAXIMUM_STEPPER_RATE", f"one step per interrupt ({packing[1]}): no "
                       "low time is waited, and an axis's rate is not known; " + _ISR)  # fmt: skip
    gap = max(bresenham_spacing(rate, fastest) - pulse, Fraction(0))
    if waited is not None and (waited.value is None or waited.value <= gap):
        return waited
    return uncertain(gap, "DEFAULT_MAX_FEEDRATE", "steps/unit x feedrate of every axis", "mm/s",
                     None, "a time between stepper interrupts, which other interrupts may delay",
                     "1 / min(2 x this axis's max rate, the fastest axis's) - pulse: Bresenham "
                     "steps it on the leading axis's events; " + _ISR)  # fmt: skip


def outrun(figs: Figures, asked: dict[str, Sustained | None]) -> Figures:
    """An axis whose steps/unit x feedrate is over 1 / (pulse + low) asks the interrupt for
    more steps than its waits can space: ``isr()`` runs late and takes the next interrupt's
    first step at once ("Advance pulses if not enough time to wait for the next ISR"), after
    no low-time wait. In a move that axis leads, every axis steps on its events: the low time
    is then not enforced (the figure is kept as what the settings ask for)."""
    pulse, low = figs.pulse.value, figs.idle.value
    if not pulse or not low or figs.idle.status == "not_enforced":
        return figs
    cap = _GIGA / (pulse + low)
    fast = [f"{a} {float(r.hz):g} Hz ({r.how})" for a, r in asked.items() if r and r.hz > cap]
    if not fast:
        return figs
    why = (f"{', '.join(fast)} over the {float(cap):g} Hz that 1 / (pulse + low) allows: the "
           "interrupt runs late and steps again with no low-time wait (stepper.cpp isr(), "
           "pulse_phase_isr's first step)")  # fmt: skip
    idle = not_enforced(figs.idle.setting, why, figs.idle.where, value=low, unit=figs.idle.unit)
    return Figures(figs.pulse, idle, figs.setup, figs.pre, figs.hold, figs.rate)


def coupled(h: Headers) -> set[str]:
    """The steppers whose motion kinematics couple (steps/unit x feedrate bounds none)."""
    return {a for k, axes in _KINEMATIC.items() if h.enabled(k) for a in axes}


def driver_rate(global_rate: Guaranteed, coupled: bool) -> Guaranteed:
    note = "the driver rate Marlin times pulses for; not a cap on motion"
    if coupled:
        note += (
            "; kinematics couple this axis with others (steps/unit x feedrate does not bound it)"
        )
    # MAXIMUM_STEPPER_RATE spaces the pulses of one interrupt (it sets _MIN_PULSE_LOW_NS,
    # stepper/cycles.h); nothing caps the planner's step rate at it: no bound above
    return (
        uncertain(global_rate.value, global_rate.setting, global_rate.where, "Hz", None,
                  "the planner does not cap the step rate at MAXIMUM_STEPPER_RATE", note)
        if global_rate.value is not None
        else Guaranteed(None, global_rate.setting, global_rate.where, "Hz", "unknown", note)
    )  # fmt: skip


@dataclass(frozen=True)
class Sustained:
    hz: Fraction
    where: str
    how: str


def sustained_rate(
    h: Headers, axis: str, present: Collection[str], info: dict[str, str]
) -> Sustained | None:
    """Steps/unit x max feedrate (Hz) of an uncoupled axis (the planner keeps every axis's
    speed under its ``max_feedrate_mm_s``), else None; ``present``: the axes with a driver
    (the arrays list the linear axes present, then the extruders)."""
    spu, feed = _array(h, "DEFAULT_AXIS_STEPS_PER_UNIT"), _array(h, "DEFAULT_MAX_FEEDRATE")
    base = axis.rstrip("0123456789") if not axis.startswith("E") else "E"
    if base in coupled(h) or spu is None or feed is None:
        return None
    linear = [a for a in LINEAR if a in present]
    if base == "E":
        distinct = h.enabled("DISTINCT_E_FACTORS") is True
        # 1.1.9's HANGPRINTER has four anchors A-D before E in the arrays
        first_e = 4 if h.enabled("HANGPRINTER") else len(linear)
        index = first_e + (int(axis[1:]) if distinct else 0)
    else:
        index = LINEAR.index(base) if base in linear else len(linear)
        index = linear.index(base) if base in linear else index
    s = spu[0][min(index, len(spu[0]) - 1)]
    f = feed[0][min(index, len(feed[0]) - 1)]
    info["steps/unit"] = f"{float(s):g} (DEFAULT_AXIS_STEPS_PER_UNIT, {spu[1]})"
    info["max feedrate"] = f"{float(f):g} mm/s (DEFAULT_MAX_FEEDRATE, {feed[1]})"
    return Sustained(s * f, feed[1], f"{float(s):g} steps/unit x {float(f):g} mm/s")
