"""The reports of one capture, for ``check`` and ``watch``: the report-file options,
``--firmware`` findings added (:func:`finish_report`) and every output asked for written
(:func:`write_outputs`, the ``--format`` document by :mod:`wavecheck.cli._formats`).

Options added here (see :func:`add_report_arguments`): ``--plot FILE.png``, ``--html FILE.html``,
``--gtkw FILE.gtkw``, ``-j N``, ``-q/--quiet``, and the stepgen configuration options
(:mod:`wavecheck.cli._stepgen_args`). Several captures: :mod:`wavecheck.cli._batch`.
"""

from __future__ import annotations

import argparse
import sys
from typing import TYPE_CHECKING

from wavecheck.cli._axis_args import check_options
from wavecheck.cli._firmware_args import check_firmware, firmware_config
from wavecheck.cli._formats import FORMATS, Checked, axis_reports
from wavecheck.cli._stepgen_args import add_stepgen_arguments
from wavecheck.cli._tuning_args import required
from wavecheck.engine import CheckOptions, MachineReport
from wavecheck.output import atomic_write, figure_file, gtkw_file, output_file
from wavecheck.progress import QUIET_HELP
from wavecheck.record import record

if TYPE_CHECKING:  # read only with --firmware
    from wavecheck.firmware.guarantee import FirmwareConfig

__all__ = ["Asked", "add_report_arguments", "asked", "finish_report", "write_outputs"]


@record(frozen=True)
class Asked:
    """What a check is asked, read from its arguments once, before any capture (a bad option
    or file is reported before any capture is read): the options object and the firmware
    configuration of ``--firmware`` (None without it)."""

    options: CheckOptions
    firmware: FirmwareConfig | None = None


def asked(args: argparse.Namespace) -> Asked:
    """The :class:`Asked` of ``check``'s (or ``simulate``'s) arguments."""
    return Asked(check_options(args), firmware_config(args))


def add_report_arguments(p: argparse.ArgumentParser) -> None:
    """Add the report-file, quiet and LinuxCNC-configuration options to ``check``'s parser."""
    out = p.add_argument_group("reports")  # output_file: checked before any work (wavecheck.output)
    out.add_argument(
        "--plot",
        type=figure_file,
        metavar="FILE.png",
        help="timing diagrams and histograms (PNG; .jpg, .svg or .pdf by the file's name)",
    )
    out.add_argument(
        "--html", type=output_file, metavar="FILE.html", help="one self-contained HTML page"
    )
    out.add_argument(
        "--gtkw",
        type=gtkw_file,
        metavar="FILE.gtkw",
        help="GTKWave save file with markers at the worst violations (a non-VCD capture is "
        "written as FILE.vcd beside it)",
    )
    out.add_argument(
        "-j",
        "--jobs",
        type=int,
        metavar="N",
        help="several captures: check them in N processes (default: the cores; 1: in this "
        "process). Each summary line prints as its capture finishes (to stdout with -o, else to "
        "stderr on a terminal), so their order may vary; the report (text, JSON, JUnit) lists "
        "the captures in input order. --plot, --gtkw, --html and --steps-csv run in one process",
    )
    out.add_argument(
        "-q",
        "--quiet",
        action="store_true",
        help=QUIET_HELP,
    )
    add_stepgen_arguments(p)


def finish_report(
    args: argparse.Namespace, machine: MachineReport, firmware: FirmwareConfig | None = None
) -> Checked:
    """Add the findings against ``firmware`` (``--firmware``); a single unnamed axis as its
    Report."""
    for report in machine.axes:
        if firmware is not None:  # the capture against its own firmware settings
            report.firmware = check_firmware(args, firmware, report)
    if len(machine.axes) == 1 and machine.axes[0].axis is None:
        return machine.axes[0]
    return machine


def write_outputs(args: argparse.Namespace, report: Checked) -> None:
    """Render ``report`` in ``--format`` to ``-o`` FILE (a one-line summary on stdout) or stdout."""
    if getattr(args, "pulseview", None):  # issue 28: the decoder stacked in a PulseView session
        from wavecheck.sigrok.session import write_pulseview

        for line in write_pulseview(args, axis_reports(report)):
            print(line, file=sys.stderr)
    text = FORMATS[args.format].render(report, args)
    if args.output:
        from wavecheck.report.claims import outcome_line, requirement_line

        atomic_write(args.output, text)
        if getattr(args, "quiet", False):  # -q: the report file only
            return
        steps = sum(r.steps.count for r in axis_reports(report))
        print(
            f"{outcome_line(report, required(args))}: {report.total_violations} violation(s), "
            f"{steps} steps; "
            f"report written to {args.output}"
        )
        missing = requirement_line(report, required(args))
        if missing:
            print(missing)
    else:
        sys.stdout.write(text)
