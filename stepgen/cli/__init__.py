"""The ``stepgen`` command: simulate LinuxCNC's software stepgen, plan its timing."""

from __future__ import annotations

import gc
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


#: Allocations between two young-generation collections while the ``stepgen`` program runs
#: (Python's default is 700): importing numpy and a command's modules made ~40 collections.
#: The cyclic garbage a collection would free waits for at most this many allocations.
GC_YOUNG_THRESHOLD = 50_000


def main(argv: Sequence[str] | None = None) -> int:
    """Run ``stepgen`` with ``argv`` (default: ``sys.argv[1:]``); returns the exit code.

    As the program (``argv`` None: the console script, ``python -m stepgen``) the cyclic
    garbage collector runs less often, and the objects left at the end are frozen, so the
    collection at interpreter exit does not walk them again: together ~20 ms of the 20 s
    ``--command`` run's ~0.23 s CPU (bench/README.md, Round 6). Called with ``argv`` (tests,
    other programs) nothing about the collector changes."""
    if argv is not None:
        return _run(argv)
    gc.set_threshold(GC_YOUNG_THRESHOLD, *gc.get_threshold()[1:])
    try:
        return _run(None)
    finally:
        gc.freeze()


def _run(argv: Sequence[str] | None) -> int:
    return run_cli(
        "stepgen",
        "A faithful model of LinuxCNC's software step generator, and its timing calculator.",
        COMMANDS,
        argv,
    )
