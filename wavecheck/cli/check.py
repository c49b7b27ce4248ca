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

from wavecheck.axes import AxisMap, parse_axes, per_axis, split_invert
from wavecheck.capture.model import Capture
from wavecheck.cli._capture_args import (
    add_capture_arguments,
    capture_from_args,
    resolution_from_args,
)
from wavecheck.cli._reports import (
    Checked,
    add_report_arguments,
    axis_reports,
    latency_ns,
    render_json_report,
    render_junit_report,
    render_text_report,
    run_checks,
    stepgen_config,
)
from wavecheck.cli.config import add_firmware_arguments, add_tuning_arguments, check_firmware
from wavecheck.drives.library import load_drive
from wavecheck.drives.model import Drive
from wavecheck.drives.tune import tune_drive
from wavecheck.engine import check_machine
from wavecheck.errors import UsageError
from wavecheck.output import atomic_write, output_file
from wavecheck.report.json import DEFAULT_VIOLATION_CAP
from wavecheck.report.text import DEFAULT_TEXT_VIOLATIONS

__all__ = ["RENDERERS", "build_report", "register", "run", "write_outputs"]

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
        required=True,
        metavar="ID|FILE|AXIS=ID",
        help="drive id from rules/ or a TOML file; AXIS=ID gives one axis its own drive "
        "(repeatable: --drive x=gecko-g202 --drive y=leadshine-dm542)",
    )
    p.add_argument(
        "--map",
        action="append",
        default=[],
        metavar="[AXIS.]ROLE=CH",
        help="map roles to channels by name, index or the end of a hierarchical name "
        "(step=STEP,dir=3, step=s2.step; repeatable); each role and each channel once; several "
        "axes: --map x.step=5,x.dir=6 --map y.step=3,y.dir=4 (a role without an axis, e.g. "
        "enable=EN, is shared). Without --map, channels are mapped from their waveforms when "
        "that is unambiguous (see wavecheck info)",
    )
    p.add_argument(
        "--invert",
        action="append",
        default=[],
        metavar="[AXIS.]ROLE",
        help="invert a role (repeatable; x.step for one axis)",
    )
    p.add_argument(
        "--type",
        action="append",
        default=None,
        metavar="N|AXIS=N",
        help="LinuxCNC step type 0..15 (default: the drive's; 0 step/dir); AXIS=N for one axis",
    )
    p.add_argument(
        "--user-step-type",
        metavar="V,V,...",
        help="state table for --type 15 (LinuxCNC user_step_type=, phase A = bit 0)",
    )
    p.add_argument(
        "--dir-forward",
        action="append",
        default=None,
        metavar="low|high|AXIS=low|high",
        help="DIR level that means forward (default low: LinuxCNC and grbl drive DIR high for "
        "negative moves); AXIS=high for one axis",
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


def _int_option(text: str, option: str) -> int:
    try:
        return int(text)
    except ValueError:
        raise UsageError(f"{option} {text!r} is not a whole number (e.g. {option} 2)") from None


def _forward(text: str) -> int:
    if text not in ("low", "high"):
        raise UsageError(f"--dir-forward {text!r}: give low or high")
    return 1 if text == "high" else 0


def _axes_of(args: argparse.Namespace, capture: Capture) -> tuple[list[AxisMap], list[str]]:
    """The axes of the run and a note on how they were found.

    ``--map`` as given; without it, channels named after their roles (``step``, ``dir``,
    ``stepgen.0.phase-A``) as before, else the roles inferred from the waveforms
    (:func:`wavecheck.roles.propose`) when that is unambiguous; when it is not, a usage error
    lists the candidates and the ``--map`` line to copy.
    """
    if args.map:
        return parse_axes(args.map), []
    if any(c.name.rsplit(".", 1)[-1].strip().lower() in ("step", "up", "phase-a") for c in capture.channels):
        return [AxisMap(None, {})], []  # named after their roles: engine.auto_map
    from wavecheck.roles import propose

    proposal = propose(capture)
    if not proposal.unambiguous:
        conflicts = "; ".join(
            f"{c.question}: {' | '.join(c.candidates)}" for c in proposal.ambiguous
        ) or "no STEP, UP/DOWN or phase channel found"
        hint = f" (e.g. {proposal.map_args()})" if proposal.axes else ""
        raise UsageError(
            f"{capture.path}: the channels' roles cannot be told from the waveforms: {conflicts}; "
            f"give --map{hint}"
        )
    single = len(proposal.axes) == 1
    axes = [
        AxisMap(None if single else a.name, dict(a.mapping), a.step_type or None, a.inverted)
        for a in proposal.axes
    ]
    return axes, [f"channels mapped from their waveforms: {proposal.map_args()} {proposal.type_args()}".rstrip()]


def build_report(args: argparse.Namespace, path: str) -> Checked:
    """Read ``path`` once and check every axis of ``args`` against its drive (no output)."""
    if args.max_violations is not None and args.max_violations < 0:
        raise UsageError(f"--max-violations must be 0 or more, got {args.max_violations}")
    capture = capture_from_args(args, path, resolution=False)
    axes, found = _axes_of(args, capture)
    names = [a.name for a in axes]
    drives = per_axis(args.drive, "--drive", names)
    types = per_axis(args.type, "--type", names)
    forward = per_axis(args.dir_forward, "--dir-forward", names)
    inverts = split_invert(args.invert, names)
    loaded: dict[str, Drive] = {}
    for axis in axes:
        if axis.name not in drives:
            raise UsageError(f"--drive: axis {axis.name} has no drive (add --drive {axis.name}=ID)")
        ref = drives[axis.name]
        if ref not in loaded:
            loaded[ref] = tune_drive(load_drive(ref), args.limit, args.margin)
    machine = check_machine(
        capture,
        axes,
        {a.name: loaded[drives[a.name]] for a in axes},
        resolution_from_args(args),  # exact, a fraction of a tick included
        step_types={a: _int_option(t, "--type") for a, t in types.items()},
        forward_levels={a: _forward(f) for a, f in forward.items()},
        invert=inverts,
        active_edge=args.active_edge,
        user_table=_user_table(args.user_step_type),
        stepgen=stepgen_config(args),
        pulse_level=1 if args.pulse_level == "high" else 0,
        latency_ns=latency_ns(args),
    )
    for report in machine.axes:
        if args.firmware:  # the capture against its own firmware configuration
            report.firmware = check_firmware(args, report)
        report.notes[:0] = found
    if len(machine.axes) == 1 and machine.axes[0].axis is None:
        return machine.axes[0]
    return machine


def write_outputs(args: argparse.Namespace, report: Checked) -> None:
    """Render ``report`` in ``--format`` to ``-o`` FILE (a one-line summary on stdout) or stdout."""
    text = RENDERERS[args.format](report, args)
    if args.output:
        atomic_write(args.output, text)
        steps = sum(r.steps.count for r in axis_reports(report))
        print(
            f"{report.verdict}: {report.total_violations} violation(s), {steps} steps; "
            f"report written to {args.output}"
        )
    else:
        sys.stdout.write(text)


def run(args: argparse.Namespace) -> int:
    """Run ``wavecheck check``; returns the exit code."""
    return run_checks(args, build_report, write_outputs)
