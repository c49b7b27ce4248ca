"""``--steps-csv FILE`` and ``--steps-per-unit N|AXIS=N``, shared by ``check`` and ``measure``.

The CSV's columns are :mod:`wavecheck.report.steps_csv`'s. Several captures in one ``check`` run
write one CSV each, named ``FILE-<capture stem>.csv``.
"""

from __future__ import annotations

import argparse
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

from wavecheck.capture.blocks import BlockSource
from wavecheck.engine import AxisPlan, StepSink
from wavecheck.errors import UsageError
from wavecheck.output import output_file
from wavecheck.steps.mapping import split_per_axis

if TYPE_CHECKING:  # imported where used: only with --steps-csv
    from wavecheck.report.steps_csv import StepsCsvWriter

__all__ = ["add_steps_arguments", "check_steps_arguments", "steps_csv_path", "steps_writer"]


def add_steps_arguments(p: Any) -> None:
    """Add ``--steps-csv`` and ``--steps-per-unit`` to ``p``."""
    g = p.add_argument_group("decoded steps")
    g.add_argument(  # output_file: checked before any work (wavecheck.output)
        "--steps-csv",
        type=output_file,
        metavar="FILE.csv",
        help="write every decoded step: time_s (exact decimal), tick, axis, direction, "
        "position, rate_hz (from the axis's previous step)",
    )
    g.add_argument(
        "--steps-per-unit",
        action="append",
        default=None,
        metavar="N|AXIS=N",
        help="steps per machine unit (e.g. 80 for 80 steps/mm; x=80 for one axis): adds "
        "position_units and velocity_units_per_s to --steps-csv",
    )


def check_steps_arguments(args: argparse.Namespace) -> None:
    """Refuse ``--steps-per-unit`` without ``--steps-csv`` (before any work)."""
    if args.steps_per_unit and not args.steps_csv:
        raise UsageError("--steps-per-unit adds columns to --steps-csv: give --steps-csv FILE too")


def steps_csv_path(target: str, capture: str, used: set[str]) -> str:
    """``steps.csv`` → ``steps-<capture stem>.csv`` (a number added when stems repeat)."""
    p = Path(target)
    stem = Path(capture).stem
    name, n = str(p.with_name(f"{p.stem}-{stem}{p.suffix}")), 1
    while name in used:
        n += 1
        name = str(p.with_name(f"{p.stem}-{stem}-{n}{p.suffix}"))
    used.add(name)
    return name


def steps_writer(
    args: argparse.Namespace, target: str, source: BlockSource
) -> tuple[StepsCsvWriter, Callable[[AxisPlan], list[StepSink]]]:
    """The ``--steps-csv`` writer of one capture (``--steps-per-unit`` applied) and the
    engine's factory of its axis sinks."""
    from wavecheck.report.steps_csv import StepsCsvWriter, steps_per_unit_of

    spu = steps_per_unit_of(split_per_axis(args.steps_per_unit, "--steps-per-unit"))
    writer = StepsCsvWriter(
        target, source.skeleton.timebase, bool(args.steps_per_unit), named=set(spu) - {None}
    )

    def sinks(plan: AxisPlan) -> list[StepSink]:
        value = spu.get(plan.name, spu.get(None))
        return [writer.sink(plan.name, value)]

    return writer, sinks
