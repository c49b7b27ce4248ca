"""LinuxCNC's own configuration files: the stepgen settings of one channel, from INI and HAL.

- INI (``--ini FILE``): ``[EMCMOT] BASE_PERIOD`` and ``SERVO_PERIOD`` (ns), and any value a HAL
  file refers to as ``[SECTION]KEY``.
- HAL (``--hal FILE``, repeatable): ``loadrt stepgen step_type=0,0,1 ctrl_type=p,p,v
  user_step_type=…`` and ``setp stepgen.N.steplen 5000`` (also ``stepgen.N.steplen = 5000``);
  values may be ``[SECTION]KEY`` references into the INI. stepgen's timing parameters are ns.
- The threads a HAL file makes and what runs in them: ``loadrt threads name1=fast period1=100000
  …`` (up to three threads) and ``loadrt motmod base_period_nsec=… servo_period_nsec=…`` (the
  ``base-thread`` and ``servo-thread``) give thread periods; ``addf FUNCT THREAD [POSITION]``
  places functions. The period of the thread ``stepgen.make-pulses`` is added to is the base
  period and that of ``stepgen.update-freq``'s thread the servo period (they win over the INI's
  BASE_PERIOD/SERVO_PERIOD, which only reach stepgen through motmod); with both in one thread
  their ``addf`` order is :attr:`LinuxCNCConfig.thread_order` (reference §3, §8).
- ``setp stepgen.N.position-cmd X`` / ``velocity-cmd V`` (a constant command) and
  ``setp stepgen.N.enable 0|1``.

What a file says that a model of one stepgen channel cannot honour (a ``net`` driving the
command or ``enable`` pin, an unknown ``stepgen.N.*`` name) is listed in
:attr:`LinuxCNCConfig.ignored`, one line each naming the file and line.

The joint's ``pid`` settings: :mod:`wavecheck.linuxcnc.pid_settings`; INI and HAL syntax:
:mod:`wavecheck.linuxcnc.files`.

One parser serves ``wavecheck check`` (the ``config`` and ``latency_safe`` max step rates) and
``stepgen simulate`` (:meth:`LinuxCNCConfig.stepgen_kwargs`). Every value remembers the file
and line it came from, and errors name them (:class:`~wavecheck.errors.ConfigError`).

Rates (Hz, exact):

- ``config`` = 1 / ((steplen + stepspace) · P), each parameter rounded up to whole base periods as
  stepgen does (steplen at least one period) — stepgen's own frequency clamp.
- ``latency_safe`` (needs the worst latency ``J``): the highest rate at which every interval
  stepgen makes, each only ``n·P − J`` long in the worst case, still meets the drive. The
  intervals that do not depend on the rate (the pulse, DIR setup/hold, the gaps across a
  reversal) must meet it as set, else no rate is safe (None); the space between pulses and the
  step period grow as the rate falls, so the rate is 1 / (N·P) with N the fewest periods per
  step that give both. Requirements and ``n = ceil((T + J)/P)`` come from :mod:`wavecheck.linuxcnc.timing`.
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from dataclasses import dataclass, field
from fractions import Fraction
from typing import Any

from wavecheck.drives.datasheet import Drive
from wavecheck.errors import ConfigError
from wavecheck.linuxcnc.files import (
    HalLine,
    IniFile,
    hal_lines,
    hal_words,
    ini_value,
    int_ns,
    loadrt_args,
    read_ini,
    resolve_ref,
)
from wavecheck.linuxcnc.timing import evaluate, periods_needed, step_rate_hz
from wavecheck.steptypes import kind_of

__all__ = [
    "TIMING_PARAMS",
    "ConfigRates",
    "LinuxCNCConfig",
    "config_rates",
    "read_config",
    "read_config_lines",
]

#: stepgen's timing parameters (ns, u32), in LinuxCNC's order.
TIMING_PARAMS = ("steplen", "stepspace", "dirsetup", "dirhold", "dirdelay")
_FLOAT_PARAMS = ("position-scale", "maxvel", "maxaccel")


@dataclass
class LinuxCNCConfig:
    """The stepgen settings of one channel, with where each came from.

    Attributes:
        channel: the stepgen channel (``stepgen.N``).
        base_period_ns: BASE_PERIOD (ns), None if no INI gave it.
        servo_period_ns: SERVO_PERIOD (ns), None if no INI gave it.
        step_type: this channel's ``step_type=`` entry, None if no ``loadrt stepgen``.
        ctrl_type: ``"position"`` or ``"velocity"`` (``ctrl_type=`` p/v), None if not given.
        user_step_type: the ``user_step_type=`` table (type 15).
        params: ``setp stepgen.N.<param>`` timing values in ns (steplen, stepspace, …).
        floats: ``position-scale``, ``maxvel``, ``maxaccel`` when set.
        sources: setting → ``"file:line"``.
        threads: HAL thread name → period (ns), from ``loadrt threads`` / ``loadrt motmod``.
        functions: HAL thread name → its functions in run order (``addf``).
        thread_order: ``"update-first"`` or ``"pulses-first"`` when ``stepgen.update-freq``
            and ``stepgen.make-pulses`` run in one thread (their ``addf`` order), else None.
        command: ``("position", X)`` or ``("velocity", V)`` from ``setp stepgen.N.position-cmd``
            / ``velocity-cmd``, None if not set.
        enable: ``setp stepgen.N.enable`` (None: not set).
        enable_connected: a ``net`` drives ``stepgen.N.enable``.
        stepgen_loaded: a ``loadrt stepgen`` was read.
        hal_read: HAL commands were read (a configuration's HAL files, not only options).
        stepgen_named: a HAL command names a ``stepgen.`` pin, parameter or function.
        ignored: what the files say that the model does not honour, one line each.
    """

    channel: int = 0
    base_period_ns: int | None = None
    servo_period_ns: int | None = None
    step_type: int | None = None
    ctrl_type: str | None = None
    user_step_type: tuple[int, ...] = ()
    params: dict[str, int] = field(default_factory=dict)
    floats: dict[str, float] = field(default_factory=dict)
    sources: dict[str, str] = field(default_factory=dict)
    threads: dict[str, int] = field(default_factory=dict)
    functions: dict[str, list[str]] = field(default_factory=dict)
    thread_order: str | None = None
    command: tuple[str, float] | None = None
    enable: bool | None = None
    enable_connected: bool = False
    stepgen_loaded: bool = False
    hal_read: bool = False
    stepgen_named: bool = False
    ignored: list[str] = field(default_factory=list)

    def periods(self) -> dict[str, int]:
        """steplen, stepspace, dirsetup, dirhold in whole base periods, rounded up as stepgen
        rounds them (steplen 0 counts as 1 ns; LinuxCNC's defaults are 1 ns = one period).

        Raises:
            ConfigError: no BASE_PERIOD known.
        """
        p = self.require_base_period()
        out: dict[str, int] = {}
        for name in ("steplen", "stepspace", "dirsetup", "dirhold"):
            ns = self.params.get(name, 1)
            if name == "steplen":
                ns = max(ns, 1)
            out[name] = -(-ns // p)
        return out

    def require_base_period(self) -> int:
        """BASE_PERIOD in ns (ConfigError when no INI gave it)."""
        if self.base_period_ns is None:
            raise ConfigError(
                "no BASE_PERIOD: give --ini FILE with [EMCMOT] BASE_PERIOD (or --base-period)"
            )
        return self.base_period_ns

    def stepgen_kwargs(self) -> dict[str, Any]:
        """The settings that were set, keyed by the model's field names (``base_period_ns``, ``mode``,
        ``steplen`` …)."""
        kw: dict[str, Any] = {}
        if self.step_type is not None:
            kw["step_type"] = self.step_type
        if self.user_step_type:
            kw["user_step_type"] = self.user_step_type
        if self.base_period_ns is not None:
            kw["base_period_ns"] = self.base_period_ns
        if self.servo_period_ns is not None:
            kw["servo_period_ns"] = self.servo_period_ns
        if self.ctrl_type is not None:
            kw["mode"] = self.ctrl_type
        for name in TIMING_PARAMS:
            if name in self.params:
                kw[name] = self.params[name]
        for name, value in self.floats.items():
            kw[name.replace("-", "_")] = value
        if self.thread_order is not None:
            kw["thread_order"] = self.thread_order
        if self.enable is not None:
            kw["enable"] = self.enable
        return kw


def _list_entry(text: str, channel: int, where: str, what: str) -> str:
    items = [s.strip() for s in text.split(",")]
    if channel >= len(items):
        raise ConfigError(
            f"{where}: {what}={text} has {len(items)} channel(s); channel {channel} is not loaded "
            f"(use --channel 0..{len(items) - 1})"
        )
    return items[channel]


#: stepgen's HAL functions (reference §1).
PULSES, UPDATE = "stepgen.make-pulses", "stepgen.update-freq"
#: ``loadrt threads`` makes up to three threads (``nameN=``, ``periodN=``).
_THREADS_MAX = 3


def _thread_period(value: str, where: str, what: str) -> int:
    ns = int_ns(value, where, what)
    if ns == 0:
        raise ConfigError(f"{where}: {what} must be > 0 ns")
    return ns


def _parse_loadrt_stepgen(args: dict[str, str], cfg: LinuxCNCConfig, where: str) -> None:
    cfg.stepgen_loaded = True
    for key, value in args.items():
        if key == "step_type":
            entry = _list_entry(value, cfg.channel, where, key)
            try:
                cfg.step_type = int(entry)
            except ValueError:
                raise ConfigError(f"{where}: step_type entry {entry!r} is not a number") from None
            cfg.sources["step_type"] = where
        elif key == "ctrl_type":
            entry = _list_entry(value, cfg.channel, where, key).lower()
            if entry not in ("p", "v"):
                raise ConfigError(f"{where}: ctrl_type entry {entry!r} is not p or v")
            cfg.ctrl_type = "position" if entry == "p" else "velocity"
            cfg.sources["ctrl_type"] = where
        elif key == "user_step_type":
            try:
                cfg.user_step_type = tuple(int(v, 0) for v in value.split(",") if v)
            except ValueError:
                raise ConfigError(
                    f"{where}: user_step_type={value} is not a list of numbers"
                ) from None
            cfg.sources["user_step_type"] = where


def _parse_loadrt_threads(args: dict[str, str], cfg: LinuxCNCConfig, where: str) -> None:
    for i in range(1, _THREADS_MAX + 1):
        name = args.get(f"name{i}")
        period = args.get(f"period{i}")
        if period is None:
            if name is not None:
                cfg.ignored.append(
                    f"ignored: thread {name} ({where}) has no period{i}= (its period is not known)"
                )
            continue
        name = name or f"thread{i}"
        cfg.threads[name] = _thread_period(period, where, f"period{i}")
        cfg.sources[f"thread {name}"] = where


def _parse_loadrt_motmod(args: dict[str, str], cfg: LinuxCNCConfig, where: str) -> None:
    # motmod makes the base thread only when base_period_nsec > 0
    for key, name in (("base_period_nsec", "base-thread"), ("servo_period_nsec", "servo-thread")):
        value = args.get(key)
        if value is None:
            continue
        ns = int_ns(value, where, key)
        if ns > 0:
            cfg.threads[name] = ns
            cfg.sources[f"thread {name}"] = where


def _parse_addf(words: list[str], cfg: LinuxCNCConfig, where: str) -> None:
    """``addf FUNCT THREAD [POSITION]``: POSITION 1 = first, -1 = last (the default)."""
    if len(words) < 3:
        return
    funct, thread = words[1], words[2]
    order = cfg.functions.setdefault(thread, [])
    position = -1
    if len(words) > 3:
        try:
            position = int(words[3])
        except ValueError:
            raise ConfigError(f"{where}: addf position {words[3]!r} is not a number") from None
    if position > 0:
        order.insert(min(position - 1, len(order)), funct)
    else:
        order.insert(max(len(order) + 1 + position, 0), funct)
    if funct in (PULSES, UPDATE):
        cfg.sources[funct] = where


def _parse_net(words: list[str], cfg: LinuxCNCConfig, where: str, prefix: str) -> None:
    """``net SIGNAL PIN…``: a net that drives the channel's command or enable pin."""
    for pin in words[2:]:
        if not pin.startswith(prefix):
            continue
        name = pin[len(prefix) :]
        line = " ".join(words)
        if name in ("position-cmd", "velocity-cmd"):
            cfg.ignored.append(
                f"ignored: {line} ({where}) (the model drives {name} itself: --position, "
                "--velocity, --move, --command or --motion)"
            )
        elif name == "enable":
            cfg.enable_connected = True
            cfg.ignored.append(f"ignored: {line} ({where}) (the model keeps enable on)")


def _parse_setp(name: str, value: str, cfg: LinuxCNCConfig, where: str, prefix: str) -> None:
    param = name[len(prefix) :]
    if param in TIMING_PARAMS:
        cfg.params[param] = int_ns(value, where, name)
        cfg.sources[param] = where
    elif param in _FLOAT_PARAMS:
        try:
            cfg.floats[param] = float(value)
        except ValueError:
            raise ConfigError(f"{where}: {name} {value!r} is not a number") from None
        cfg.sources[param] = where
    elif param in ("position-cmd", "velocity-cmd"):
        try:
            number = float(value)
        except ValueError:
            raise ConfigError(f"{where}: {name} {value!r} is not a number") from None
        if not math.isfinite(number):
            raise ConfigError(f"{where}: {name} {value!r} is not finite")
        cfg.command = (param[: -len("-cmd")], number)
        cfg.sources["command"] = where
    elif param == "enable":
        if value.strip().lower() not in ("0", "1", "true", "false"):
            raise ConfigError(f"{where}: {name} {value!r} is not 0 or 1")
        cfg.enable = value.strip().lower() in ("1", "true")
        cfg.sources["enable"] = where
    else:
        cfg.ignored.append(
            f"ignored: setp {name} {value} ({where}) (not a stepgen setting the model has)"
        )


def _parse_lines(lines: Sequence[HalLine], cfg: LinuxCNCConfig, ini: IniFile | None) -> None:
    prefix = f"stepgen.{cfg.channel}."
    for hal in lines:
        where = hal.where
        words = hal_words(hal.text)
        if not words:
            continue
        if any(w.startswith("stepgen.") for w in words):
            cfg.stepgen_named = True
        if words[0] == "loadrt" and len(words) > 1:
            module = ini_value(words[1], ini)
            if module in ("stepgen", "threads", "motmod"):
                args = loadrt_args(words[2:], ini, where)
                {"stepgen": _parse_loadrt_stepgen, "threads": _parse_loadrt_threads,
                 "motmod": _parse_loadrt_motmod}[module](args, cfg, where)  # fmt: skip
            continue
        if words[0] == "addf":
            _parse_addf(words, cfg, where)
            continue
        if words[0] == "net":
            _parse_net(words, cfg, where, prefix)
            continue
        if words[0] == "setp" and len(words) >= 3:
            name, value = words[1], words[2]
        elif len(words) >= 3 and words[1] == "=":
            name, value = words[0], words[2]
        else:
            continue
        if name.startswith(prefix):
            _parse_setp(name, resolve_ref(value, ini, where), cfg, where, prefix)


def _thread_of(cfg: LinuxCNCConfig, funct: str) -> str | None:
    for thread, functs in cfg.functions.items():
        if funct in functs:
            return thread
    return None


def _apply_threads(cfg: LinuxCNCConfig) -> None:
    """Base/servo period and thread order from the threads stepgen's functions were added to."""
    pulses, update = _thread_of(cfg, PULSES), _thread_of(cfg, UPDATE)
    for thread, key, attr, funct in (
        (pulses, "BASE_PERIOD", "base_period_ns", PULSES),
        (update, "SERVO_PERIOD", "servo_period_ns", UPDATE),
    ):
        if thread is None or thread not in cfg.threads:
            continue
        ns, where = cfg.threads[thread], cfg.sources[f"thread {thread}"]
        old = getattr(cfg, attr)
        if old is not None and old != ns and cfg.sources.get(key) != where:
            cfg.ignored.append(
                f"ignored: [EMCMOT]{key} {old} ns ({cfg.sources.get(key)}): {funct} runs in "
                f"thread {thread}, period {ns} ns ({where})"
            )
        setattr(cfg, attr, ns)
        cfg.sources[key] = where
    if pulses is not None and pulses == update:
        order = cfg.functions[pulses]
        first = order.index(UPDATE) < order.index(PULSES)
        cfg.thread_order = "update-first" if first else "pulses-first"
    if (pulses is None) != (update is None):
        missing, present = (UPDATE, PULSES) if update is None else (PULSES, UPDATE)
        cfg.ignored.append(
            f"ignored: {present} is added to a thread ({cfg.sources[present]}) but {missing} is not: "
            f"LinuxCNC would make no steps; the model runs both"
        )
    if cfg.stepgen_loaded and cfg.enable is None and not cfg.enable_connected:
        cfg.ignored.append(
            f"ignored: stepgen.{cfg.channel}.enable is never set or connected (LinuxCNC would make "
            "no steps); the model keeps it on"
        )


def read_config(
    ini: str | os.PathLike[str] | None = None,
    hal: str | os.PathLike[str] | list[str | os.PathLike[str]] | None = None,
    channel: int = 0,
) -> LinuxCNCConfig:
    """Read the stepgen settings of ``channel`` from an INI and HAL files (either may be None).

    Raises:
        ConfigError: unreadable files, malformed values, a channel that is not loaded.
    """
    ini_file = read_ini(ini) if ini is not None else None
    hals = [] if hal is None else ([hal] if isinstance(hal, (str, os.PathLike)) else list(hal))
    lines = [line for h in hals for line in hal_lines(h)[0]]
    return read_config_lines(ini_file, lines, channel)


def read_config_lines(
    ini_file: IniFile | None, lines: Sequence[HalLine], channel: int = 0
) -> LinuxCNCConfig:
    """:func:`read_config` from an INI already read and HAL commands already read
    (:func:`~wavecheck.linuxcnc.files.hal_lines`)."""
    if channel < 0:
        raise ConfigError(f"--channel {channel} must be 0 or more")
    cfg = LinuxCNCConfig(channel=channel, hal_read=bool(lines))
    if ini_file is not None:
        for key, attr in (("BASE_PERIOD", "base_period_ns"), ("SERVO_PERIOD", "servo_period_ns")):
            found = ini_file.get("EMCMOT", key)
            if found is None:
                continue
            where = ini_file.place("EMCMOT", key)
            ns = int_ns(found[0].split()[0] if found[0].split() else "", where, f"[EMCMOT]{key}")
            if ns == 0:
                raise ConfigError(f"{where}: [EMCMOT]{key} must be > 0 ns")
            setattr(cfg, attr, ns)
            cfg.sources[key] = where
    _parse_lines(lines, cfg, ini_file)
    _apply_threads(cfg)
    return cfg


@dataclass(frozen=True)
class ConfigRates:
    """Max step rates from a stepgen configuration, exact Hz (None: not defined or none safe).

    Attributes:
        config: stepgen's own clamp, 1 / ((steplen + stepspace)·P) (steplen·P for types ≥ 2).
        latency_safe: the highest rate at which every interval meets the drive under ``J``.
        notes: why a rate is None, or what limits it.
        channel: the stepgen channel the rates are of.
        base_period_ns: the BASE_PERIOD they assume.
        latency_ns: the worst latency ``J`` they assume (None: not given).
    """

    config: Fraction | None
    latency_safe: Fraction | None
    notes: tuple[str, ...] = ()
    channel: int = 0
    base_period_ns: int = 0
    latency_ns: Fraction | None = None


def config_rates(
    cfg: LinuxCNCConfig,
    drive: Drive,
    latency_ns: Fraction | int | None = None,
    *,
    step_inverted: bool = False,
    step_type: int | None = None,
) -> ConfigRates:
    """The ``config`` and ``latency_safe`` rates of ``cfg`` for ``drive`` (see the module doc).

    Args:
        cfg: the configuration (needs BASE_PERIOD).
        drive: a :class:`~wavecheck.drives.datasheet.Drive`.
        latency_ns: worst latency ``J`` in ns; without it ``latency_safe`` is None.
        step_inverted: the STEP pin is inverted between stepgen and the drive (moves the active
            edge to the start of stepgen's pulse; see :mod:`wavecheck.linuxcnc.timing`).
        step_type: the step type checked (default ``cfg.step_type``, else 0). Types ≥ 2 have no
            stepspace (config = 1 / (steplen·P)) and no latency_safe (the plan is step/dir's).
    """
    if cfg.hal_read and not cfg.stepgen_loaded and not cfg.stepgen_named:
        return ConfigRates(None, None, (
            "no software stepgen: the HAL files load no stepgen, so stepgen's config and "
            "latency_safe rates do not apply (a hostmot2 or other card makes the steps)",
        ), cfg.channel, cfg.base_period_ns or 0, None)  # fmt: skip
    p = cfg.require_base_period()
    j = None if latency_ns is None else Fraction(latency_ns)

    def _rates(
        config: Fraction | None, safe: Fraction | None, notes: tuple[str, ...]
    ) -> ConfigRates:
        return ConfigRates(config, safe, notes, cfg.channel, p, j)

    n = cfg.periods()
    number = step_type if step_type is not None else cfg.step_type or 0
    if kind_of(number) == "phases":
        return _rates(
            step_rate_hz(p, n["steplen"]),
            None,
            (f"latency_safe is computed for step types 0 and 1, not step type {number}",),
        )
    config = step_rate_hz(p, n["steplen"] + n["stepspace"])
    if latency_ns is None:
        return _rates(config, None, ("latency_safe needs --latency J",))
    try:
        reqs = evaluate(drive, latency_ns, p, n, step_inverted=step_inverted)
    except ConfigError as err:
        return _rates(config, None, (f"latency_safe not computed: {err}",))
    fixed_fail = [r for r in reqs if not r.rate_dependent and r.margin_ns < 0]
    if fixed_fail:
        worst = min(fixed_fail, key=lambda r: r.margin_ns)
        return _rates(
            config,
            None,
            (
                f"no rate is latency-safe: {worst.rule} ({worst.formula}) is "
                f"{float(worst.worst_ns):g} ns < {float(worst.limit_ns):g} ns at any rate",
            ),
        )
    per_step = n["steplen"] + n["stepspace"]
    for r in reqs:
        if r.params == ("stepspace",):
            per_step = max(per_step, n["steplen"] + periods_needed(r.limit_ns, latency_ns, p))
        elif r.params == ("steplen", "stepspace"):
            per_step = max(per_step, periods_needed(r.limit_ns, latency_ns, p))
    safe = step_rate_hz(p, per_step)
    note = (
        f"latency_safe: {per_step} base periods per step (config: "
        f"{n['steplen'] + n['stepspace']}) at J = {float(latency_ns):g} ns"
    )
    return _rates(config, min(safe, config), (note,))
