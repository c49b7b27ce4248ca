"""``wavecheck config FILE --drive ID [--drive AXIS=ID]``: can this firmware configuration meet
the drive? No capture needed.

FILE is a grbl/grblHAL/Grbl_ESP32 ``$$`` dump, a Klipper ``printer.cfg``, a Marlin
``Configuration.h`` (its ``Configuration_adv.h`` is read beside it), a RepRapFirmware ``config.g``,
a Smoothieware ``config``, a FluidNC ``config.yaml``, or a LinuxCNC INI (software stepgen or Mesa
hm2 stepgen, decided by what its HALFILEs load) or HAL file, with the INI as a second file. The
format is detected by content (``--firmware-format`` forces it). For every axis and every rule:
the generator's guaranteed figure, the drive's limit, the margin, pass/fail, the max step rate the
pair allows and the setting to change. Exit 0 all pass, 1 a rule fails, 3 something cannot be
proven from the configuration (measure it), 4 a rule ``--require`` asks for was not decided, 2
unusable input.

The options it shares with other commands: :mod:`wavecheck.cli._firmware_args` and
:mod:`wavecheck.cli._tuning_args`.
"""

from __future__ import annotations

import argparse
import sys
from typing import TYPE_CHECKING, Any

from wavecheck.cli._firmware_args import add_firmware_arguments, read_firmware_args
from wavecheck.cli._formats import Formats, json_text, lazy
from wavecheck.cli._tuning_args import add_tuning_arguments
from wavecheck.drives.datasheet import Drive
from wavecheck.drives.library import load_drive
from wavecheck.drives.overrides import tune_drive
from wavecheck.errors import UsageError
from wavecheck.firmware.guarantee import FirmwareConfig
from wavecheck.output import atomic_write, output_file
from wavecheck.rules import RULE_IDS
from wavecheck.verdict import (
    check_require,
    require_list,
    required_exit_code,
    required_line,
    unmet_requirements,
)

if TYPE_CHECKING:  # imported where used: only with a firmware configuration
    pass

__all__ = [
    "register",
    "run",
]


def register(sub: Any) -> None:
    """Add the ``config`` subcommand."""
    p = sub.add_parser(
        "config",
        description=__doc__.split("\n\n")[0] if __doc__ else None,
    )
    p.add_argument("file", metavar="FILE", help="the firmware configuration file")
    p.add_argument(
        "ini",
        metavar="INI",
        nargs="?",
        help="LinuxCNC: the INI that runs FILE, a HAL file (either order; default: the INI "
        "beside FILE whose HALFILE names it)",
    )
    p.add_argument(
        "--drive",
        action="append",
        required=True,
        metavar="ID|FILE|AXIS=ID",
        help="the drive of every axis, or AXIS=ID for one axis (repeatable)",
    )
    add_tuning_arguments(p)
    add_firmware_arguments(p, positional=True)
    p.add_argument("--latency", metavar="J", help="LinuxCNC: worst base-thread latency (e.g. 11us)")
    FORMATS.add_argument(p)
    p.add_argument(
        "-o", "--output", type=output_file, metavar="FILE", help="write the report to FILE"
    )
    p.intermixed = True  # LinuxCNC's INI may follow the options
    p.set_defaults(func=run)


_REPORT = "wavecheck.report.firmware"  # loaded when a report is written
#: ``--format``: text, JSON, or JUnit (one test case per axis and rule, for CI).
FORMATS = Formats(
    {
        "text": lazy(_REPORT, "config_text"),
        "json": json_text(lazy(_REPORT, "config_dict")),
        "junit": lazy(_REPORT, "config_junit"),
    },
    help="report format (junit: one test case per axis and rule, for CI)",
)


def _drives(args: argparse.Namespace, cfg: FirmwareConfig) -> list[tuple[str, Drive]]:
    default: Drive | None = None
    per_axis: dict[str, Drive] = {}
    for text in args.drive:
        axis, sep, ident = text.partition("=")
        drive = tune_drive(load_drive(ident if sep else text), args.limit, args.margin)
        if sep:
            found = cfg.find(axis)
            if found is None:
                raise UsageError(
                    f"--drive {text}: no axis {axis!r} in {cfg.path} "
                    f"(axes: {', '.join(cfg.axis_names)})"
                )
            per_axis[found.axis] = drive
        elif default is None:
            default = drive
        else:
            raise UsageError("--drive: give one drive for every axis, the others as AXIS=ID")
    out = []
    for a in cfg.axis_names:
        d = per_axis.get(a, default)
        if d is not None:
            out.append((a, d))
    return out


def run(args: argparse.Namespace) -> int:
    """Run ``wavecheck config``; returns the exit code."""
    from wavecheck.firmware.evaluate import evaluate_config

    require = require_list(args.require)
    check_require(require, RULE_IDS)
    cfg = read_firmware_args(args, args.file, args.ini)
    result = evaluate_config(cfg, [(cfg.axis(a), d) for a, d in _drives(args, cfg)])
    if not result.pairs:
        raise UsageError("no axis has a drive: give --drive ID or --drive AXIS=ID")
    unmet = unmet_requirements(result.statuses, require)
    text = FORMATS.render(args.format, result, require)
    if args.output:
        atomic_write(args.output, text)
        print(
            f"{result.verdict_line}: {len(result.pairs)} axis/drive pair(s); report written to "
            f"{args.output}"
        )
        if unmet:
            print(required_line(unmet, result.statuses))
    else:
        sys.stdout.write(text)
    return required_exit_code(result.exit_code, unmet)
