"""``wavecheck check CAPTURE --drive ID|FILE``: check every edge against a drive's datasheet.

Exit codes: 0 pass, 1 a rule failed, 3 only indeterminate results (or nothing checkable), 2
unusable input or usage (one line, no traceback).

The command is a thin layer: options → :func:`wavecheck.engine.run_check` → a renderer. New
outputs register in :data:`RENDERERS` (``--format``); extra side outputs (plots, HTML, GTKWave
files) can be added as options handled in :func:`write_outputs`.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable
from typing import Any

from wavecheck.cli._capture_args import (
    add_capture_arguments,
    capture_from_args,
    resolution_from_args,
)
from wavecheck.cli._reports import (
    add_report_arguments,
    latency_ns,
    render_json_report,
    render_junit_report,
    render_text_report,
    run_checks,
    stepgen_config,
)
from wavecheck.cli.config import add_firmware_arguments, add_tuning_arguments, check_firmware
from wavecheck.drives.library import load_drive
from wavecheck.drives.tune import tune_drive
from wavecheck.engine import run_check
from wavecheck.errors import UsageError
from wavecheck.interface import parse_map
from wavecheck.output import atomic_write, output_file
from wavecheck.report.json import DEFAULT_VIOLATION_CAP
from wavecheck.report.model import Report
from wavecheck.report.text import DEFAULT_TEXT_VIOLATIONS

__all__ = ["RENDERERS", "build_report", "register", "run", "write_outputs"]

#: ``--format`` name → renderer(report, args) → text.
RENDERERS: dict[str, Callable[[Report, argparse.Namespace], str]] = {
    # text/json: the plain renderers, plus the stepgen configuration's rates when --ini/--hal
    "text": render_text_report,
    "json": render_json_report,
    "junit": render_junit_report,
}


def register(sub: Any) -> None:
    """Add the ``check`` subcommand."""
    p = sub.add_parser(
        "check",
        help="check every edge of a capture against a drive's timing rules",
        description="Check every STEP/DIR edge of CAPTURE against a drive's datasheet timing. "
        "Exit 0 pass, 1 a rule failed, 3 only indeterminate, 2 unusable input.",
    )
    p.add_argument(
        "capture",
        metavar="CAPTURE",
        nargs="+",
        help="the capture(s) (.sr, .vcd, or a sigrok-cli format); several files and glob "
        "patterns ('runs/*.sr') give a summary line each and the worst exit code",
    )
    p.add_argument(
        "--drive", required=True, metavar="ID|FILE", help="drive id from rules/ or a TOML file"
    )
    p.add_argument(
        "--map",
        action="append",
        default=[],
        metavar="ROLE=CH",
        help="map roles to channels by name, index or the end of a hierarchical name "
        "(step=STEP,dir=3, step=s2.step; repeatable); each role and each channel once; channels "
        "named after a role (STEP, dir, stepgen.0.phase-A) are mapped by default",
    )
    p.add_argument(
        "--invert", action="append", default=[], metavar="ROLE", help="invert a role (repeatable)"
    )
    p.add_argument(
        "--type",
        type=int,
        default=None,
        metavar="N",
        help="LinuxCNC step type 0..15 (default: the drive's; 0 step/dir)",
    )
    p.add_argument(
        "--user-step-type",
        metavar="V,V,...",
        help="state table for --type 15 (LinuxCNC user_step_type=, phase A = bit 0)",
    )
    p.add_argument(
        "--dir-forward",
        choices=("low", "high"),
        default="low",
        help="DIR level that means forward (default low: LinuxCNC and grbl drive DIR high for "
        "negative moves)",
    )
    p.add_argument(
        "--pulse-level",
        choices=("high", "low"),
        default="high",
        help="level of the generator's step pulses at its output (default high, as LinuxCNC, "
        "grbl, Marlin, Klipper and Smoothieware make them; --invert step says the drive sees "
        "the other level)",
    )
    p.add_argument(
        "--active-edge",
        choices=("rising", "falling", "both"),
        help="override the drive's active STEP edge",
    )
    add_tuning_arguments(p)
    add_firmware_arguments(p)
    add_capture_arguments(p)
    p.add_argument("--format", choices=sorted(RENDERERS), default="text", help="report format")
    p.add_argument(  # output_file: checked before any work (wavecheck.output)
        "-o", "--output", type=output_file, metavar="FILE", help="write the report to FILE"
    )
    p.add_argument(
        "--max-violations",
        type=int,
        default=None,
        metavar="N",
        help=f"violations listed (text default {DEFAULT_TEXT_VIOLATIONS}, "
        f"JSON default {DEFAULT_VIOLATION_CAP}); the total is always given",
    )
    add_report_arguments(p)
    p.set_defaults(func=run)


def _user_table(text: str | None) -> tuple[int, ...] | None:
    if not text:
        return None
    try:
        return tuple(int(v, 0) for v in text.replace(" ", "").split(",") if v)
    except ValueError:
        raise UsageError(
            f"--user-step-type {text!r} is not a list of integers (e.g. --user-step-type 1,3,2,0)"
        ) from None


def build_report(args: argparse.Namespace, path: str) -> Report:
    """Read ``path`` and the drive named in ``args`` and check it (no output)."""
    if args.max_violations is not None and args.max_violations < 0:
        raise UsageError(f"--max-violations must be 0 or more, got {args.max_violations}")
    drive = tune_drive(load_drive(args.drive), args.limit, args.margin)
    capture = capture_from_args(args, path, resolution=False)
    report = run_check(
        capture,
        drive,
        parse_map(args.map),
        args.invert,
        args.type,
        resolution_from_args(args),  # exact, a fraction of a tick included
        forward_level=1 if args.dir_forward == "high" else 0,
        active_edge=args.active_edge,
        user_table=_user_table(args.user_step_type),
        stepgen=stepgen_config(args),
        pulse_level=1 if args.pulse_level == "high" else 0,
        latency_ns=latency_ns(args),
    )
    if args.firmware:  # the capture against its own firmware configuration
        report.firmware = check_firmware(args, report)
    return report


def write_outputs(args: argparse.Namespace, report: Report) -> None:
    """Render ``report`` in ``--format`` to ``-o`` FILE (a one-line summary on stdout) or stdout."""
    text = RENDERERS[args.format](report, args)
    if args.output:
        atomic_write(args.output, text)
        print(
            f"{report.verdict}: {report.total_violations} violation(s), {report.steps.count} steps; "
            f"report written to {args.output}"
        )
    else:
        sys.stdout.write(text)


def run(args: argparse.Namespace) -> int:
    """Run ``wavecheck check``; returns the exit code."""
    return run_checks(args, build_report, write_outputs)
