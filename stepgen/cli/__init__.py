"""The ``stepgen`` command: simulate LinuxCNC's software stepgen, plan its timing."""

from __future__ import annotations

from collections.abc import Sequence

from wavecheck.cli._main import run_cli

__all__ = ["main"]

COMMANDS = ("stepgen.cli.simulate", "stepgen.cli.plan", "stepgen.cli.tune")


def main(argv: Sequence[str] | None = None) -> int:
    """Run ``stepgen`` with ``argv`` (default: ``sys.argv[1:]``); returns the exit code."""
    return run_cli(
        "stepgen",
        "A faithful model of LinuxCNC's software step generator, and its timing calculator.",
        COMMANDS,
        argv,
    )
