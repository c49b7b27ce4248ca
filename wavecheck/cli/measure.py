"""``wavecheck measure CAPTURE [--map …]``: the timing a scope user reads off, without a drive.

Per axis: steps, reversals, and for every interval kind of the step type the count, min, max,
mean, percentiles and where the extremes are, plus the step-rate range
(:mod:`wavecheck.measurement`; the intervals are ``check``'s). Text or ``--format json``
(:mod:`wavecheck.report.measured`), ``--plot``/``--html`` with position, step rate and histograms,
``--steps-csv`` with every step. Exit 0, or 2 for unusable input (nothing is judged).

``--firmware FILE`` (issue 15) compares each axis's measured minima with the configuration that
made the capture, as ``check --firmware`` does (:func:`wavecheck.firmware.capture.firmware_check`):
shortest pulse vs the configured pulse, DIR setup vs the configured delay, highest rate vs the
configured maximum; a capture that violates its own configuration exits 1.
"""

from __future__ import annotations

import argparse
import sys
from typing import TYPE_CHECKING, Any

from wavecheck.cli._axis_args import add_axis_arguments, add_engine_arguments, check_options
from wavecheck.cli._capture_args import add_capture_arguments, source_from_args
from wavecheck.cli._firmware_args import add_firmware_arguments, check_firmware, firmware_config
from wavecheck.cli._formats import Formats, json_text
from wavecheck.cli._steps_args import add_steps_arguments, check_steps_arguments, steps_writer
from wavecheck.measurement import Measurement, measure
from wavecheck.output import atomic_write, figure_file, figure_format, output_file
from wavecheck.progress import QUIET_HELP, activate
from wavecheck.report.measured import measurement_dict, render_measure_text
from wavecheck.verdict import EXIT_FAIL, EXIT_PASS

if TYPE_CHECKING:
    from wavecheck.firmware.capture import FirmwareCheck

__all__ = ["build_measurement", "register", "run"]


def register(sub: Any) -> None:
    """Add the ``measure`` subcommand."""
    p = sub.add_parser(
        "measure",
        description="Measure CAPTURE per axis: steps, reversals, and for every interval kind "
        "(high, low, period, DIR setup/hold, …) min, max, mean, percentiles and where the "
        "extremes are, plus the step-rate range. No drive, no limits, no verdict. Exit 0, or 2 "
        "for unusable input.",
    )
    p.add_argument(
        "capture", metavar="CAPTURE", help="the capture (.sr, .vcd, or a sigrok-cli format)"
    )
    add_axis_arguments(p, drive=False)
    add_firmware_arguments(p)
    add_capture_arguments(p)
    FORMATS.add_argument(p)
    p.add_argument(  # output_file: checked before any work (wavecheck.output)
        "-o", "--output", type=output_file, metavar="FILE", help="write the report to FILE"
    )
    out = p.add_argument_group("figures")
    out.add_argument(
        "--plot",
        type=figure_file,
        metavar="FILE.png",
        help="position and step rate against time per axis (reversals marked), and a histogram "
        "of every interval kind (PNG; .jpg, .svg or .pdf by the file's name)",
    )
    out.add_argument(
        "--html", type=output_file, metavar="FILE.html", help="one self-contained HTML page"
    )
    add_steps_arguments(p)
    add_engine_arguments(p)
    p.add_argument("-q", "--quiet", action="store_true", help=QUIET_HELP)
    p.set_defaults(func=run)


def build_measurement(args: argparse.Namespace) -> Measurement:
    """Read the capture once and measure every axis of ``args``; ``--steps-csv`` is written
    meanwhile."""
    source = source_from_args(args, args.capture)
    options = check_options(args, with_drive=False)
    if not args.steps_csv:
        return measure(source, options)
    writer, sinks = steps_writer(args, args.steps_csv, source)
    try:
        m = measure(source, options, step_sinks=sinks, settled=writer.settled)
    except BaseException:
        writer.abort()
        raise
    writer.close()
    return m


def firmware_checks(args: argparse.Namespace, m: Measurement) -> list[FirmwareCheck]:
    """``--firmware``: every measured axis against the configured axis (``--axis``, default the
    first), compared as ``check --firmware`` compares a report (empty without ``--firmware``)."""
    cfg = firmware_config(args)
    if cfg is None:
        return []
    from wavecheck.firmware.capture import observed_in_measurement

    return [check_firmware(args, cfg, observed_in_measurement(a, m.resolution_ns)) for a in m.axes]


def _measure_doc(m: Measurement, own: list[FirmwareCheck]) -> dict[str, Any]:
    """The measurement's JSON, each axis with its ``--firmware`` findings."""
    doc = measurement_dict(m)
    if own:
        from wavecheck.report.firmware import firmware_check_dict

        for axis, fc in zip(doc["axes"], own, strict=True):
            axis["firmware"] = firmware_check_dict(fc)
    return doc


def _measure_text(m: Measurement, own: list[FirmwareCheck]) -> str:
    """The measurement's text, each axis's ``--firmware`` findings after it."""
    text = render_measure_text(m)
    if own:
        from wavecheck.report.firmware import firmware_check_lines

        for a, fc in zip(m.axes, own, strict=True):
            head = [] if a.name is None else [f"axis {a.name}:"]
            text += "\n" + "\n".join([*head, *firmware_check_lines(fc)]) + "\n"
    return text


#: ``--format``: text or JSON.
FORMATS = Formats({"text": _measure_text, "json": json_text(_measure_doc)})


def run(args: argparse.Namespace) -> int:
    """Run ``wavecheck measure``; returns the exit code."""
    check_steps_arguments(args)
    with activate(f"reading {args.capture}", quiet=args.quiet, unit="bytes"):
        m = build_measurement(args)
    own = firmware_checks(args, m)
    text = FORMATS.render(args.format, m, own)
    if args.output:
        atomic_write(args.output, text)
    if args.output and not args.quiet:
        steps = ", ".join(
            f"{'' if a.name is None else a.name + ' '}{a.steps.count}" for a in m.axes
        )
        print(f"measured {len(m.axes)} axis/axes ({steps} steps); report written to {args.output}")
    elif not args.output:
        sys.stdout.write(text)
    png = None
    if args.plot or args.html:
        from wavecheck.report.measured_plot import render_measure_png

        png = render_measure_png(m)
    if args.plot:
        fmt = figure_format(args.plot)
        assert png is not None
        atomic_write(args.plot, png if fmt == "png" else render_measure_png(m, fmt=fmt))
    if args.html:
        from wavecheck.report.measured import write_measure_html

        write_measure_html(m, args.html, png)
    return EXIT_FAIL if any(fc.verdict == "fail" for fc in own) else EXIT_PASS
