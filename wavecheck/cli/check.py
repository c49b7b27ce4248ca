"""``wavecheck check CAPTURE --drive ID|FILE``: check every edge against a drive's datasheet.

Exit codes: 0 pass, 1 a rule failed, 3 only indeterminate results (or nothing checkable), 4 a
rule ``--require`` asks for was not decided (unchecked or indeterminate), 2 unusable input or
usage (one line, no traceback).

The command is a thin layer: options → :func:`wavecheck.engine.check_source` → a renderer. New
outputs register in :data:`wavecheck.cli._formats.FORMATS` (``--format``); extra side outputs
(plots, HTML, GTKWave files) are options handled in :func:`wavecheck.cli._reports.write_outputs`.
"""

from __future__ import annotations

import argparse
import sys
from typing import Any

from wavecheck.cli._axis_args import (
    add_axis_arguments,
    add_engine_arguments,
)
from wavecheck.cli._batch import expand_captures, run_checks
from wavecheck.cli._capture_args import add_capture_arguments
from wavecheck.cli._check_flow import build_report
from wavecheck.cli._firmware_args import add_firmware_arguments
from wavecheck.cli._formats import FORMATS, Checked
from wavecheck.cli._pulseview_args import add_pulseview_argument, check_pulseview
from wavecheck.cli._reports import Asked, add_report_arguments, write_outputs
from wavecheck.cli._steps_args import (
    add_steps_arguments,
    check_steps_arguments,
    steps_csv_path,
)
from wavecheck.cli._tuning_args import add_tuning_arguments
from wavecheck.errors import UsageError
from wavecheck.output import output_file
from wavecheck.report.json import DEFAULT_VIOLATION_CAP
from wavecheck.report.text import DEFAULT_TEXT_VIOLATIONS

__all__ = [
    "build_report",
    "register",
    "run",
]


def register(sub: Any) -> None:
    """Add the ``check`` subcommand."""
    p = sub.add_parser(
        "check",
        description="Check every STEP/DIR edge of CAPTURE against a drive's datasheet timing. "
        "Exit 0 pass, 1 a rule failed, 3 only indeterminate, 4 a rule --require asks for was "
        "not decided, 2 unusable input.",
    )
    p.add_argument(
        "capture",
        metavar="CAPTURE",
        nargs="+",
        help="the capture(s) (.sr, .vcd, or a sigrok-cli format); several files and glob "
        "patterns ('runs/*.sr') give a summary line each and the worst exit code",
    )
    p.add_argument(
        "--drive",
        action="append",
        metavar="ID|FILE|AXIS=ID",
        help="drive id from rules/ or a TOML file; AXIS=ID gives one axis its own drive "
        "(repeatable: --drive x=gecko-g202 --drive y=leadshine-dm542). Required, except for "
        "a snippet written by wavecheck watch --snippets: it carries its drive, map and step "
        "type, and options given here override them",
    )
    add_axis_arguments(p)
    add_tuning_arguments(p)
    add_firmware_arguments(p)
    add_capture_arguments(p)
    p.add_argument("--format", choices=sorted(FORMATS), default="text", help="report format")
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
    add_pulseview_argument(p)
    add_steps_arguments(p)
    add_engine_arguments(p)
    p.set_defaults(func=run)


class _Refusing(argparse.ArgumentParser):
    """A parser whose errors are UsageErrors (for the options a snippet carries)."""

    def error(self, message: str) -> None:  # type: ignore[override]
        raise UsageError(message)


def _stored_settings(args: argparse.Namespace) -> None:
    """Without ``--drive``: take the options the captures carry (snippets of ``wavecheck watch
    --snippets``; :func:`wavecheck.live.snippets.stored_arguments`) where none was given.

    Raises:
        UsageError: a capture carries none, or they carry different ones.
    """
    from wavecheck.live.snippets import stored_arguments

    patterns = args.capture if isinstance(args.capture, list) else [args.capture]
    paths = expand_captures(patterns)
    found = {tuple(stored_arguments(p) or ()) for p in paths}
    stored = next(iter(found)) if len(found) == 1 else ()
    if not stored:
        raise UsageError(
            "the following arguments are required: --drive (only a snippet written by "
            "wavecheck watch --snippets carries its own"
            + (", and these captures carry different ones)" if len(found) > 1 else ")")
        )
    parser = _Refusing(prog="wavecheck")
    sub = parser.add_subparsers(parser_class=_Refusing)
    register(sub)
    try:
        given = parser.parse_args(["check", paths[0], *stored])
    except UsageError as err:
        raise UsageError(f"{paths[0]}: the check options it carries: {err}") from None
    for key, value in vars(given).items():  # an option given on the command line wins
        if key != "capture" and getattr(args, key, None) == sub.choices["check"].get_default(key):
            setattr(args, key, value)
    import shlex  # for the message only: not at every start

    print(
        f"wavecheck: {paths[0]}: checked with the options it carries: {shlex.join(stored)}",
        file=sys.stderr,
    )


def run(args: argparse.Namespace) -> int:
    """Run ``wavecheck check``; returns the exit code."""
    if not args.drive:
        _stored_settings(args)
    check_steps_arguments(args)
    if getattr(args, "pulseview", None):  # issue 28: one capture, one PulseView session
        check_pulseview(args, len(expand_captures(args.capture)))
    if not args.steps_csv:
        return run_checks(args, build_report, write_outputs)
    patterns = args.capture if isinstance(args.capture, list) else [args.capture]
    several = len(expand_captures(patterns)) > 1
    used: set[str] = set()

    def build_and_export(a: argparse.Namespace, what: Asked, path: str) -> Checked:
        """:func:`build_report`, the capture's steps written to ``--steps-csv`` meanwhile."""
        target = steps_csv_path(a.steps_csv, path, used) if several else a.steps_csv
        return build_report(a, what, path, target)

    return run_checks(args, build_and_export, write_outputs)
