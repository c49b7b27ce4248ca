"""``stepgen plan``: the step timing calculator (LinuxCNC's StepTimingCalculator as a command).

``stepgen plan --drive ID|FILE --latency J|FILE [--base-period P] [--invert-step]
[--limit RULE=T] [--margin 2x|+T] [--format text|json|ini|hal] [--channel N] [-o FILE]``

``--limit`` gives a figure the drive's file lacks or overrides one (a drive without a DIR hold
figure, such as the Leadshine DM542, is planned with ``--limit dir_hold=5us`` from its manual or
a measurement), and ``--margin`` tightens every figure, as for ``wavecheck check`` and ``config``
(:mod:`wavecheck.drives.overrides`).

Times carry their unit (``11us``, ``15500ns``); a bare number other than 0 is refused with the
fix spelled out (docs/reference.md "Numbers and units"). A base period below 1 us is refused and a latency
below 100 ns warned about, as almost surely a unit slip. ``--latency`` also takes a file (any
value not written as a number): cyclictest summary or ``-h`` histogram output,
``latency-histogram --nox`` output, or latency-test's one-number ``~/.latency`` (ns), each read
in its own documented unit. ``--latency-from CAPTURE`` (or a capture given to ``--latency``)
reads the worst lateness from the step pins (``wavecheck latency``, channels mapped as ``check``
maps them) and plans from it plus one sample; it refuses when that lateness is not established
(no lattice, or lateness of a period or more). When the capture cannot tell two readings apart,
the larger is planned from.

Exit codes: 0 a plan was made, 2 unusable input or no established latency (one line on stderr).
"""

from __future__ import annotations

import argparse
import sys
from fractions import Fraction
from pathlib import Path
from typing import Any

from stepgen.latencyfiles import CAPTURE_SUFFIXES, read_latency_file
from stepgen.plan import plan
from stepgen.plan_render import render_hal, render_ini, render_json, render_text
from wavecheck.cli._tuning_args import add_limit_arguments
from wavecheck.errors import ConfigError, UsageError, WavecheckError
from wavecheck.output import atomic_write, output_file
from wavecheck.units import BASE_PERIOD, LATENCY, Plausible, is_number, option_ns, shorten

__all__ = ["parse_latency_arg", "parse_time_arg", "read_capture_latency", "register", "run"]

_FORMATS = ("text", "json", "ini", "hal")


def register(sub: Any) -> None:
    """Add the ``plan`` subcommand to ``sub`` (an argparse subparsers object)."""
    p = sub.add_parser(
        "plan",
        description=(
            "The step timing calculator: from a drive's datasheet figures and the worst latency J "
            "it gives the minimum and the simple BASE_PERIOD, each stepgen parameter as "
            "n = ceil((T + J) / P) periods, the max step rate and each requirement's margin. "
            "Times carry their unit (11us, 16000ns); a bare number is refused."
        ),
    )
    p.add_argument(
        "--drive", required=True, metavar="ID|FILE", help="drive id from rules/ or a rule file"
    )
    p.add_argument(
        "--latency",
        metavar="J|FILE",
        help="worst latency with its unit (e.g. 11us; below 100 ns gives a warning), or a "
        "cyclictest / latency-histogram --nox / ~/.latency file, or a capture (.sr/.vcd) of the "
        "step pins (see --latency-from)",
    )
    p.add_argument(
        "--latency-from",
        metavar="CAPTURE",
        help="a capture of the running machine's step pins: the worst base-thread lateness read "
        "from it (wavecheck latency) plus one sample period",
    )
    p.add_argument(
        "--cyclictest-nsecs",
        action="store_true",
        help="the --latency file is a cyclictest summary run with -N (numbers in ns, not us)",
    )
    p.add_argument(
        "--base-period",
        metavar="P",
        help="BASE_PERIOD to plan for, with its unit (e.g. 16us; below 1 us is refused); "
        "default: the minimum rounded up to a whole us",
    )
    p.add_argument(
        "--invert-step",
        action="store_true",
        help="the STEP pin is inverted to the drive (default: not inverted, as in the G202 "
        "example of LinuxCNC's Stepper Tuning chapter)",
    )
    add_limit_arguments(p)
    p.add_argument(
        "--format", choices=_FORMATS, default="text", help="output format (default text)"
    )
    p.add_argument(
        "--channel",
        type=int,
        default=0,
        metavar="N",
        help="stepgen channel for ini/hal (default 0)",
    )
    p.add_argument(  # output_file: checked before any work (wavecheck.output)
        "-o", "--output", type=output_file, metavar="FILE", help="write the output here"
    )
    p.set_defaults(func=run)


def _warn(message: str) -> None:
    print(f"stepgen: warning: {message}", file=sys.stderr)


def parse_time_arg(
    text: str, option: str, plausible: Plausible | None = None
) -> tuple[Fraction, str]:
    """Read a time option as exact ns; returns ``(ns, where it came from)``. Its unit is
    required (:func:`wavecheck.units.parse_option`), ``plausible`` judges the value.

    Raises:
        UnitError: no unit, not a time, out of range, or implausible.
    """
    return option_ns(text, option, plausible, _warn), f"{option} {text}"


def read_capture_latency(path: str | Path) -> tuple[int, str]:
    """The worst base-thread lateness (ns, rounded up) of a capture's step pins plus one sample
    period (every edge, lateness 0 included, is seen up to a sample late), and where it came
    from (:mod:`wavecheck.lattice`).

    Raises:
        ConfigError: the lateness is not established
            (:attr:`wavecheck.lattice.LatencyReport.unestablished` says why).
    """
    from wavecheck.step_latency import latency_of

    report = latency_of(str(path))
    worst = report.max_lateness_bound_ns
    if not report.established or worst is None:
        raise ConfigError(
            f"{path}: no latency to plan from: {report.unestablished or report.reason}; give "
            "--latency (from latency-test or cyclictest)"
        )
    ns = -(-worst.numerator // worst.denominator)
    assert report.max_lateness_ns is not None
    return ns, (
        f"{path}: worst lateness of the base thread on the step pins, "
        f"{float(report.max_lateness_ns):g} ns + one sample ({float(report.resolution_ns):g} ns), "
        f"P = {float(report.period_ns or 0):g} ns inferred from the capture"
    )


def parse_latency_arg(text: str, cyclictest_unit: str = "us") -> tuple[Fraction, str]:
    """``--latency``: a time, or a file of a latency tool; returns ``(ns, where it came from)``.

    Text written as a number (``11us``, ``11``, ``1e400s``) is a time, anything else a file.
    ``cyclictest_unit`` is the unit of a cyclictest summary's numbers (``"ns"`` if it ran with -N).
    """
    if is_number(text.strip()):
        return parse_time_arg(text, "--latency", LATENCY)
    path = Path(text).expanduser()
    if not path.exists():
        raise UsageError(
            f"--latency {shorten(text)!r} is neither a time such as '11us' nor an existing file "
            "(give the worst latency, or a cyclictest / latency-histogram / ~/.latency file, or a "
            "capture)"
        )
    if path.suffix.lower() in CAPTURE_SUFFIXES:
        worst_ns, description = read_capture_latency(path)
    else:
        worst_ns, description = read_latency_file(path, cyclictest_unit=cyclictest_unit)
    return Fraction(worst_ns), description


def run(args: argparse.Namespace) -> int:
    """Run ``stepgen plan``; returns 0 (errors raise a WavecheckError, exit 2)."""
    from wavecheck.drives.library import load_drive
    from wavecheck.drives.overrides import tune_drive

    if args.channel < 0 or args.channel > 15:
        raise UsageError(f"--channel {args.channel}: stepgen has channels 0..15")
    if (args.latency is None) == (args.latency_from is None):
        raise UsageError("give --latency J|FILE or --latency-from CAPTURE (one of them)")
    if args.latency_from is not None:
        worst_ns, source = read_capture_latency(args.latency_from)
        latency = Fraction(worst_ns)
    else:
        latency, source = parse_latency_arg(args.latency, "ns" if args.cyclictest_nsecs else "us")
    period = None
    if args.base_period is not None:
        period, _ = parse_time_arg(args.base_period, "--base-period", BASE_PERIOD)
    drive = tune_drive(load_drive(args.drive), args.limit, args.margin)
    result = plan(drive, latency, period, step_inverted=args.invert_step, latency_source=source)
    if args.format == "json":
        out = render_json(result)
    elif args.format == "ini":
        out = render_ini(result, args.channel)
    elif args.format == "hal":
        out = render_hal(result, args.channel)
    else:
        try:
            other = plan(drive, latency, result.base_period_ns, step_inverted=not args.invert_step)
        except WavecheckError:  # pragma: no cover - same figures, same checks
            other = None
        out = render_text(result, other)
    if args.output:
        atomic_write(args.output, out)
        print(f"stepgen plan: wrote {args.output} (latency {source})", file=sys.stderr)
    else:
        sys.stdout.write(out)
    return 0
