"""LinuxCNC's software stepgen: the channels a configuration loads (``loadrt stepgen``), read by
:mod:`wavecheck.linuxcnc.stepgen_config`, with the n·P − J arithmetic of :mod:`wavecheck.linuxcnc.timing`.

Line numbers are LinuxCNC's ``src/hal/components/stepgen.c`` at git f1270d6ed7 (Debian's
2.9.0~pre1; the algorithm is unchanged since 2007). Each timing parameter defaults to 1 ns
(1149-1161) and is rounded up to whole base periods ``P`` (``ulceil``, 757-763, applied at
833-860; steplen 0 becomes 1, and dirhold 1 when dirhold + dirsetup is 0). Any base-thread run may
be up to ``J`` (the worst latency) late, so an interval of ``n`` periods is only ``n·P − J`` on
the wire (``J`` = 0 when not given, with a note). A step starts timer1 = steplen, timer2 =
timer1 + dirhold and timer3 = timer2 + dirsetup (651-658); DIR changes only when timer2 has run
out (643-649): LinuxCNC's dirhold counts from the end of the pulse, so the hold from the leading
edge is steplen + dirhold. A reversal holds the DDS until timer3 has run out (617-625), so across
a reversal the space between pulses is only dirhold + dirsetup periods. DIR setup is what
``dirsetup`` asks for, not a bound stepgen keeps: when the velocity changes sign after timer3 has
run out, DIR and the next step can change in the same period (LinuxCNC issue #2332): a rule that
passes on it is indeterminate, one that fails still fails. The rate is clamped to 1 / (steplen +
stepspace) and, when ``maxvel`` > 0, to maxvel × |position-scale| (876-902).

What a parallel-port pin does to the output (inversion, hal_parport's reset, sim_parport) is
:mod:`wavecheck.linuxcnc.parport`.
"""

from __future__ import annotations

from collections.abc import Callable
from fractions import Fraction

from wavecheck.errors import ConfigError
from wavecheck.firmware.guarantee import (
    FixRole,
    GeneratorGuarantee,
    Guaranteed,
    at_most,
    not_enforced,
    unknown,
)
from wavecheck.linuxcnc.configuration import LinuxCNCFiles
from wavecheck.linuxcnc.parport import PinOut, pin_out
from wavecheck.linuxcnc.stepgen_config import LinuxCNCConfig, read_config_lines
from wavecheck.linuxcnc.timing import periods_needed, step_rate_hz

__all__ = ["PARAMETER", "axes", "fixer", "maxvel_fix"]

_MAX_CHANNELS = 16


def axes(files: LinuxCNCFiles, latency_ns: Fraction | None) -> list[GeneratorGuarantee]:
    """One guarantee per software stepgen channel (empty when stepgen is not loaded)."""
    configs: list[LinuxCNCConfig] = []
    for channel in range(_MAX_CHANNELS):
        try:
            cfg = read_config_lines(files.ini, files.lines, channel)
        except ConfigError as err:
            if configs and "is not loaded" in str(err):
                break
            raise
        if not cfg.stepgen_loaded:
            return []
        configs.append(cfg)
    j = Fraction(latency_ns) if latency_ns is not None else Fraction(0)
    return [_axis(files, cfg, j) for cfg in configs]


def _axis(files: LinuxCNCFiles, cfg: LinuxCNCConfig, j: Fraction) -> GeneratorGuarantee:
    if cfg.base_period_ns is None:
        place = cfg.sources.get("step_type", files.path)
        raise ConfigError(
            f"{place}: stepgen is loaded but no base period is known: no [EMCMOT] BASE_PERIOD, "
            "and stepgen.make-pulses runs in no thread with a period"
        )
    p = cfg.require_base_period()
    n = cfg.periods()
    src = cfg.sources

    def fig(
        names: tuple[str, ...], setting: str, note: str = "", minus: Fraction = Fraction(0)
    ) -> Guaranteed:
        periods = sum(n[x] for x in names)
        value = max(periods * p - j - minus, Fraction(0))
        at = src.get(names[-1], "stepgen default (1 ns = one period)")
        extra = f" - {float(minus):g} ns" if minus else ""
        return Guaranteed(value, setting, at, "ns", "derived",
                          f"{periods} x {p} ns{extra} - J" + (f"; {note}" if note else ""))  # fmt: skip

    step = pin_out(files, f"stepgen.{cfg.channel}.step", p)
    dirp = pin_out(files, f"stepgen.{cfg.channel}.dir", p)
    notes: list[str] = []
    if cfg.step_type not in (None, 0):
        notes.append(f"step_type {cfg.step_type}: only step/dir (0) is modelled here")
    if step.pin:
        notes.append(f"STEP drives {step.pin}" + (" (inverted)" if step.inverted else ""))
    if step.simulated:
        notes.append(f"{step.pin}-reset is set, but the port is sim_parport, whose reset function "
                     "does nothing (sim_parport.comp:28): the pulse is steplen")  # fmt: skip
    if step.reset_ns is not None or step.reset_unknown:
        pulse, idle, hold, trailing, rate = _reset(cfg, step, p, n, j, notes)
    else:
        same = n["stepspace"]
        reversal = n["dirhold"] + n["dirsetup"]
        idle = (
            fig(("stepspace",), "stepspace")
            if same <= reversal
            else fig(("dirhold", "dirsetup"), "dirhold + dirsetup", "across a reversal")
        )
        pulse = fig(("steplen",), "steplen")
        hold = fig(("steplen", "dirhold"), "steplen + dirhold",
                   "dirhold counts from the end of the pulse")  # fmt: skip
        trailing = fig(("dirhold",), "dirhold")
        rate = Guaranteed(step_rate_hz(p, n["steplen"] + n["stepspace"]),
                          "1 / ((steplen + stepspace) x P)",
                          src.get("stepspace", src.get("BASE_PERIOD", "")), "ns", "derived",
                          "stepgen's own clamp")  # fmt: skip
        if n["stepspace"] == 0:
            notes.append("stepspace 0 without the parport reset function: STEP stays high at the "
                         "top rate")  # fmt: skip
    rate = _maxvel_clamp(files, cfg, rate)
    info = {
        "base period": f"{p} ns ({src.get('BASE_PERIOD', '')})",
        **{k: f"{v} base periods" for k, v in n.items()},
    }
    if cfg.floats.get("position-scale"):
        info["position-scale"] = f"{cfg.floats['position-scale']!r} steps/unit"
    if step.pin:
        info["reset"] = ".".join(step.pin.split(".")[:2])
    joint, letter = files.joint_of(f"stepgen.{cfg.channel}")
    aliases = tuple(a for a in (f"joint.{joint}" if joint is not None else "", letter) if a)
    return GeneratorGuarantee(
        axis=f"stepgen.{cfg.channel}",
        pulse=pulse,
        idle=idle,
        dir_setup=_collapsible(fig(("dirsetup",), "dirsetup")),
        dir_hold=hold,
        max_rate=rate,
        pulse_level=0 if step.inverted else 1,
        dir_hold_trailing=trailing,
        dir_inverted=dirp.inverted,
        info=info,
        notes=tuple(notes),
        aliases=aliases,
    )


def _maxvel_clamp(files: LinuxCNCFiles, cfg: LinuxCNCConfig, rate: Guaranteed) -> Guaranteed:
    """``rate``, or ``maxvel x |position-scale|`` when ``setp stepgen.N.maxvel`` is lower
    (stepgen.c clamps the commanded velocity to maxvel when it is > 0)."""
    maxvel, scale = cfg.floats.get("maxvel"), cfg.floats.get("position-scale")
    if not maxvel or maxvel <= 0 or not scale:
        return rate
    hz = Fraction(repr(maxvel)) * abs(Fraction(repr(scale)))
    if rate.value is not None and hz >= rate.value:
        return rate
    at = files.setp.get(f"stepgen.{cfg.channel}.maxvel", ("", ""))[1]
    return Guaranteed(hz, "maxvel x |position-scale|", at, "units/s", "derived",
                      f"stepgen clamps the velocity to maxvel {maxvel:g} units/s "
                      f"(position-scale {scale:g} steps/unit)")  # fmt: skip


#: LinuxCNC issue #2332 (open): stepgen.c can start a step sooner than dirsetup after a DIR change.
DIRSETUP_COLLAPSE = (
    "the software stepgen can fail to obey dirsetup (LinuxCNC issue #2332: a step follows a DIR "
    "change sooner than dirsetup)"
)


def _collapsible(setup: Guaranteed) -> Guaranteed:
    """The configured DIR setup as what stepgen aims at, not a bound it keeps (issue #2332)."""
    return not_enforced(setup.setting, f"{DIRSETUP_COLLAPSE}; configured {setup.note}",
                        setup.where, setup.value, setup.unit)  # fmt: skip


def _reset(
    cfg: LinuxCNCConfig, step: PinOut, p: int, n: dict[str, int], j: Fraction, notes: list[str]
) -> tuple[Guaranteed, Guaranteed, Guaranteed, Guaranteed, Guaranteed]:
    """Pulse, idle, DIR hold (leading, trailing) and rate on a parport pin with ``reset``."""
    src = cfg.sources
    if step.reset_ns is None:
        pulse = unknown("reset-time", f"{step.reset_unknown}: the pulse on {step.pin} is not known")
    else:
        pulse = Guaranteed(step.reset_ns, "parport reset-time", step.reset_where, "ns", "derived",
                           f"the reset function lowers {step.pin} reset-time after the write "
                           f"(clamped to P/4 = {p // 4} ns)")  # fmt: skip
    width = pulse.value or Fraction(0)
    # a step starts at most every steplen + stepspace periods; with steplen > 1 the pin is set
    # again each period of the step, so pulses are one period apart
    apart = n["steplen"] + n["stepspace"] if n["steplen"] <= 1 else 1
    idle = Guaranteed(max(max(apart, 1) * p - width - j, Fraction(0)),
                      "(steplen + stepspace) x BASE_PERIOD - reset-time",
                      src.get("stepspace", src.get("BASE_PERIOD", "")), "ns", "derived",
                      "the pin is written once per step and reset within the period: the rest "
                      "until the next step is idle, less J")  # fmt: skip
    lead = n["steplen"] + n["dirhold"]
    hold = Guaranteed(max(lead * p - j, Fraction(0)), "steplen + dirhold", src.get("dirhold", ""),
                      "ns", "derived", f"{lead} x {p} ns - J from the write that starts the pulse")  # fmt: skip
    trailing = Guaranteed(max(lead * p - width - j, Fraction(0)), "steplen + dirhold - reset-time",
                          src.get("dirhold", ""), "ns", "derived", "from the reset that ends the pulse")  # fmt: skip
    per_step = n["steplen"] + n["stepspace"]
    rate = Guaranteed(step_rate_hz(p, per_step), "1 / ((steplen + stepspace) x P)",
                      src.get("stepspace", src.get("BASE_PERIOD", "")), "ns", "derived",
                      "stepgen's own clamp; the reset pin makes one pulse per period")  # fmt: skip
    notes.append(f"{step.pin} is reset each period (parport reset): the pulse is the reset time")
    if n["steplen"] > 1:
        notes.append(f"steplen is {n['steplen']} periods with the reset function: each step makes "
                     f"{n['steplen']} pulses on {step.pin} (StepConf sets steplen 1)")  # fmt: skip
    return pulse, idle, hold, trailing, rate


#: The stepgen parameter that makes each figure (the software stepgen's and hm2's alike).
PARAMETER: dict[str, str] = {"pulse": "steplen", "idle": "stepspace", "setup": "dirsetup",
                             "hold": "dirhold", "trailing_hold": "dirhold"}  # fmt: skip


def maxvel_fix(gen: str, axis: GeneratorGuarantee, need: Fraction, why: str = "") -> str:
    """The ``setp GEN.maxvel`` line that lowers the step rate to ``need`` (both stepgens clamp
    the velocity to maxvel; stepgen.c 884-902), "" when the position-scale is not known."""
    scale = axis.info.get("position-scale", "").split(" ")[0]
    if not scale or not Fraction(scale):
        return ""
    return f"add `setp {gen}.maxvel {at_most(need / abs(Fraction(scale)))}` (units/s{why})"


def fixer(j: Fraction) -> Callable[[GeneratorGuarantee, FixRole, Fraction], str]:
    """How to say which stepgen setting to change, at latency ``j``: a ``setp`` line to add
    after the configuration's own (the last ``setp`` of a parameter wins)."""

    def fix(axis: GeneratorGuarantee, role: FixRole, need: Fraction) -> str:
        p = int(axis.info.get("base period", "0 ns").split(" ")[0])
        name = PARAMETER.get(role)
        if p <= 0:
            return ""
        if name is None:  # the rate: maxvel clamps it (stepgen.c), else steplen + stepspace
            clamp = maxvel_fix(axis.axis, axis, need, "; stepgen clamps to it")
            if clamp:
                return clamp
            steplen = int(axis.info.get("steplen", "0").split(" ")[0])
            periods = max(-(-Fraction(10**9) // (need * p)) - steplen, 1)
            return f"add `setp {axis.axis}.stepspace {periods * p}` ({periods} base periods)"
        if role == "pulse" and axis.pulse.setting == "parport reset-time":
            value = int(-(-need // 1))
            if value > p // 4:
                return (
                    f"the parport reset pulse is at most P/4 = {p // 4} ns: raise BASE_PERIOD to "
                    f"at least {4 * value} ns"
                )
            return f"add `setp {axis.info.get('reset', 'parport.0')}.reset-time {value}` (ns)"
        if role == "hold":
            need -= int(axis.info.get("steplen", "0").split(" ")[0]) * p
        if role == "idle" and axis.pulse.setting == "parport reset-time":
            # (1 + stepspace) periods - reset-time - J (steplen 1, as StepConf sets it)
            space = periods_needed(need + (axis.pulse.value or 0), j, p) - 1
            return f"add `setp {axis.axis}.stepspace {space * p}` ({space} base periods of {p} ns)"
        periods = periods_needed(max(need, Fraction(0)), j, p)
        at_j = f"({periods} base periods of {p} ns at J = {float(j):g} ns)"
        if role == "idle":  # across a reversal the space is dirhold + dirsetup
            n = {k: int(axis.info.get(k, "0").split(" ")[0]) for k in ("dirhold", "dirsetup")}
            if n["dirhold"] + n["dirsetup"] < periods:
                hold = (periods - n["dirsetup"]) * p
                return (
                    f"add `setp {axis.axis}.stepspace {periods * p}` and "
                    f"`setp {axis.axis}.dirhold {hold}` {at_j}: across a reversal the space is "
                    "dirhold + dirsetup"
                )
        return f"add `setp {axis.axis}.{name} {periods * p}` {at_j}"

    return fix
