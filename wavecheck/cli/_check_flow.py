"""One capture through ``check``'s engine and outputs: :func:`build_report` (``check`` runs it
on each of its captures), and :func:`run_check` for a command that makes the capture itself
(``simulate``): the options ``check`` has, without its several-captures and snippet handling."""

from __future__ import annotations

import argparse

from wavecheck.cli._batch import run_checks
from wavecheck.cli._capture_args import source_from_args
from wavecheck.cli._formats import Checked
from wavecheck.cli._pulseview_args import check_pulseview
from wavecheck.cli._reports import Asked, finish_report, write_outputs
from wavecheck.cli._steps_args import check_steps_arguments, steps_writer
from wavecheck.engine import check_source, start
from wavecheck.errors import UsageError

__all__ = ["build_report", "run_check"]


def build_report(
    args: argparse.Namespace, what: Asked, path: str, steps_csv: str | None = None
) -> Checked:
    """Read ``path`` once and check every axis as ``what`` asks (and write the steps to
    ``steps_csv`` as they are decoded)."""
    if args.max_violations is not None and args.max_violations < 0:
        raise UsageError(f"--max-violations must be 0 or more, got {args.max_violations}")
    source = source_from_args(args, path)
    if steps_csv is None:
        return finish_report(args, check_source(source, what.options), what.firmware)
    writer, sinks = steps_writer(args, steps_csv, source)
    try:
        machine, blocks = start(source, what.options, step_sinks=sinks)
        for block in blocks:
            machine.feed(block)
            writer.settled(machine.settled(block.end))
        checked = finish_report(args, machine.finish(source.capture()), what.firmware)
    except BaseException:
        writer.abort()
        raise
    writer.close()
    return checked


def run_check(args: argparse.Namespace) -> int:
    """Check the one capture ``args.capture`` names, write the outputs; the exit code."""
    check_steps_arguments(args)
    if getattr(args, "pulseview", None):
        check_pulseview(args, 1)
    return run_checks(
        args, lambda a, what, path: build_report(a, what, path, a.steps_csv), write_outputs
    )
