"""The ``wavecheck`` command: info, check, measure, drives, compare, crosscheck, latency, simulate."""

from __future__ import annotations

from collections.abc import Sequence

from wavecheck.cli._main import Command, as_program, run_cli

__all__ = ["COMMANDS", "main"]

#: Every subcommand: the module that builds its parser (imported only when that subcommand
#: runs) and its line in ``wavecheck --help``, in the order listed there.
COMMANDS = {
    "info": Command(
        "wavecheck.cli.info", "show a capture's channels, sample rate, duration and edge counts"
    ),
    "check": Command(
        "wavecheck.cli.check", "check every edge of a capture against a drive's timing rules"
    ),
    "measure": Command(
        "wavecheck.cli.measure",
        "measure every interval and the steps of a capture, without a drive",
    ),
    "drives": Command(
        "wavecheck.cli.drives", "list the drive rule files, or show one with its sources"
    ),
    "compare": Command(
        "wavecheck.cli.compare",
        "compare a capture with a golden trace (steps, times, rule tables)",
    ),
    "crosscheck": Command(
        "wavecheck.cli.crosscheck",
        "compare wavecheck's step decode with sigrok-cli's counter/stepper_motor decoders",
    ),
    "config": Command(
        "wavecheck.cli.config", "can a firmware configuration meet the drive? (no capture needed)"
    ),
    "latency": Command(
        "wavecheck.cli.latency",
        "base-thread latency from the step pins: the invocation lattice k·P + l of a capture",
    ),
    "follow": Command(
        "wavecheck.cli.follow",
        "following error: commanded motion against the position decoded from a capture",
    ),
    "watch": Command(
        "wavecheck.cli.watch",
        "check a running machine live, from a logic analyzer through sigrok-cli",
    ),
    "simulate": Command(
        "wavecheck.cli.simulate",
        "run grbl or Klipper on a simulated MCU: its own STEP/DIR pins from the G-code, checked",
    ),
    "sigrok": Command(
        "wavecheck.cli.sigrok",
        "install the wavecheck protocol decoder for PulseView and sigrok-cli",
    ),
}


def main(argv: Sequence[str] | None = None) -> int:
    """Run ``wavecheck`` with ``argv`` (default: ``sys.argv[1:]``); returns the exit code.

    Without ``argv`` (the console script, ``python -m wavecheck``) it runs as the program
    (:func:`~wavecheck.cli._main.as_program`: the garbage collector tuned for one command);
    called with ``argv`` (tests, other programs) nothing about the collector changes."""
    if argv is not None:
        return _run(argv)
    return as_program(lambda: _run(None))


def _run(argv: Sequence[str] | None) -> int:
    return run_cli(
        "wavecheck",
        "Check STEP/DIR waveforms against stepper drive datasheet timing.",
        COMMANDS,
        argv,
    )
