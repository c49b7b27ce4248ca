"""``stepgen simulate --ini/--hal``: fill the simulate options from LinuxCNC's own files.

The stepgen settings (:func:`~wavecheck.linuxcnc.stepgen_config.read_config`) and, with ``--pid``,
the joint's pid and following-error limits (:func:`~wavecheck.linuxcnc.pid_settings.read_pid_config`:
``setp pid.N.Pgain …``, ``[JOINT_n] P, I, D, FF0, FF1, FF2, BIAS, DEADBAND, MAX_OUTPUT, FERROR,
MIN_FERROR, MAX_VELOCITY``; ``MAX_VELOCITY``/``MAX_ACCELERATION`` also as ``--move``'s limits)
fill every option not given on the command line.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from stepgen.cli.pid_options import GAIN_OPTIONS
from wavecheck.cli._linuxcnc_args import add_file_arguments
from wavecheck.errors import ConfigError

if TYPE_CHECKING:  # the readers are imported only when files are given
    from wavecheck.linuxcnc.pid_settings import PidConfig
    from wavecheck.linuxcnc.stepgen_config import LinuxCNCConfig

__all__ = ["add_simulate_arguments", "apply_to_simulate_args"]

#: simulate's motion options: a command the files set fills one only when none is given.
_MOTIONS = ("position", "velocity", "command", "move", "motion")
#: pid pin → its ``--pid`` option's dest (``Pgain`` → ``pgain``).
_PIN_DEST = {pin: dest for dest, pin in GAIN_OPTIONS.items()}
#: PidConfig's following-error limits → their ``--pid`` option's dest.
_LIMIT_DEST = {"ferror": "ferror", "min_ferror": "min_ferror", "max_velocity": "joint_max_velocity"}


def add_simulate_arguments(parser: Any) -> None:
    """Add ``--ini``, ``--hal`` and ``--channel`` to ``stepgen simulate``'s parser.

    Settings read from the files fill every option left at its default; an option given with
    another value on the command line wins.
    """
    add_file_arguments(parser.add_argument_group("LinuxCNC configuration files"))
    g = parser.add_argument_group("LinuxCNC pid (--pid with --ini/--hal)")
    g.add_argument(
        "--joint",
        type=int,
        help="the joint whose [JOINT_n] gains and limits apply (default: the one the pid driving "
        "stepgen.N.velocity-cmd is netted to, else --channel)",
    )
    g.add_argument(
        "--pid-name",
        help="the pid instance (pid.0, pid.x; default: the one whose output drives the channel's "
        "velocity-cmd, else joint n's)",
    )
    defaults = {a.dest: a.default for a in parser._actions}  # noqa: SLF001
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
    from wavecheck.linuxcnc.stepgen_config import TIMING_PARAMS, read_config

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
    _apply_pid(args, cfg)
    return cfg


def _apply_pid(args: Any, cfg: LinuxCNCConfig) -> PidConfig | None:
    """With ``--pid``: fill the pid and following-error options from the files (an option
    given on the command line wins) and drop the stepgen parser's "net … velocity-cmd ignored"
    line for the net pid's output drives (the closed loop honours it). Without ``--pid``: a
    note when the files close a loop around the channel."""
    from wavecheck.linuxcnc.pid_settings import read_pid_config

    hal = list(args.hal or [])
    kwargs: dict[str, Any] = {
        "channel": getattr(args, "channel", 0),
        "joint": getattr(args, "joint", None),
        "name": getattr(args, "pid_name", None),
    }
    ignored: list[str] = args._linuxcnc_ignored
    if not getattr(args, "pid", False):
        try:
            pc = read_pid_config(args.ini, hal, **kwargs)
        except ConfigError:
            return None  # the open-loop run does not depend on the pid's settings
        if pc.drives is not None:
            ignored.append(
                f"note: {pc.name}.output drives {pc.drives} ({pc.sources['drives']}): give --pid "
                "to close the loop (now the motion options drive it)"
            )
        return pc
    pc = read_pid_config(args.ini, hal, **kwargs)
    for pin, value in pc.pins.items():
        dest = _PIN_DEST[pin]
        if getattr(args, dest, None) is None:
            setattr(args, dest, value)
    if pc.error_previous_target is False and getattr(args, "error_previous_target", True):
        args.error_previous_target = False
    for attr, dest in _LIMIT_DEST.items():
        value = getattr(pc, attr)
        if value is not None and getattr(args, dest, None) is None:
            setattr(args, dest, value)
    # the trajectory keeps to the joint's limits; stepgen's own (STEPGEN_MAXVEL/MAXACCEL,
    # 1.25× these in pncconf's configurations) leave the loop its headroom (pid reference §3)
    for attr, dest in (("max_velocity", "move_vel"), ("max_acceleration", "move_accel")):
        value = getattr(pc, attr)
        if value is not None and getattr(args, dest, None) is None:
            setattr(args, dest, value)
    args._pid_from_files = bool(pc.pins)
    args._pid_config = pc
    if pc.drives is not None:
        net = f"({pc.sources['drives']})"
        ignored[:] = [
            line for line in ignored if not (line.startswith("ignored: net ") and net in line)
        ]
    if cfg.ctrl_type == "position":
        ignored.append(
            f"ignored: ctrl_type=p ({cfg.sources['ctrl_type']}): pid drives velocity-cmd, so the "
            "closed loop runs the channel in velocity mode"
        )
    ignored += pc.ignored
    return pc
