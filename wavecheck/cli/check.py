"""``wavecheck check CAPTURE --drive ID|FILE``: check every edge against a drive's datasheet.

Exit codes: 0 pass, 1 a rule failed, 3 only indeterminate results (or nothing checkable), 4 a
rule ``--require`` asks for was not decided (unchecked or indeterminate), 2 unusable input or
usage (one line, no traceback).

The command is a thin layer: options → :func:`wavecheck.engine.run.check_source` → a renderer. New
outputs register in :data:`RENDERERS` (``--format``); extra side outputs (plots, HTML, GTKWave
files) can be added as options handled in :func:`write_outputs`.
"""

from __future__ import annotations

import argparse
import shlex
import sys
from collections.abc import Callable
from typing import Any

from wavecheck.cli._axis_args import (
    add_axis_arguments,
    add_engine_arguments,
    check_options,
    required,
)
from wavecheck.cli._capture_args import add_capture_arguments, source_from_args
from wavecheck.cli._reports import (
    Checked,
    add_report_arguments,
    axis_reports,
    expand_captures,
    render_json_report,
    render_junit_report,
    render_text_report,
    run_checks,
)
from wavecheck.cli._steps_args import (
    add_steps_arguments,
    check_steps_arguments,
    steps_csv_path,
    steps_writer,
)
from wavecheck.cli.config import add_firmware_arguments, add_tuning_arguments, check_firmware
from wavecheck.engine import MachineReport, check_source, start
from wavecheck.errors import UsageError
from wavecheck.output import atomic_write, output_file
from wavecheck.report.json import DEFAULT_VIOLATION_CAP
from wavecheck.report.text import DEFAULT_TEXT_VIOLATIONS
from wavecheck.sigrok.session import add_pulseview_argument, check_pulseview

__all__ = [
    "RENDERERS",
    "build_report",
    "finish_report",
    "register",
    "run",
    "write_outputs",
]

#: ``--format`` name → renderer(report, args) → text.
RENDERERS: dict[str, Callable[[Checked, argparse.Namespace], str]] = {
    # text/json: the plain renderers, plus the stepgen configuration's rates when --ini/--hal
    "text": render_text_report,
    "json": render_json_report,
    "junit": render_junit_report,
}


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
    add_pulseview_argument(p)
    add_steps_arguments(p)
    add_engine_arguments(p)
    p.set_defaults(func=run)


def finish_report(args: argparse.Namespace, machine: MachineReport) -> Checked:
    """Add ``--firmware`` findings; a single unnamed axis as its Report."""
    for report in machine.axes:
        if getattr(args, "firmware", None):  # the capture against its own firmware settings
            report.firmware = check_firmware(args, report)
    if len(machine.axes) == 1 and machine.axes[0].axis is None:
        return machine.axes[0]
    return machine


def build_report(args: argparse.Namespace, path: str, steps_csv: str | None = None) -> Checked:
    """Read ``path`` once and check every axis of ``args`` against its drive (and write the
    steps to ``steps_csv`` as they are decoded)."""
    if args.max_violations is not None and args.max_violations < 0:
        raise UsageError(f"--max-violations must be 0 or more, got {args.max_violations}")
    options = check_options(args)
    source = source_from_args(args, path)
    if steps_csv is None:
        return finish_report(args, check_source(source, options))
    writer, sinks = steps_writer(args, steps_csv, source)
    try:
        machine, blocks = start(source, options, step_sinks=sinks)
        for block in blocks:
            machine.feed(block)
            writer.settled(machine.settled(block.end))
        checked = finish_report(args, machine.finish(source.capture()))
    except BaseException:
        writer.abort()
        raise
    writer.close()
    return checked


def write_outputs(args: argparse.Namespace, report: Checked) -> None:
    """Render ``report`` in ``--format`` to ``-o`` FILE (a one-line summary on stdout) or stdout."""
    if getattr(args, "pulseview", None):  # issue 28: the decoder stacked in a PulseView session
        from wavecheck.sigrok.session import write_pulseview

        for line in write_pulseview(args, axis_reports(report)):
            print(line, file=sys.stderr)
    text = RENDERERS[args.format](report, args)
    if args.output:
        from wavecheck.report.claims import requirement_line, verdict_line

        atomic_write(args.output, text)
        if getattr(args, "quiet", False):  # -q: the report file only
            return
        steps = sum(r.steps.count for r in axis_reports(report))
        print(
            f"{verdict_line(report)}: {report.total_violations} violation(s), {steps} steps; "
            f"report written to {args.output}"
        )
        missing = requirement_line(report, required(args))
        if missing:
            print(missing)
    else:
        sys.stdout.write(text)


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

    def build_and_export(a: argparse.Namespace, path: str) -> Checked:
        """:func:`build_report`, the capture's steps written to ``--steps-csv`` meanwhile."""
        target = steps_csv_path(a.steps_csv, path, used) if several else a.steps_csv
        return build_report(a, path, target)

    return run_checks(args, build_and_export, write_outputs)
