"""``stepgen simulate --ini/--hal``: fill the simulate options from LinuxCNC's own files."""

from __future__ import annotations

from typing import Any

from wavecheck.cli.linuxcnc import add_file_arguments
from wavecheck.linuxcnc.config import TIMING_PARAMS, LinuxCNCConfig, read_config

__all__ = ["add_simulate_arguments", "apply_to_simulate_args"]

#: simulate option dest → how a LinuxCNCConfig fills it.
_SIMULATE_FIELDS = (
    "base_period",
    "servo_period",
    "type",
    "user_step_type",
    "mode",
    "position_scale",
    "maxvel",
    "maxaccel",
    "thread_order",
    *TIMING_PARAMS,
)
#: simulate's motion options: a command the files set fills one only when none is given.
_MOTIONS = ("position", "velocity", "command", "move", "motion")


def add_simulate_arguments(parser: Any) -> None:
    """Add ``--ini``, ``--hal`` and ``--channel`` to ``stepgen simulate``'s parser.

    Settings read from the files fill every option left at its default; an option given with
    another value on the command line wins.
    """
    add_file_arguments(parser.add_argument_group("LinuxCNC configuration files"))
    defaults = {
        a.dest: a.default for a in parser._actions if a.dest in _SIMULATE_FIELDS  # noqa: SLF001
    }
    parser.set_defaults(_linuxcnc_defaults=defaults)


def apply_to_simulate_args(args: Any) -> LinuxCNCConfig | None:
    """Fill ``stepgen simulate``'s options from ``--ini``/``--hal`` (see
    :func:`add_simulate_arguments`); returns the configuration read, or None without files.

    Besides the settings: the threads' periods (base/servo period), the ``addf`` order in one
    thread (``--thread-order``), ``setp stepgen.N.enable``, and a ``setp …position-cmd`` /
    ``velocity-cmd`` (a constant command, used when no motion option is given). What the files
    say that the run does not honour goes to ``args._linuxcnc_ignored``, one line each.
    """
    args._linuxcnc_ignored = []
    if not getattr(args, "ini", None) and not getattr(args, "hal", None):
        return None
    cfg = read_config(args.ini, list(args.hal or []), getattr(args, "channel", 0))
    defaults: dict[str, Any] = getattr(args, "_linuxcnc_defaults", {})
    values: dict[str, Any] = {
        # LinuxCNC's files hold bare ns; the options need the unit
        "base_period": None if cfg.base_period_ns is None else f"{cfg.base_period_ns}ns",
        "servo_period": None if cfg.servo_period_ns is None else f"{cfg.servo_period_ns}ns",
        "type": cfg.step_type,
        "user_step_type": ",".join(str(v) for v in cfg.user_step_type) or None,
        "mode": cfg.ctrl_type,
        "position_scale": cfg.floats.get("position-scale"),
        "maxvel": cfg.floats.get("maxvel"),
        "maxaccel": cfg.floats.get("maxaccel"),
    }
    values["thread_order"] = cfg.thread_order
    for name in TIMING_PARAMS:
        values[name] = f"{cfg.params[name]}ns" if name in cfg.params else None
    for dest, value in values.items():
        if value is None or not hasattr(args, dest):
            continue
        if dest in defaults and getattr(args, dest) != defaults[dest]:
            continue  # given on the command line: it wins
        setattr(args, dest, value)
    if cfg.enable is not None:
        args.enable = cfg.enable
    ignored = list(cfg.ignored)
    if cfg.command is not None:
        kind, value = cfg.command
        where = cfg.sources["command"]
        given = [k for k in _MOTIONS if getattr(args, k, None) is not None]
        if given:
            ignored.append(
                f"ignored: setp stepgen.{cfg.channel}.{kind}-cmd {value:g} ({where}): --{given[0]} "
                "drives the command"
            )
        elif kind != args.mode:
            ignored.append(
                f"ignored: setp stepgen.{cfg.channel}.{kind}-cmd {value:g} ({where}): the channel "
                f"is in {args.mode} mode (no {kind}-cmd pin)"
            )
        else:
            setattr(args, kind, value)
    args._linuxcnc_ignored = ignored
    return cfg
