"""The closed-loop options of ``stepgen simulate --pid`` and ``stepgen tune`` (pid's pins and the
servo plant), apart from the loop itself, so that building ``stepgen simulate``'s parser imports
no pid, plant or tuning code (start-up: ``bench/README.md``, issue 38)."""

from __future__ import annotations

from typing import Any

from wavecheck.output import figure_file
from wavecheck.units import number_option

__all__ = [
    "GAIN_OPTIONS",
    "SERVO_OPTIONS",
    "add_pid_arguments",
    "add_servo_arguments",
    "add_servo_loop_arguments",
]

#: option dest → PidGains field.
GAIN_OPTIONS = {
    "pgain": "Pgain",
    "igain": "Igain",
    "dgain": "Dgain",
    "bias": "bias",
    "ff0": "FF0",
    "ff1": "FF1",
    "ff2": "FF2",
    "ff3": "FF3",
    "deadband": "deadband",
    "maxerror": "maxerror",
    "maxerror_i": "maxerrorI",
    "maxerror_d": "maxerrorD",
    "maxcmd_d": "maxcmdD",
    "maxcmd_dd": "maxcmdDD",
    "maxcmd_ddd": "maxcmdDDD",
    "maxoutput": "maxoutput",
}
#: option dest → ServoParams field.
SERVO_OPTIONS = {
    "inertia": "inertia",
    "viscous": "viscous",
    "torque_constant": "torque_constant",
    "coulomb": "coulomb",
    "load": "load",
    "encoder_counts": "counts_per_unit",
    "amp_limit": "amp_limit",
}


def add_pid_arguments(group: Any) -> None:
    """pid's pins as options (LinuxCNC names; unset = the component's or the files' value)."""
    for dest, pin in GAIN_OPTIONS.items():
        group.add_argument(
            "--" + dest.replace("_", "-"), dest=dest, type=number_option, help=f"pid.N.{pin}"
        )
    group.add_argument(
        "--no-error-previous-target",
        dest="error_previous_target",
        action="store_false",
        default=True,
        help="pid.N.error-previous-target FALSE (default TRUE, as LinuxCNC)",
    )


def add_servo_arguments(group: Any) -> None:
    """The servo plant's options (``--plant servo``)."""
    from stepgen.plant import ServoParams

    d = ServoParams()
    group.add_argument("--inertia", type=number_option, default=d.inertia, help="J, F·s²/unit")
    group.add_argument("--viscous", type=number_option, default=d.viscous, help="B, F·s/unit")
    group.add_argument(
        "--torque-constant",
        type=number_option,
        default=d.torque_constant,
        help="Kt, F per amp unit",
    )
    group.add_argument("--coulomb", type=number_option, default=0.0, help="Coulomb friction, F")
    group.add_argument(
        "--load", type=number_option, default=0.0, help="constant load, F (e.g. gravity)"
    )
    group.add_argument(
        "--encoder-counts",
        type=number_option,
        default=0.0,
        help="encoder counts per unit (0 = exact)",
    )
    group.add_argument(
        "--amp-limit", type=number_option, default=0.0, help="amplifier limit (0 = none)"
    )


def add_servo_loop_arguments(parser: Any) -> None:
    """The ``--pid`` option group of ``stepgen simulate``."""
    g = parser.add_argument_group(
        "closed loop (--pid: LinuxCNC's pid between the command and the plant)"
    )
    g.add_argument("--pid", action="store_true", help="close the loop with pid (see stepgen tune)")
    g.add_argument(
        "--plant",
        choices=("stepgen", "servo"),
        default="stepgen",
        help="stepgen: pid.output → stepgen velocity-cmd (default; unset gains are pncconf's "
        "P = 1/servo period, FF1 = 1); servo: pid.output → amplifier of a motor and load",
    )
    add_pid_arguments(g)
    g.add_argument("--ferror", type=number_option, help="[JOINT_n]FERROR (default 1.0)")
    g.add_argument("--min-ferror", type=number_option, help="[JOINT_n]MIN_FERROR (default FERROR)")
    g.add_argument(
        "--joint-max-velocity", type=number_option, help="[JOINT_n]MAX_VELOCITY (FERROR scaling)"
    )
    g.add_argument(
        "--plot",
        type=figure_file,
        help="command, feedback, following error (PNG; .jpg, .svg or .pdf by the file's name)",
    )
    add_servo_arguments(parser.add_argument_group("servo plant (--pid --plant servo)"))
