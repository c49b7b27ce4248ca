"""LinuxCNC's ``pid`` settings from its own files: ``loadrt pid num_chan=/names=``, ``setp
pid.N.Pgain …`` (values may be ``[JOINT_n]P`` references), the nets wiring an instance to
``stepgen.N.velocity-cmd`` and ``joint.N.motor-pos-cmd``, and the INI's ``[JOINT_n] P, I, D, FF0,
FF1, FF2, BIAS, DEADBAND, MAX_OUTPUT`` and motion's ``FERROR, MIN_FERROR, MAX_VELOCITY,
MAX_ACCELERATION``, into a :class:`PidConfig` (``stepgen simulate --pid``)."""

from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass, field

from wavecheck.config_text import read_text
from wavecheck.errors import ConfigError
from wavecheck.linuxcnc.files import (
    INI_REF,
    IniFile,
    hal_words,
    loadrt_args,
    read_ini,
    resolve_ref,
)

__all__ = ["JOINT_PID_KEYS", "PID_PINS", "PidConfig", "read_pid_config"]

# --- pid (reference pid-linuxcnc.md §1, §3, §4.4) -------------------------------------------

#: pid's tunable float input pins (pid reference §1), in its table's order.
PID_PINS = (
    "Pgain",
    "Igain",
    "Dgain",
    "bias",
    "FF0",
    "FF1",
    "FF2",
    "FF3",
    "deadband",
    "maxerror",
    "maxerrorI",
    "maxerrorD",
    "maxcmdD",
    "maxcmdDD",
    "maxcmdDDD",
    "maxoutput",
)
#: pid's bit input that a configuration sets (pncconf writes it, pid reference §3).
_PID_BIT = "error-previous-target"
#: pid pins whose signal the model makes itself (the loop's wiring).
_PID_WIRING = ("command", "feedback", "output", "enable", "index-enable")
#: ``[JOINT_n]`` key → the pid pin pncconf's ``setp pid.N.<pin> [JOINT_n]<KEY>`` sets from it.
JOINT_PID_KEYS = {
    "P": "Pgain",
    "I": "Igain",
    "D": "Dgain",
    "BIAS": "bias",
    "FF0": "FF0",
    "FF1": "FF1",
    "FF2": "FF2",
    "DEADBAND": "deadband",
    "MAX_OUTPUT": "maxoutput",
}
#: ``[JOINT_n]`` keys motion reads itself (its following-error check, pid reference §4.4, and
#: the joint's limits the trajectory planner keeps to).
_JOINT_MOTION_KEYS = {
    "FERROR": "ferror",
    "MIN_FERROR": "min_ferror",
    "MAX_VELOCITY": "max_velocity",
    "MAX_ACCELERATION": "max_acceleration",
}
#: ``loadrt pid`` makes three instances unless ``num_chan=``/``names=`` say otherwise.
_PID_DEFAULT_CHANNELS = 3
#: at most 16 instances (pid reference §1).
_PID_MAX_CHANNELS = 16


@dataclass
class PidConfig:
    """The pid of one joint and motion's following-error limits, with where each came from.

    Attributes:
        joint: the joint (``[JOINT_n]``, ``joint.N.*``).
        name: the pid instance (``pid.0``, ``pid.x``), None when the HAL files load none for
            this joint (then ``pins`` are the INI's ``[JOINT_n]`` gains, read as pncconf's
            ``setp`` lines read them).
        pins: pid pin → value (``Pgain``, ``FF1``, ``maxerror`` …, only those set).
        error_previous_target: ``setp <name>.error-previous-target`` (None: not set).
        ferror, min_ferror, max_velocity, max_acceleration: ``[JOINT_n] FERROR``,
            ``MIN_FERROR``, ``MAX_VELOCITY``, ``MAX_ACCELERATION`` (None: not in the INI).
        drives: the stepgen pin the instance's ``output`` is netted to
            (``stepgen.0.velocity-cmd``), None if none.
        chosen: why this instance is the joint's (``"its output drives stepgen.0.velocity-cmd"``).
        sources: pin or key → ``"file:line"``.
        ignored: what the files say about this pid that the model does not honour.
    """

    joint: int = 0
    name: str | None = None
    pins: dict[str, float] = field(default_factory=dict)
    error_previous_target: bool | None = None
    ferror: float | None = None
    min_ferror: float | None = None
    max_velocity: float | None = None
    max_acceleration: float | None = None
    drives: str | None = None
    chosen: str = ""
    sources: dict[str, str] = field(default_factory=dict)
    ignored: list[str] = field(default_factory=list)


@dataclass
class _PidHal:
    """What the HAL files say about every pid instance (before one is chosen)."""

    instances: list[str] = field(default_factory=list)
    loaded: bool = False
    # instance → pin → (value as written, where); INI references are resolved only for the
    # chosen instance (another component's reference is not this model's business)
    setp: dict[str, dict[str, tuple[str, str]]] = field(default_factory=dict)
    # signal → [(pin, where)]
    nets: dict[str, list[tuple[str, str]]] = field(default_factory=dict)


def _float_value(value: str, where: str, what: str) -> float:
    try:
        number = float(value.split()[0]) if value.split() else float("nan")
    except ValueError:
        raise ConfigError(f"{where}: {what} {value!r} is not a number") from None
    if not math.isfinite(number):
        raise ConfigError(f"{where}: {what} {value!r} is not a finite number")
    return number


def _pid_loadrt(args: dict[str, str], hal: _PidHal, where: str) -> None:
    if "names" in args and "num_chan" in args:
        raise ConfigError(f"{where}: loadrt pid takes num_chan= or names=, not both")
    if "names" in args:
        names = [n.strip() for n in args["names"].split(",") if n.strip()]
    else:
        text = args.get("num_chan", str(_PID_DEFAULT_CHANNELS))
        try:
            count = int(text)
        except ValueError:
            raise ConfigError(f"{where}: loadrt pid num_chan={text} is not a number") from None
        names = [f"pid.{i}" for i in range(count)]
    if not 1 <= len(names) <= _PID_MAX_CHANNELS:
        raise ConfigError(
            f"{where}: loadrt pid makes {len(names)} instances (1..{_PID_MAX_CHANNELS})"
        )
    hal.loaded = True
    hal.instances += [n for n in names if n not in hal.instances]


def _pid_pin(name: str) -> tuple[str, str] | None:
    """``pid.x.Pgain`` → (``pid.x``, ``Pgain``) when the last part is a pid pin."""
    inst, _, pin = name.rpartition(".")
    if inst and (
        pin in PID_PINS or pin == _PID_BIT or pin in _PID_WIRING or pin.endswith("-deriv")
    ):
        return inst, pin
    return None


def _parse_pid_hal(path: str | os.PathLike[str], hal: _PidHal, ini: IniFile | None) -> None:
    text = read_text(path)
    for no, raw in enumerate(text.replace("\\\n", " ").splitlines(), 1):
        line = raw.split("#", 1)[0].strip()
        words = hal_words(line) if line else []
        if not words:
            continue
        where = f"{path}:{no}"
        if words[0] == "loadrt" and len(words) > 1 and words[1] == "pid":
            _pid_loadrt(loadrt_args(words[2:], ini, where), hal, where)
        elif words[0] == "net" and len(words) > 2:
            pins = [w for w in words[2:] if w not in ("<=", "=>", "<=>")]
            hal.nets.setdefault(words[1], []).extend((pin, where) for pin in pins)
        elif (words[0] == "setp" and len(words) >= 3) or (len(words) >= 3 and words[1] == "="):
            name, value = (words[1], words[2]) if words[0] == "setp" else (words[0], words[2])
            found = _pid_pin(name)
            if found is None or found[1] in _PID_WIRING:
                continue
            inst, pin = found
            hal.setp.setdefault(inst, {})[pin] = (value, where)


def _net_peers(hal: _PidHal, pin: str) -> list[tuple[str, str]]:
    """The pins sharing a signal with ``pin`` (and where each was netted)."""
    out: list[tuple[str, str]] = []
    for members in hal.nets.values():
        if any(p == pin for p, _ in members):
            out += [(p, w) for p, w in members if p != pin]
    return out


def _joint_refs(hal: _PidHal, inst: str) -> set[int]:
    """The ``n`` of every ``[JOINT_n]`` reference among ``inst``'s setp values."""
    out: set[int] = set()
    for raw, _ in hal.setp.get(inst, {}).values():
        m = re.match(r"^\[JOINT_(\d{1,6})\]", raw)
        if m:
            out.add(int(m.group(1)))
    return out


def _motor_joint(hal: _PidHal, inst: str) -> int | None:
    """The joint whose ``motor-pos-cmd`` is netted to ``inst.command``."""
    for pin, _ in _net_peers(hal, f"{inst}.command"):
        m = re.match(r"^joint\.(\d{1,6})\.motor-pos-cmd$", pin)
        if m:
            return int(m.group(1))
    return None


def _choose_pid(
    hal: _PidHal, name: str | None, joint: int | None, channel: int
) -> tuple[str | None, str]:
    """(the instance, why) — see :func:`read_pid_config`."""
    known = hal.instances if hal.loaded else sorted(i for i in hal.setp if i.startswith("pid."))
    if name is not None:
        if name not in known:
            listed = ", ".join(known) or "none"
            raise ConfigError(f"pid {name!r} is not in the HAL files (pid instances: {listed})")
        return name, "given"
    target = f"stepgen.{channel}.velocity-cmd"
    for inst in known:
        if any(p == target for p, _ in _net_peers(hal, f"{inst}.output")):
            return inst, f"its output drives {target}"
    if joint is not None:
        for inst in known:
            if _motor_joint(hal, inst) == joint or _joint_refs(hal, inst) == {joint}:
                return inst, f"it is joint {joint}'s"
        if f"pid.{joint}" in known and f"pid.{joint}" in hal.setp:
            return f"pid.{joint}", f"joint {joint}"
    return None, ""


def read_pid_config(
    ini: str | os.PathLike[str] | None = None,
    hal: str | os.PathLike[str] | list[str | os.PathLike[str]] | None = None,
    *,
    channel: int = 0,
    joint: int | None = None,
    name: str | None = None,
) -> PidConfig:
    """Read the pid driving stepgen ``channel`` (or of ``joint``) and ``[JOINT_n]``'s limits.

    The instance: ``name`` if given; else the one whose ``output`` is netted to
    ``stepgen.<channel>.velocity-cmd`` (pid reference §3's wiring); else, with ``joint``, the
    one netted to ``joint.<joint>.motor-pos-cmd`` or whose setp values all read
    ``[JOINT_<joint>]`` (pncconf's ``setp pid.x.Pgain [JOINT_0]P``), else ``pid.<joint>``. The
    joint: ``joint``, else the instance's ``motor-pos-cmd`` net, else the one ``[JOINT_n]``
    its setp values read, else ``channel``. With an instance, its ``setp`` values are its pins
    (LinuxCNC's pid only knows what HAL sets; an INI gain no setp reads is listed in
    ``ignored``); without one the INI's ``[JOINT_n]`` gains are the pins.

    Raises:
        ConfigError: unreadable files, a value that is not a finite number, FERROR,
            MAX_VELOCITY or MAX_ACCELERATION not > 0, MIN_FERROR < 0, a ``name`` the files do not load.
    """
    ini_file = read_ini(ini) if ini is not None else None
    hals = [] if hal is None else ([hal] if isinstance(hal, (str, os.PathLike)) else list(hal))
    ph = _PidHal()
    for h in hals:
        _parse_pid_hal(h, ph, ini_file)
    inst, why = _choose_pid(ph, name, joint, channel)
    if joint is None and inst is not None:
        refs = _joint_refs(ph, inst)
        joint = _motor_joint(ph, inst)
        if joint is None and len(refs) == 1:
            joint = next(iter(refs))
    cfg = PidConfig(joint=channel if joint is None else joint, name=inst, chosen=why)
    section = f"JOINT_{cfg.joint}"
    if inst is not None:
        read_keys = set()
        for pin, (raw, where) in ph.setp.get(inst, {}).items():
            value = resolve_ref(raw, ini_file, where)
            if pin == _PID_BIT:
                v = value.strip().lower()
                if v not in ("0", "1", "true", "false"):
                    raise ConfigError(f"{where}: {inst}.{pin} {value!r} is not 0, 1, true or false")
                cfg.error_previous_target = v in ("1", "true")
            elif pin in PID_PINS:
                cfg.pins[pin] = _float_value(value, where, f"{inst}.{pin}")
            else:
                cfg.ignored.append(
                    f"ignored: setp {inst}.{pin} ({where}) (the model uses pid's own estimates)"
                )
                continue
            cfg.sources[pin] = where
            m = INI_REF.match(raw)
            if m and m.group(1) == section:
                read_keys.add(m.group(2) or m.group(3))
        for pin in ("command-deriv", "feedback-deriv", *PID_PINS):
            for signal, members in ph.nets.items():
                at = next((w for p, w in members if p == f"{inst}.{pin}"), None)
                if at is None:
                    continue
                if pin.endswith("-deriv"):
                    what = "pid's own derivative estimate"
                else:
                    what = (
                        f"the setp value ({cfg.pins[pin]:g})"
                        if pin in cfg.pins
                        else "pid's default"
                    )
                cfg.ignored.append(
                    f"ignored: net {signal} {inst}.{pin} ({at}) (its value is not known to the "
                    f"model, which uses {what})"
                )
        for peer, where in _net_peers(ph, f"{inst}.output"):
            if peer == f"stepgen.{channel}.velocity-cmd":
                cfg.drives = peer
                cfg.sources["drives"] = where
        if ini_file is not None:
            for key, pin in JOINT_PID_KEYS.items():
                found = ini_file.get(section, key)
                if found is not None and key not in read_keys and pin not in cfg.pins:
                    cfg.ignored.append(
                        f"ignored: [{section}]{key} = {found[0]} ({ini}:{found[1]}): no setp "
                        f"{inst}.{pin} reads it (LinuxCNC's pid keeps its own value)"
                    )
    elif ini_file is not None:
        for key, pin in JOINT_PID_KEYS.items():
            found = ini_file.get(section, key)
            if found is not None:
                where = f"{ini}:{found[1]}"
                cfg.pins[pin] = _float_value(found[0], where, f"[{section}]{key}")
                cfg.sources[pin] = where
    if ini_file is not None:
        for key, attr in _JOINT_MOTION_KEYS.items():
            found = ini_file.get(section, key)
            if found is None:
                continue
            where = f"{ini}:{found[1]}"
            limit = _float_value(found[0], where, f"[{section}]{key}")
            if limit < 0 or (limit == 0 and key != "MIN_FERROR"):
                need = ">= 0" if key == "MIN_FERROR" else "> 0"
                raise ConfigError(f"{where}: [{section}]{key} {found[0]} must be {need}")
            setattr(cfg, attr, limit)
            cfg.sources[key] = where
    return cfg
