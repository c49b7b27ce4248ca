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
    *TIMING_PARAMS,
)


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
    :func:`add_simulate_arguments`); returns the configuration read, or None without files."""
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
    for name in TIMING_PARAMS:
        values[name] = f"{cfg.params[name]}ns" if name in cfg.params else None
    for dest, value in values.items():
        if value is None or not hasattr(args, dest):
            continue
        if dest in defaults and getattr(args, dest) != defaults[dest]:
            continue  # given on the command line: it wins
        setattr(args, dest, value)
    return cfg
