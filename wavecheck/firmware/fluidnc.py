"""FluidNC: a machine ``config.yaml`` (reference ``firmware-timing.md`` §10; FluidNC's wiki
``config/axes`` and ``FluidNC/src/Stepping.cpp`` where the reference is silent).

Read with PyYAML (the node tree keeps every value's line): ``stepping:`` ``engine`` (default RMT),
``pulse_us`` (default 4, 0..30), ``dir_delay_us`` (default 0, 0..10), ``disable_delay_us``;
per axis ``steps_per_mm``,
``max_rate_mm_per_min`` and ``motor0``/``motor1`` with one driver section that has a
``step_pin`` (``standard_stepper``, ``stepstick``, ``tmc_2209`` …; an ``rc_servo`` or other
motor without one is not a step generator). ``gpio.26:low`` is an inverted pin. FluidNC's own
parser also takes ``key:value`` without a space; such lines are read as it reads them.

What each engine guarantees at the pin:

- **RMT**: each step is one RMT item, ``dir_delay_us`` at the idle level (one 0.25 µs tick when
  0) then ``pulse_us`` active: the pulse and the DIR setup are hardware-timed, before every
  pulse. Max rate 1e6 / (2·pulse + dir_delay) steps/s.
- **TIMED**: the CPU raises the pin, spins ``pulse_us`` and lowers it; ``dir_delay_us`` is spun
  after a DIR change. Both spins count CPU cycles from a read taken after the pin write
  (``timed_engine.c`` 31-33, 41-46, ``spinUntil``), so the set value is a lower bound; interrupts
  lengthen the pulse, by an amount nothing bounds, which the low time then loses (``uncertain``).
- **I2S_STATIC / I2S_STREAM** (both names find the one ``I2S`` engine in current FluidNC:
  ``Stepping.cpp`` ``find_engine`` matches the name's start): every output is a sample of the
  I2S FIFO, one sample per frame of ``i2so: min_pulse_us`` (1, 2 or 4 µs, default 2:
  ``I2SOBus``). The step is ``ceil(pulse_us / frame)`` frames, at least one, ``pulse_us`` capped
  at 20 µs (``i2s_engine.cpp`` ``init_engine``, ``I2S_MAX_USEC_PER_PULSE``): hardware-timed. A
  DIR change is pushed as one sample before the step's samples and the CPU then spins
  ``dir_delay_us`` (``finish_dir``); the spin only widens the gap when the FIFO has run dry, so
  the DIR setup the engine guarantees is one frame, whatever ``dir_delay_us`` says. Max rate
  1e6 / (2 × pulse frames × frame) (``max_pulses_per_sec``).

DIR hold is not timed by any engine: DIR changes at a later step event, at least one pulse
after the last pulse's leading edge when the step rate stays under the engine's maximum. Under
RMT and TIMED the step events are the stepping interrupt's, which other interrupts may delay:
the low time and the DIR hold have no bound below (``uncertain``: never a PASS); I2S clocks its
samples out of a FIFO. The max step rate of an axis is ``steps_per_mm × max_rate_mm_per_min / 60``;
its steps are at least 1 / min(2 × that, the fastest axis's) apart (grbl's Bresenham, kept by
FluidNC's ``Stepper.cpp``: :func:`wavecheck.firmware.grbl.bresenham_spacing`).
"""

from __future__ import annotations

import os
import re
from collections.abc import Iterator
from dataclasses import dataclass
from fractions import Fraction

import yaml

from wavecheck.errors import ConfigError
from wavecheck.firmware._text import number, read_text, where
from wavecheck.firmware.grbl import bresenham_spacing
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

__all__ = ["ENGINES", "looks_like", "read"]

#: FluidNC's stepping engines, as ``stepping: engine:`` names them (case-insensitive).
ENGINES = ("RMT", "TIMED", "I2S_STATIC", "I2S_STREAM")
_US = Fraction(1000)
_RMT_TICK_NS = Fraction(250)  # RMT clock 4 ticks/us: a dir_delay of 0 is one tick
_FRAMES_US = (1, 2, 4)  # i2so min_pulse_us values (I2SOBus pulseUsValues)
_I2S_MAX_PULSE_NS = Fraction(20) * _US  # i2s_out.h I2S_MAX_USEC_PER_PULSE
_NO_SPACE = re.compile(r"^([ \t]*[A-Za-z0-9_]+)[ \t]*:(?=[^\s])", re.M)
_AXES = "xyzabcuvw"


#: Top-level sections only FluidNC machine files have (a file with two of them is FluidNC's,
#: whether or not it has motors).
_TOP = re.compile(
    r"^(stepping|axes|i2so|kinematics|coolant|probe|control|macros|user_outputs|sdcard|spi)"
    r"[ \t]*:[ \t\r]*(?:#.*)?$",
    re.M,
)


def looks_like(text: str) -> bool:
    """A FluidNC machine file: YAML with a top-level ``axes:`` mapping holding axis mappings
    (``  x:``) or two of FluidNC's top-level sections, no ``[section]`` headers (Klipper's
    ``axes: z`` is a value, not a mapping)."""
    if re.search(r"^\[[^\]\n]+\][ \t\r]*$", text, re.M):
        return False
    found = set(_TOP.findall(text))
    return len(found) >= 2 or (
        "axes" in found and bool(re.search(r"^[ \t]+[xyzabc][ \t]*:[ \t\r]*(#.*)?$", text, re.M))
    )


@dataclass(frozen=True)
class _Value:
    text: str
    line: int


def _compose(path: str, text: str) -> yaml.Node:
    try:
        node = yaml.compose(_NO_SPACE.sub(r"\1: ", text), Loader=yaml.CSafeLoader)
    except yaml.MarkedYAMLError as err:
        mark = err.problem_mark or err.context_mark
        line = f":{mark.line + 1}" if mark is not None else ""
        raise ConfigError(f"{path}{line}: not YAML FluidNC reads: {err.problem}") from None
    except (yaml.YAMLError, RecursionError) as err:
        raise ConfigError(f"{path}: not YAML FluidNC reads ({type(err).__name__})") from None
    if not isinstance(node, yaml.MappingNode):
        raise ConfigError(f"{path}: not a FluidNC machine file (no top-level settings)")
    return node


def _drop_flow(node: yaml.Node, found: list[int]) -> yaml.Node:
    """``node`` with every flow collection (``key: { a: 1 }``) made the one string value FluidNC
    sees: its tokenizer reads a line's key and the rest of the line as the value
    (Configuration/Tokenizer.cpp), and a section reads only the more-indented lines below it
    (ParserHandler::enterSection), so the settings inside the braces are never read. ``found``
    gets the line of each."""
    if isinstance(node, yaml.CollectionNode) and node.flow_style:
        found.append(node.start_mark.line + 1)
        return yaml.ScalarNode("tag:yaml.org,2002:str", "{...}", node.start_mark, node.end_mark)
    if isinstance(node, yaml.MappingNode):
        node.value = [(k, _drop_flow(v, found)) for k, v in node.value]
    return node


def _items(node: yaml.Node | None) -> Iterator[tuple[str, yaml.Node]]:
    if isinstance(node, yaml.MappingNode):
        for key, value in node.value:
            if isinstance(key, yaml.ScalarNode):
                yield str(key.value).strip().lower(), value


def _child(node: yaml.Node | None, key: str) -> yaml.Node | None:
    """The section ``key`` of ``node``: the first one when it is repeated."""
    return next((v for k, v in _items(node) if k == key), None)


def _scalar(node: yaml.Node | None, key: str) -> _Value | None:
    """The value of ``key``: the last one when it is repeated (FluidNC's parser assigns each
    ``key: value`` line as it reads it, so a later line overwrites an earlier one)."""
    found = [v for k, v in _items(node) if k == key and isinstance(v, yaml.ScalarNode)]
    if found:
        return _Value(str(found[-1].value).strip(), found[-1].start_mark.line + 1)
    return None


def _us(path: str, node: yaml.Node | None, key: str, default: int, high: int) -> Guaranteed:
    """A whole-µs setting of ``node`` as ns (FluidNC stores these as integers)."""
    found = _scalar(node, key)
    if found is None:
        return Guaranteed(Fraction(default) * _US, key, "firmware default", "us", "default")
    at = where(path, found.line)
    value = number(found.text, at, key, low=0, high=high, unit="us")
    return Guaranteed(Fraction(int(value)) * _US, key, at, "us", "set")


def read(path: str | os.PathLike[str]) -> FirmwareConfig:
    """Read a FluidNC ``config.yaml`` (see the module doc)."""
    p = str(path)
    flows: list[int] = []
    root = _drop_flow(_compose(p, read_text(path)), flows)
    stepping = _child(root, "stepping")
    engine_v = _scalar(stepping, "engine")
    engine = engine_v.text.upper() if engine_v else "RMT"
    if engine not in ENGINES:
        raise ConfigError(
            f"{where(p, engine_v.line) if engine_v else p}: stepping engine {engine_v and engine_v.text!r}"
            f" is not one of {', '.join(ENGINES)}"
        )
    engine_at = where(p, engine_v.line) if engine_v else "firmware default"
    pulse = _us(p, stepping, "pulse_us", 4, 30)
    dir_delay = _us(p, stepping, "dir_delay_us", 0, 10)
    notes = [
        f"stepping engine {engine} ({engine_at}); pulse_us and dir_delay_us apply to every motor"
    ]
    if flows:
        notes.append(
            f"{where(p, flows[0])}: {len(flows)} YAML flow mapping(s) {{...}}: FluidNC reads such "
            "a line as one value and leaves the section empty (Tokenizer.cpp, "
            "ParserHandler::enterSection): their settings are not read; write one key per line"
        )
    frame = _frame(p, root) if engine.startswith("I2S") else None
    if frame is not None and frame.value is not None:
        notes.append(f"I2S frame {frame.value / _US} us (i2so: min_pulse_us, {frame.where})")
    pulse = _engine_pulse(engine, pulse, frame)
    setup = _setup(engine, dir_delay, frame)
    engine_max = _engine_rate(engine, pulse, dir_delay)
    axes_node = _child(root, "axes")
    axes: list[GeneratorGuarantee] = []
    seen: set[str] = set()
    fastest = _fastest(p, axes_node)
    for name, axis_node in _items(axes_node):
        if name not in _AXES or name in seen:
            continue  # a repeated axis section: the first is read
        seen.add(name)
        for motor in ("motor0", "motor1"):
            driver = _driver(_child(axis_node, motor))
            if driver is None:
                continue
            kind, drv = driver
            axes.append(
                _axis(
                    p, name, motor, kind, drv, axis_node, pulse, setup, engine_max, engine, fastest
                )  # fmt: skip
            )
    if not axes:
        why = (
            f"; {len(flows)} YAML flow mapping(s) {{...}} (first at line {flows[0]}) are not read "
            "by FluidNC's parser: write one key per line"
            if flows
            else ""
        )
        raise ConfigError(
            f"{p}: no axis has a motor with a step_pin (no step generator to check){why}"
        )
    return FirmwareConfig(
        firmware="fluidnc",
        path=p,
        axes=tuple(axes),
        files=(p,),
        notes=tuple(notes),
        fixer=_fix,
    )


def _frame(path: str, root: yaml.Node) -> Guaranteed:
    """The I2S frame: ``i2so: min_pulse_us``, one of 1, 2, 4 µs (FluidNC's ``I2SOBus``
    ``pulseUsValues``), default 2."""
    found = _scalar(_child(root, "i2so"), "min_pulse_us")
    if found is None:
        return Guaranteed(2 * _US, "min_pulse_us", "firmware default", "us", "default")
    at = where(path, found.line)
    value = number(found.text, at, "min_pulse_us", low=1, high=4, unit="us")
    if value not in _FRAMES_US:
        raise ConfigError(
            f"{at}: i2so min_pulse_us {found.text} is not one FluidNC takes (1, 2 or 4)"
        )
    return Guaranteed(value * _US, "min_pulse_us", at, "us", "set")


def _engine_pulse(engine: str, pulse: Guaranteed, frame: Guaranteed | None) -> Guaranteed:
    """The pulse as the engine makes it."""
    if engine == "RMT":
        return Guaranteed(pulse.value, pulse.setting, pulse.where, "us", pulse.status,
                          "RMT: hardware-timed")  # fmt: skip
    if frame is not None and frame.value is not None and pulse.value is not None:
        asked = min(max(pulse.value, frame.value), _I2S_MAX_PULSE_NS)
        frames = -(-asked // frame.value)
        note = (
            f"I2S: {frames} FIFO frame(s) of {frame.value / _US} us (pulse_us rounded up to "
            "whole frames, at least one, at most 20 us: i2s_engine.cpp init_engine)"
        )
        return Guaranteed(frames * frame.value, pulse.setting, pulse.where, "us", "derived", note)
    # FluidNC/esp32/timed_engine.c:41-46 @ 763a648: finish_step takes the end time from the CPU
    # cycle counter after the STEP write, start_unstep spins until it (spinUntil): the pulse is
    # at least pulse_us, so the set value is the lower bound
    note = ("TIMED: the CPU spins pulse_us from a cycle count taken after the STEP write "
            "(timed_engine.c:41-46); interrupts only lengthen it")  # fmt: skip
    return Guaranteed(pulse.value, pulse.setting, pulse.where, "us", pulse.status, note)


def _setup(engine: str, dir_delay: Guaranteed, frame: Guaranteed | None) -> Guaranteed:
    dd = dir_delay.value or Fraction(0)
    if engine == "RMT":
        value = dd if dd else _RMT_TICK_NS
        note = "RMT: every pulse starts with dir_delay_us at the idle level (one 0.25 us tick at 0)"
        return Guaranteed(value, dir_delay.setting, dir_delay.where, "us", "set", note)
    if frame is not None:
        note = (
            "I2S: a DIR change is one FIFO frame ahead of the step (i2s_engine.cpp finish_dir); "
            f"the dir_delay_us spin after it ({float(dd / _US):g} us) widens the gap only when "
            "the FIFO has run dry, so one frame is what the engine guarantees"
        )
        return Guaranteed(frame.value, frame.setting, frame.where, "us", "derived", note)
    if not dd:  # timed_engine.c finish_dir: delay_us(0), the next GPIO write is the step
        return not_enforced(
            dir_delay.setting,
            "TIMED with dir_delay_us 0: the CPU writes DIR and then STEP with no wait between "
            "(timed_engine.c finish_dir spins dir_delay_us), so the setup is instruction time",
            dir_delay.where,
        )
    # timed_engine.c:31-33: finish_dir spins delay_us(dir_delay_us) after the DIR writes, a
    # cycle-counted wait (spinUntil(usToEndTicks(us))): at least the set value
    note = "TIMED: the CPU spins dir_delay_us after a DIR change (timed_engine.c:31-33)"
    return Guaranteed(dd, dir_delay.setting, dir_delay.where, "us", dir_delay.status, note)


def _engine_rate(engine: str, pulse: Guaranteed, dir_delay: Guaranteed) -> Fraction | None:
    p, dd = pulse.value or Fraction(0), dir_delay.value or Fraction(0)
    if engine == "RMT":
        return Fraction(10**9) / (2 * p + dd) if 2 * p + dd else None
    return Fraction(10**9) / (2 * p) if p else None


def _fastest(path: str, axes_node: yaml.Node | None) -> Fraction | None:
    """The highest max step rate of the axes with a motor (None when one has no rate)."""
    rates = []
    seen: set[str] = set()
    for name, axis_node in _items(axes_node):
        if name not in _AXES or name in seen:
            continue
        seen.add(name)
        if all(_driver(_child(axis_node, m)) is None for m in ("motor0", "motor1")):
            continue
        spm_v = _scalar(axis_node, "steps_per_mm")
        rate_v = _scalar(axis_node, "max_rate_mm_per_min")
        if spm_v is None or rate_v is None:
            return None
        spm = number(spm_v.text, where(path, spm_v.line), "steps_per_mm", low=0)
        mm_min = number(rate_v.text, where(path, rate_v.line), "max_rate_mm_per_min", low=0)
        rates.append(spm * mm_min / 60)
    return max(rates) if rates else None


def _driver(motor: yaml.Node | None) -> tuple[str, yaml.Node] | None:
    """The motor's driver section with a step pin (``NO_PIN`` is none: no step generator)."""
    for kind, node in _items(motor):
        pin = _scalar(node, "step_pin")
        if pin is not None and pin.text.strip().lower() not in ("no_pin", ""):
            return kind, node
    return None


def _pin(value: _Value | None) -> tuple[str, bool]:
    """(pin, inverted) of ``gpio.26:low`` style pin text."""
    if value is None:
        return "", False
    parts = [s.strip().lower() for s in value.text.split(":")]
    return parts[0], "low" in parts[1:]


def _axis(
    path: str,
    name: str,
    motor: str,
    kind: str,
    drv: yaml.Node,
    axis_node: yaml.Node,
    pulse: Guaranteed,
    setup: Guaranteed,
    engine_max: Fraction | None,
    engine: str,
    fastest: Fraction | None,
) -> GeneratorGuarantee:
    step_pin, step_low = _pin(_scalar(drv, "step_pin"))
    _, dir_low = _pin(_scalar(drv, "direction_pin"))
    info = {
        "driver": f"{kind} ({motor}, step_pin {step_pin})",
        "engine": engine,
    }
    spm_v = _scalar(axis_node, "steps_per_mm")
    rate_v = _scalar(axis_node, "max_rate_mm_per_min")
    max_rate = Guaranteed(None, "max_rate_mm_per_min", "", "mm/min", "unknown", "not set")
    idle: Guaranteed = unknown("max_rate_mm_per_min", "no steps_per_mm or max rate for this axis")
    if spm_v and rate_v:
        spm_at, rate_at = where(path, spm_v.line), where(path, rate_v.line)
        spm = number(spm_v.text, spm_at, "steps_per_mm", low=0)
        mm_min = number(rate_v.text, rate_at, "max_rate_mm_per_min", low=0)
        info["steps/mm"] = f"{spm_v.text} (steps_per_mm, {spm_at})"
        info["max rate"] = f"{rate_v.text} mm/min (max_rate_mm_per_min, {rate_at})"
        hz = spm * mm_min / 60
        note = f"{name}: steps_per_mm x max_rate_mm_per_min / 60"
        if engine_max is not None:
            note += f"; the {engine} engine makes at most {float(engine_max):.6g} steps/s"
        max_rate = Guaranteed(hz, "steps_per_mm x max_rate_mm_per_min / 60", rate_at,
                              "mm/min", "derived", note)  # fmt: skip
        if hz > 0 and pulse.value is not None and fastest:
            gap = bresenham_spacing(hz, fastest) - pulse.value
            spacing = ("1 / min(2 x this axis's max rate, the fastest axis's) - pulse: FluidNC's "
                       "Stepper.cpp keeps grbl's Bresenham, which puts the steps on the dominant "
                       "axis's ticks")  # fmt: skip
            if engine in ("RMT", "TIMED"):
                idle = uncertain(max(gap, Fraction(0)), "max_rate_mm_per_min", rate_at,
                                 "mm/min", None, _ISR_JITTER[engine], spacing)  # fmt: skip
            else:  # I2S: the steps are samples of a FIFO clocked out by the I2S hardware
                idle = Guaranteed(max(gap, Fraction(0)), "max_rate_mm_per_min", rate_at,
                                  "mm/min", "derived", spacing)  # fmt: skip
    hold_note = "DIR changes at a later step event: at least one pulse after the leading edge"
    return GeneratorGuarantee(
        axis=name if motor == "motor0" else f"{name}.{motor}",
        pulse=pulse,
        idle=idle,
        dir_setup=setup,
        dir_hold=(
            uncertain(
                pulse.value, "pulse_us", pulse.where, "us", None, _ISR_JITTER[engine], hold_note
            )  # fmt: skip
            if engine in ("RMT", "TIMED")
            else Guaranteed(pulse.value, "pulse_us", pulse.where, "us", "derived", hold_note)
        ),
        max_rate=max_rate,
        pulse_level=0 if step_low else 1,
        dir_hold_trailing=Guaranteed(
            Fraction(0),
            "pulse_us",
            pulse.where,
            "us",
            "derived",  # 0: no figure can fall below it
            "DIR may change right after the pulse ends",
        ),  # fmt: skip
        dir_inverted=dir_low,
        info=info,
        aliases=(f"{name}.motor0",) if motor == "motor0" else (),
    )


#: Why the times between step events have no bound under the RMT and TIMED engines: each step
#: (RMT: its transmission started, TIMED: the pin written) and each DIR write happens when the
#: stepping timer's interrupt runs, which other interrupts may delay by an amount no source
#: bounds, so two events may come closer than their ticks; TIMED's pulse spin
#: (timed_engine.c:45-46) is also lengthened by an interrupt, which the low time then loses.
_ISR_JITTER = {
    "RMT": "the stepping interrupt starts each RMT pulse and writes DIR, and other interrupts may "
    "delay it by an amount no source bounds",
    "TIMED": "the stepping interrupt writes STEP and DIR, and other interrupts may delay it, or "
    "lengthen the pulse's spin (timed_engine.c:45-46), by an amount no source bounds",
}


def _fix(axis: GeneratorGuarantee, role: FixRole, need: Fraction) -> str:
    engine = axis.info.get("engine", "RMT").split(" ")[0]
    i2s = engine.startswith("I2S")
    if role == "setup" and i2s:
        frame = next((f for f in _FRAMES_US if f * _US >= need), None)
        if frame is None:
            return (
                f"FluidNC's I2S engine tops out at one {_FRAMES_US[-1]} us frame of DIR setup: "
                f"this drive needs {float(need / _US):g} us (the RMT or TIMED engine spins "
                "dir_delay_us)"
            )
        return f"set `i2so: min_pulse_us: {frame}` (the I2S frame: 1, 2 or 4 us)"
    if role in ("pulse", "hold", "setup"):
        key, top = ("dir_delay_us", 10) if role == "setup" else ("pulse_us", 20 if i2s else 30)
        us: Fraction = max(Fraction(-(-need // _US)), Fraction(1 if role != "setup" else 0))
        if us > top:
            return (
                f"FluidNC tops out at {key} {top} us with the {engine} engine: this drive needs "
                f"{float(us):g} us"
            )
        return f"set `stepping: {key}: {us}` (whole us, at most {top})"
    if role == "trailing_hold":
        return (
            "FluidNC may change DIR right after the pulse ends: invert the step pin (add or "
            f"remove `:low`) of {axis.axis} so that the drive's active edge starts the pulse"
        )
    if role == "idle" and axis.pulse.value is not None:
        # twice this axis's rate under 1 / (pulse + low): no dominant axis can crowd its steps
        need = Fraction(10**9) / (axis.pulse.value + need) / 2
    spm = axis.info.get("steps/mm", "").split(" ")[0]
    if spm:
        return (
            f"set `{axis.axis.split('.')[0]}: max_rate_mm_per_min: "
            f"{at_most(need * 60 / Fraction(spm))}`"
        )
    return f"lower `{axis.axis.split('.')[0]}: max_rate_mm_per_min`"
