"""LinuxCNC's own configuration files: the stepgen settings of one channel, from INI and HAL.

- INI (``--ini FILE``): ``[EMCMOT] BASE_PERIOD`` and ``SERVO_PERIOD`` (ns), and any value a HAL
  file refers to as ``[SECTION]KEY``.
- HAL (``--hal FILE``, repeatable): ``loadrt stepgen step_type=0,0,1 ctrl_type=p,p,v
  user_step_type=…`` and ``setp stepgen.N.steplen 5000`` (also ``stepgen.N.steplen = 5000``);
  values may be ``[SECTION]KEY`` references into the INI. stepgen's timing parameters are ns.

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

import os
import re
from dataclasses import dataclass, field
from fractions import Fraction
from pathlib import Path
from typing import Any

from wavecheck.drives.model import Drive
from wavecheck.errors import ConfigError
from wavecheck.linuxcnc.steptypes import kind_of
from wavecheck.linuxcnc.timing import evaluate, periods_needed, step_rate_hz

__all__ = [
    "TIMING_PARAMS",
    "ConfigRates",
    "IniFile",
    "LinuxCNCConfig",
    "config_rates",
    "read_config",
    "read_ini",
]

#: stepgen's timing parameters (ns, u32), in LinuxCNC's order.
TIMING_PARAMS = ("steplen", "stepspace", "dirsetup", "dirhold", "dirdelay")
_FLOAT_PARAMS = ("position-scale", "maxvel", "maxaccel")
_INI_REF = re.compile(r"^\[([^\]]+)\](\S+)$")


@dataclass
class IniFile:
    """A LinuxCNC INI file: section → key → every (value, line) in file order.

    LinuxCNC allows a key more than once (``HALFILE``); :meth:`get` returns the first, as
    LinuxCNC's ``ini.find`` does.
    """

    path: str
    sections: dict[str, dict[str, list[tuple[str, int]]]] = field(default_factory=dict)

    def get(self, section: str, key: str) -> tuple[str, int] | None:
        """The first value of ``[section] key`` and its line, or None."""
        values = self.sections.get(section, {}).get(key)
        return values[0] if values else None


def read_ini(path: str | os.PathLike[str]) -> IniFile:
    """Read a LinuxCNC INI file (``#``/``;`` comment lines, ``KEY = VALUE`` lines).

    Raises:
        ConfigError: the file cannot be read or a line is neither a section nor ``KEY = VALUE``.
    """
    text = _read(path)
    ini = IniFile(str(path))
    section: str | None = None
    for no, raw in enumerate(text.splitlines(), 1):
        line = raw.strip()
        if not line or line[0] in "#;":
            continue
        if line.startswith("["):
            if not line.endswith("]"):
                raise ConfigError(f"{path}: line {no}: bad section header {line!r} (expected [NAME])")
            section = line[1:-1].strip()
            ini.sections.setdefault(section, {})
            continue
        if "=" not in line:
            raise ConfigError(f"{path}: line {no}: {line!r} is not KEY = VALUE")
        if section is None:
            raise ConfigError(f"{path}: line {no}: {line!r} comes before any [SECTION]")
        key, value = (s.strip() for s in line.split("=", 1))
        ini.sections[section].setdefault(key, []).append((value, no))
    return ini


def _read(path: str | os.PathLike[str]) -> str:
    try:
        return Path(path).read_text(encoding="utf-8", errors="replace")
    except OSError as err:
        raise ConfigError(f"{path}: cannot read: {err.strerror or err}") from None


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
        return kw


def _int_ns(value: str, where: str, what: str) -> int:
    try:
        number = Fraction(value)
    except (ValueError, ZeroDivisionError):
        raise ConfigError(f"{where}: {what} {value!r} is not a number of ns") from None
    if number.denominator != 1 or number < 0 or number > 2**32 - 1:
        raise ConfigError(f"{where}: {what} {value!r} is not a whole u32 number of ns")
    return int(number)


def _resolve(value: str, ini: IniFile | None, where: str) -> str:
    m = _INI_REF.match(value)
    if not m:
        return value
    if ini is None:
        raise ConfigError(f"{where}: {value} refers to the INI file (give --ini FILE)")
    found = ini.get(m.group(1), m.group(2))
    if found is None:
        raise ConfigError(f"{where}: {value} is not in {ini.path}")
    return found[0]


def _list_entry(text: str, channel: int, where: str, what: str) -> str:
    items = [s.strip() for s in text.split(",")]
    if channel >= len(items):
        raise ConfigError(
            f"{where}: {what}={text} has {len(items)} channel(s); channel {channel} is not loaded "
            f"(use --channel 0..{len(items) - 1})"
        )
    return items[channel]


def _parse_hal(path: str | os.PathLike[str], cfg: LinuxCNCConfig, ini: IniFile | None) -> None:
    text = _read(path)
    lines = text.replace("\\\n", " ").splitlines()
    prefix = f"stepgen.{cfg.channel}."
    for no, raw in enumerate(lines, 1):
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        where = f"{path}:{no}"
        words = line.split()
        if words[0] == "loadrt" and len(words) > 1 and words[1] == "stepgen":
            for arg in words[2:]:
                if "=" not in arg:
                    continue
                key, value = arg.split("=", 1)
                value = _resolve(value, ini, where)
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
                        raise ConfigError(f"{where}: user_step_type={value} is not a list of numbers") from None
                    cfg.sources["user_step_type"] = where
            continue
        if words[0] == "setp" and len(words) >= 3:
            name, value = words[1], words[2]
        elif len(words) >= 3 and words[1] == "=":
            name, value = words[0], words[2]
        else:
            continue
        if not name.startswith(prefix):
            continue
        param = name[len(prefix) :]
        value = _resolve(value, ini, where)
        if param in TIMING_PARAMS:
            cfg.params[param] = _int_ns(value, where, name)
            cfg.sources[param] = where
        elif param in _FLOAT_PARAMS:
            try:
                cfg.floats[param] = float(value)
            except ValueError:
                raise ConfigError(f"{where}: {name} {value!r} is not a number") from None
            cfg.sources[param] = where


def read_config(
    ini: str | os.PathLike[str] | None = None,
    hal: str | os.PathLike[str] | list[str | os.PathLike[str]] | None = None,
    channel: int = 0,
) -> LinuxCNCConfig:
    """Read the stepgen settings of ``channel`` from an INI and HAL files (either may be None).

    Raises:
        ConfigError: unreadable files, malformed values, a channel that is not loaded.
    """
    if channel < 0:
        raise ConfigError(f"--channel {channel} must be 0 or more")
    cfg = LinuxCNCConfig(channel=channel)
    ini_file = read_ini(ini) if ini is not None else None
    if ini_file is not None:
        for key, attr in (("BASE_PERIOD", "base_period_ns"), ("SERVO_PERIOD", "servo_period_ns")):
            found = ini_file.get("EMCMOT", key)
            if found is None:
                continue
            where = f"{ini}:{found[1]}"
            ns = _int_ns(found[0].split()[0], where, f"[EMCMOT]{key}")
            if ns == 0:
                raise ConfigError(f"{where}: [EMCMOT]{key} must be > 0 ns")
            setattr(cfg, attr, ns)
            cfg.sources[key] = where
    hals = [] if hal is None else ([hal] if isinstance(hal, (str, os.PathLike)) else list(hal))
    for h in hals:
        _parse_hal(h, cfg, ini_file)
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
        drive: a :class:`~wavecheck.drives.model.Drive`.
        latency_ns: worst latency ``J`` in ns; without it ``latency_safe`` is None.
        step_inverted: the STEP pin is inverted between stepgen and the drive (moves the active
            edge to the start of stepgen's pulse; see :mod:`wavecheck.linuxcnc.timing`).
        step_type: the step type checked (default ``cfg.step_type``, else 0). Types ≥ 2 have no
            stepspace (config = 1 / (steplen·P)) and no latency_safe (the plan is step/dir's).
    """
    p = cfg.require_base_period()
    j = None if latency_ns is None else Fraction(latency_ns)

    def _rates(config: Fraction | None, safe: Fraction | None, notes: tuple[str, ...]) -> ConfigRates:
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
