"""``wavecheck config FILE --drive ID [--drive AXIS=ID]``: can this firmware configuration meet
the drive? No capture needed.

FILE is a grbl/grblHAL/Grbl_ESP32 ``$$`` dump, a Klipper ``printer.cfg``, a Marlin
``Configuration.h`` (its ``Configuration_adv.h`` is read beside it), a RepRapFirmware ``config.g``,
a Smoothieware ``config``, a FluidNC ``config.yaml``, or a LinuxCNC INI (software stepgen or Mesa
hm2 stepgen, decided by what its HALFILEs load). The
format is detected by content (``--firmware-format`` forces it). For every axis and every rule:
the generator's guaranteed figure, the drive's limit, the margin, pass/fail, the max step rate the
pair allows and the setting to change. Exit 0 all pass, 1 a rule fails, 3 something cannot be
proven from the configuration (measure it), 4 a rule ``--require`` asks for was not decided, 2
unusable input.

Also here: the options ``check`` shares (``--firmware``, ``--firmware-axis``, ``--limit``,
``--margin``) and :func:`check_firmware`, which ``check --firmware`` runs on each report and
``measure --firmware`` on each axis (pairing: :mod:`wavecheck.firmware.pairing`).
"""

from __future__ import annotations

import argparse
import json
import sys
from typing import TYPE_CHECKING, Any

from wavecheck.drives.datasheet import Drive
from wavecheck.drives.library import load_drive
from wavecheck.drives.overrides import tune_drive
from wavecheck.errors import UsageError
from wavecheck.firmware import FIRMWARES, read_firmware
from wavecheck.firmware.guarantee import FirmwareConfig
from wavecheck.output import atomic_write, output_file
from wavecheck.rules import RULE_IDS
from wavecheck.units import parse_frequency, time_ns
from wavecheck.verdict import (
    check_require,
    require_list,
    required_exit_code,
    required_line,
    unmet_requirements,
)

if TYPE_CHECKING:  # imported where used: only with a firmware configuration
    from wavecheck.firmware.capture import FirmwareCheck

__all__ = [
    "add_firmware_arguments",
    "add_limit_arguments",
    "add_tuning_arguments",
    "check_firmware",
    "register",
    "run",
]


def add_limit_arguments(p: argparse.ArgumentParser) -> None:
    """``--limit RULE=VALUE`` (repeatable) and ``--margin 2x|+500ns``: the drive's figures as
    the user changes them (:func:`wavecheck.drives.overrides.tune_drive`; ``stepgen plan`` too)."""
    p.add_argument(
        "--limit",
        action="append",
        default=[],
        metavar="RULE=VALUE",
        help="override one drive figure (step_high=5us, max_rate=100kHz; repeatable); the "
        "report shows the datasheet figure beside it",
    )
    p.add_argument(
        "--margin",
        metavar="2x|+500ns",
        help="tighten every datasheet figure: a factor (2x, as StepConf advises for 3.3 V "
        "parallel ports) or an added time (+500ns); --limit figures are taken as given",
    )


def add_tuning_arguments(p: argparse.ArgumentParser) -> None:
    """:func:`add_limit_arguments` and ``--require RULES|all`` (which rules must be decided)."""
    add_limit_arguments(p)
    p.add_argument(
        "--require",
        action="append",
        default=[],
        metavar="RULES|all",
        help="rules that must be decided (comma-separated; all: every rule the drive gives a "
        "figure for): one not checked or indeterminate makes the run exit 4, with a line "
        "saying why (repeatable)",
    )


def add_firmware_arguments(p: argparse.ArgumentParser, *, positional: bool = False) -> None:
    """``--firmware FILE`` (unless ``positional``), ``--firmware-format``, ``--axis``,
    ``--hm2-clock``; LinuxCNC's ``--latency`` comes from the stepgen options where present."""
    if not positional:
        p.add_argument(
            "--firmware",
            metavar="FILE",
            help="the firmware configuration that made the capture: a capture violating its "
            "own configuration is reported apart from the drive rules",
        )
        p.add_argument(
            "--axis",
            metavar="NAME",
            help="the axis of --firmware FILE a single unnamed capture axis is (default: the "
            "only or the first; the report says which)",
        )
        p.add_argument(
            "--firmware-axis",
            action="append",
            default=[],
            metavar="CAPTURE=FIRMWARE",
            help="pair a capture axis with a firmware axis of another name (y=beta, "
            "x=stepper_x; repeatable); otherwise axes pair by name",
        )
    p.add_argument(
        "--firmware-format",
        choices=FIRMWARES,
        help="the firmware (default: detected from the content)",
    )
    p.add_argument(
        "--hm2-clock", metavar="F", help="Mesa stepgen clock (e.g. 33MHz) for exact rounding"
    )


def _read(args: argparse.Namespace, path: str) -> FirmwareConfig:
    j = getattr(args, "latency", None)
    clock = getattr(args, "hm2_clock", None)
    return read_firmware(
        path,
        args.firmware_format,
        latency_ns=time_ns(j) if j else None,
        clock_hz=parse_frequency(clock) if clock else None,
    )


def check_firmware(args: argparse.Namespace, subject: Any) -> FirmwareCheck:
    """``check --firmware`` / ``measure --firmware``: one capture axis (a Report or an
    :class:`~wavecheck.firmware.capture.Observed`) against its firmware axis."""
    from wavecheck.firmware.capture import Observed, firmware_check
    from wavecheck.firmware.pairing import pair_axis, parse_pairs

    cached = getattr(args, "_firmware_config", None)
    cfg: FirmwareConfig = cached if cached is not None else _read(args, args.firmware)
    args._firmware_config = cfg
    name = subject.axis_name if isinstance(subject, Observed) else subject.axis
    pairing = pair_axis(cfg, name, parse_pairs(getattr(args, "firmware_axis", []) or []),
                        getattr(args, "axis", None))  # fmt: skip
    return firmware_check(subject, cfg, pairing.axis, str(pairing))


def register(sub: Any) -> None:
    """Add the ``config`` subcommand."""
    p = sub.add_parser(
        "config",
        description=__doc__.split("\n\n")[0] if __doc__ else None,
    )
    p.add_argument("file", metavar="FILE", help="the firmware configuration file")
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
    p.add_argument(
        "--format",
        choices=("text", "json", "junit"),
        default="text",
        help="report format (junit: one test case per axis and rule, for CI)",
    )
    p.add_argument(
        "-o", "--output", type=output_file, metavar="FILE", help="write the report to FILE"
    )
    p.set_defaults(func=run)


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
    from wavecheck.report.firmware import config_dict, config_junit, config_text

    require = require_list(args.require)
    check_require(require, RULE_IDS)
    cfg = _read(args, args.file)
    result = evaluate_config(cfg, [(cfg.axis(a), d) for a, d in _drives(args, cfg)])
    if not result.pairs:
        raise UsageError("no axis has a drive: give --drive ID or --drive AXIS=ID")
    unmet = unmet_requirements(result.statuses, require)
    if args.format == "json":
        text = json.dumps(config_dict(result, require), indent=2, ensure_ascii=False) + "\n"
    elif args.format == "junit":
        text = config_junit(result, require)
    else:
        text = config_text(result, require)
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
