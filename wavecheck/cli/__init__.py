"""The ``wavecheck`` command: info, check, measure, drives, compare, crosscheck, latency."""

from __future__ import annotations

from collections.abc import Sequence

from wavecheck.cli._main import run_cli

__all__ = ["main"]

COMMANDS = (
    "wavecheck.cli.info",
    "wavecheck.cli.check",
    "wavecheck.cli.measure",
    "wavecheck.cli.drives",
    "wavecheck.cli.compare",
    "wavecheck.cli.crosscheck",
    "wavecheck.cli.config",
    "wavecheck.cli.latency",
    "wavecheck.cli.follow",
    "wavecheck.cli.watch",
    "wavecheck.cli.sigrok",
)


def main(argv: Sequence[str] | None = None) -> int:
    """Run ``wavecheck`` with ``argv`` (default: ``sys.argv[1:]``); returns the exit code."""
    return run_cli(
        "wavecheck",
        "Check STEP/DIR waveforms against stepper drive datasheet timing.",
        COMMANDS,
        argv,
    )
