"""The ``stepgen`` command: simulate LinuxCNC's software stepgen, plan its timing."""

from __future__ import annotations

from collections.abc import Sequence

from wavecheck.cli._main import Command, run_cli

__all__ = ["COMMANDS", "main"]

#: Every subcommand: the module that builds its parser (imported only when that subcommand
#: runs) and its line in ``stepgen --help``.
COMMANDS = {
    "simulate": Command(
        "stepgen.cli.simulate",
        "simulate LinuxCNC's software stepgen with base-thread latency; write VCD or .sr",
    ),
    "plan": Command(
        "stepgen.cli.plan",
        "choose BASE_PERIOD and steplen/stepspace/dirsetup/dirhold for a drive and a latency",
    ),
    "tune": Command(
        "stepgen.cli.tune",
        "tune pid by the integrator's manual method on a model plant (stepgen or servo)",
    ),
}


def main(argv: Sequence[str] | None = None) -> int:
    """Run ``stepgen`` with ``argv`` (default: ``sys.argv[1:]``); returns the exit code."""
    return run_cli(
        "stepgen",
        "A faithful model of LinuxCNC's software step generator, and its timing calculator.",
        COMMANDS,
        argv,
    )
