"""``wavecheck check CAPTURE --drive ID|FILE``: check every edge against a drive's datasheet.

Exit codes: 0 pass, 1 a rule failed, 3 only indeterminate results (or nothing checkable), 2
unusable input or usage (one line, no traceback).

The command is a thin layer: options → :func:`wavecheck.engine.run_check` → a renderer. New
outputs register in :data:`RENDERERS` (``--format``); extra side outputs (plots, HTML, GTKWave
files) can be added as options handled in :func:`write_outputs`.
"""

from __future__ import annotations

import argparse
import shlex
import sys
from collections.abc import Callable
from dataclasses import dataclass
from fractions import Fraction
from typing import Any

from wavecheck.axes import AxisMap
from wavecheck.capture.model import Capture
from wavecheck.cli._axis_args import (
    add_axis_arguments,
    axis_runs,
    pulse_level,
    roles_from_waveforms,
    user_table,
)
from wavecheck.cli._capture_args import (
    add_capture_arguments,
    capture_from_args,
    resolution_from_args,
)
from wavecheck.cli._reports import (
    Checked,
    add_report_arguments,
    axis_reports,
    expand_captures,
    latency_ns,
    render_json_report,
    render_junit_report,
    render_text_report,
    run_checks,
    stepgen_config,
)
from wavecheck.cli._steps_args import (
    add_steps_arguments,
    check_steps_arguments,
    steps_csv_path,
    write_steps,
)
from wavecheck.cli.config import add_firmware_arguments, add_tuning_arguments, check_firmware
from wavecheck.drives.library import load_drive
from wavecheck.drives.model import Drive
from wavecheck.drives.tune import tune_drive
from wavecheck.engine import check_machine
from wavecheck.errors import UsageError
from wavecheck.output import atomic_write, output_file
from wavecheck.report.json import DEFAULT_VIOLATION_CAP
from wavecheck.report.machine import MachineReport
from wavecheck.report.steps_csv import AxisSteps
from wavecheck.report.text import DEFAULT_TEXT_VIOLATIONS
from wavecheck.stream.blocks import BlockSource, open_stream
from wavecheck.stream.engine import DEFAULT_BLOCK_EDGES, NotStreamable, check_stream

__all__ = [
    "RENDERERS",
    "CheckSetup",
    "build_report",
    "check_setup",
    "finish_report",
    "kept_violations",
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
    add_steps_arguments(p)
    p.add_argument(
        "--block-edges",
        type=int,
        default=None,
        metavar="N",
        help="check a .sr or VCD block by block, about N edges at a time (memory follows N, "
        "not the capture's length; default 262144)",
    )
    p.add_argument(
        "--no-stream",
        action="store_true",
        help="read the whole capture into memory first (the reference path; --steps-csv and "
        "--firmware always do; a streamed --plot, --gtkw or --html draws the signals from small "
        "windows kept around the worst places)",
    )
    p.set_defaults(func=run)


def _stream_source(args: argparse.Namespace, path: str) -> BlockSource | None:
    """A block reader for ``path`` when this check can be streamed (module
    :mod:`wavecheck.stream`), else None: read whole."""
    whole_only = ("steps_csv", "firmware", "no_stream")  # they need every step
    if any(getattr(args, k, None) for k in whole_only):
        return None
    if args.block_edges is not None and args.block_edges < 1:
        raise UsageError(f"--block-edges must be 1 or more, got {args.block_edges}")
    from wavecheck.cli._capture_args import samplerate_from_args

    source = open_stream(
        path,
        samplerate=samplerate_from_args(args),
        input_format=getattr(args, "input_format", None),
    )
    if source is None or not roles_from_waveforms(args, source.skeleton):
        return source
    return None  # the roles come from the waveforms: read whole


@dataclass
class CheckSetup:
    """What ``check``'s options say about a capture: the axes, their drives and the engine's
    keyword arguments (:func:`wavecheck.engine.check_machine`), and notes on how the roles were
    found."""

    axes: list[AxisMap]
    drives: dict[str | None, Drive]
    options: dict[str, Any]
    resolution: Fraction | None
    found: list[str]


def check_setup(args: argparse.Namespace, capture: Capture) -> CheckSetup:
    """Resolve ``args``' axes, drives (each loaded once, tuned by ``--limit``/``--margin``) and
    options against ``capture`` (its channels; the edges are not needed)."""
    runs, found = axis_runs(args, capture)
    loaded: dict[str, Drive] = {}
    for axis in runs:
        if axis.drive is None:  # check's --drive is required; axis_runs gives every axis one
            raise UsageError(f"--drive: axis {axis.name} has no drive")
        if axis.drive not in loaded:
            loaded[axis.drive] = tune_drive(load_drive(axis.drive), args.limit, args.margin)
    options: dict[str, Any] = {
        "step_types": {a.name: a.step_type for a in runs if a.step_type is not None},
        "forward_levels": {a.name: a.forward_level for a in runs},
        "invert": {a.name: a.invert for a in runs},
        "active_edge": args.active_edge,
        "user_table": user_table(args),
        "stepgen": stepgen_config(args),
        "pulse_level": pulse_level(args),
        "latency_ns": latency_ns(args),
    }
    return CheckSetup(
        [AxisMap(a.name, a.roles) for a in runs],
        {a.name: loaded[a.drive] for a in runs if a.drive is not None},
        options,
        resolution_from_args(args),  # exact, a fraction of a tick included
        found,
    )


def finish_report(args: argparse.Namespace, machine: MachineReport, found: list[str]) -> Checked:
    """Add ``--firmware`` findings and the role notes; a single unnamed axis as its Report."""
    for report in machine.axes:
        if getattr(args, "firmware", None):  # the capture against its own firmware settings
            report.firmware = check_firmware(args, report)
        report.notes[:0] = found
    if len(machine.axes) == 1 and machine.axes[0].axis is None:
        return machine.axes[0]
    return machine


def build_report(args: argparse.Namespace, path: str) -> Checked:
    """Read ``path`` once and check every axis of ``args`` against its drive (no output)."""
    if args.max_violations is not None and args.max_violations < 0:
        raise UsageError(f"--max-violations must be 0 or more, got {args.max_violations}")
    source = _stream_source(args, path)
    capture = (
        source.skeleton if source is not None else capture_from_args(args, path, resolution=False)
    )
    setup = check_setup(args, capture)
    machine = None
    if source is not None:
        try:
            machine = check_stream(
                source, setup.axes, setup.drives, setup.resolution,
                keep_violations=kept_violations(args),
                block_edges=args.block_edges or DEFAULT_BLOCK_EDGES, **setup.options,
            )  # fmt: skip
        except NotStreamable:
            machine = None
    if machine is None:
        if source is not None:
            capture = capture_from_args(args, path, resolution=False)
        machine = check_machine(
            capture, setup.axes, setup.drives, setup.resolution, **setup.options
        )
    return finish_report(args, machine, setup.found)


def kept_violations(args: argparse.Namespace) -> int:
    """Violations a streamed check keeps per rule: enough for every output's list."""
    return max(DEFAULT_VIOLATION_CAP, DEFAULT_TEXT_VIOLATIONS, args.max_violations or 0)


def write_outputs(args: argparse.Namespace, report: Checked) -> None:
    """Render ``report`` in ``--format`` to ``-o`` FILE (a one-line summary on stdout) or stdout."""
    text = RENDERERS[args.format](report, args)
    if args.output:
        atomic_write(args.output, text)
        if getattr(args, "quiet", False):  # -q: the report file only
            return
        steps = sum(r.steps.count for r in axis_reports(report))
        print(
            f"{report.verdict}: {report.total_violations} violation(s), {steps} steps; "
            f"report written to {args.output}"
        )
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
    if not args.steps_csv:
        return run_checks(args, build_report, write_outputs)
    patterns = args.capture if isinstance(args.capture, list) else [args.capture]
    several = len(expand_captures(patterns)) > 1
    used: set[str] = set()

    def build_and_export(a: argparse.Namespace, path: str) -> Checked:
        """:func:`build_report`, then the capture's steps to ``--steps-csv``."""
        checked = build_report(a, path)
        target = steps_csv_path(a.steps_csv, path, used) if several else a.steps_csv
        reports = axis_reports(checked)
        axes = [AxisSteps(r.axis, r.events()) for r in reports]
        write_steps(a, target, axes, reports[0].capture.timebase)
        return checked

    return run_checks(args, build_and_export, write_outputs)
