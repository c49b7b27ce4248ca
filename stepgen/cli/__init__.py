"""The ``stepgen`` command: simulate LinuxCNC's software stepgen, plan its timing."""

from __future__ import annotations

import sys
from collections.abc import Sequence

from wavecheck.cli._main import run_cli

__all__ = ["main"]

#: Each subcommand's module (``stepgen.cli.NAME`` registers the subcommand NAME).
COMMANDS = ("stepgen.cli.simulate", "stepgen.cli.plan", "stepgen.cli.tune")


def main(argv: Sequence[str] | None = None) -> int:
    """Run ``stepgen`` with ``argv`` (default: ``sys.argv[1:]``); returns the exit code.

    When the first argument names a subcommand only that one's module is imported (the others
    would only add start-up time); otherwise all of them, for ``--help`` and usage errors."""
    args = sys.argv[1:] if argv is None else list(argv)
    chosen = [m for m in COMMANDS if args and m.rsplit(".", 1)[1] == args[0]]
    return run_cli(
        "stepgen",
        "A faithful model of LinuxCNC's software step generator, and its timing calculator.",
        chosen or COMMANDS,
        args,
    )
