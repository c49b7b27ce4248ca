"""The axes of a run, shared by ``check`` and ``measure``: mapping options → per-axis parameters.

Options added by :func:`add_axis_arguments`: ``--map`` (``[AXIS.]ROLE=CH``), ``--invert``,
``--type``, ``--user-step-type``, ``--dir-forward``, ``--pulse-level``, ``--active-edge``.
:func:`check_options` turns them into the run's options object (the syntax is
:mod:`wavecheck.steps.mapping`); without ``--map`` the engine takes the roles from channel names or
infers them from the waveforms (:func:`wavecheck.roles.propose`) when that is unambiguous.
"""

from __future__ import annotations

import argparse
from typing import Any

from wavecheck.capture.blocks import WHOLE
from wavecheck.cli._tuning_args import required
from wavecheck.drives.datasheet import Drive
from wavecheck.engine import CheckOptions
from wavecheck.errors import UsageError
from wavecheck.steps.mapping import parse_axes, split_per_axis

__all__ = [
    "add_axis_arguments",
    "add_engine_arguments",
    "check_options",
    "pulse_level",
    "user_table",
]


def add_axis_arguments(p: Any, *, drive: bool = True) -> None:
    """Add the mapping options to ``p``; ``drive=False`` words ``--active-edge`` for a command
    without a drive (``measure``: default rising)."""
    p.add_argument(
        "--map",
        action="append",
        default=[],
        metavar="[AXIS.]ROLE=CH",
        help="map roles to channels by name, index or the end of a hierarchical name "
        "(step=STEP,dir=3, step=s2.step; repeatable); each role and each channel once; several "
        "axes: --map x.step=5,x.dir=6 --map y.step=3,y.dir=4 (a role without an axis, e.g. "
        "enable=EN, is shared). Without --map, channels are mapped from their waveforms when "
        "that is unambiguous (see wavecheck info)",
    )
    p.add_argument(
        "--invert",
        action="append",
        default=[],
        metavar="[AXIS.]ROLE",
        help="invert a role (repeatable; x.step for one axis)",
    )
    p.add_argument(
        "--type",
        action="append",
        default=None,
        metavar="N|AXIS=N",
        help="LinuxCNC step type 0..15 (default: "
        + ("the drive's" if drive else "found with the channels, else 0 step/dir or 1 up/down")
        + "; 0 step/dir); AXIS=N for one axis",
    )
    p.add_argument(
        "--user-step-type",
        metavar="V,V,...",
        help="state table for --type 15 (LinuxCNC user_step_type=, phase A = bit 0)",
    )
    p.add_argument(
        "--dir-forward",
        action="append",
        default=None,
        metavar="low|high|AXIS=low|high",
        help="DIR level that means forward (default low: LinuxCNC and grbl drive DIR high for "
        "negative moves); AXIS=high for one axis",
    )
    p.add_argument(
        "--pulse-level",
        choices=("high", "low"),
        default=None,
        help="level of the generator's step pulses at its output (default: as the waveform "
        "shows it, where every pulse is shorter than every gap; else high, as LinuxCNC, grbl, "
        "Marlin, Klipper and Smoothieware make them; --invert step says the drive sees the "
        "other level)",
    )
    p.add_argument(
        "--active-edge",
        choices=("rising", "falling", "both"),
        default=None if drive else "rising",
        help="override the drive's active STEP edge"
        if drive
        else "the STEP edge that counts a step and starts DIR setup/hold (default rising; "
        "falling for a drive that steps on it, e.g. the Gecko G202)",
    )


def user_table(args: argparse.Namespace) -> tuple[int, ...] | None:
    """``--user-step-type`` as state values (None when not given)."""
    text: str | None = args.user_step_type
    if not text:
        return None
    try:
        return tuple(int(v, 0) for v in text.replace(" ", "").split(",") if v)
    except ValueError:
        raise UsageError(
            f"--user-step-type {text!r} is not a list of integers (e.g. --user-step-type 1,3,2,0)"
        ) from None


def pulse_level(args: argparse.Namespace) -> int | None:
    """``--pulse-level``: 1 high, 0 low, None not given."""
    if args.pulse_level is None:
        return None
    return 1 if args.pulse_level == "high" else 0


def _int_option(text: str, option: str) -> int:
    try:
        return int(text)
    except ValueError:
        raise UsageError(f"{option} {text!r} is not a whole number (e.g. {option} 2)") from None


def _forward(text: str) -> int:
    if text not in ("low", "high"):
        raise UsageError(f"--dir-forward {text!r}: give low or high")
    return 1 if text == "high" else 0


def add_engine_arguments(p: Any) -> None:
    """Add ``--block-edges`` and ``--no-stream`` (how much the engine checks at a time)."""
    p.add_argument(
        "--block-edges",
        type=int,
        default=None,
        metavar="N",
        help="check about N edges at a time (memory follows N, not the capture's length; "
        f"default {CheckOptions.block_edges}); the results do not depend on it",
    )
    p.add_argument(
        "--no-stream",
        action="store_true",
        help="check the whole capture as one window (the same engine with one block: memory "
        "follows the capture; the results are the same)",
    )


def check_options(args: argparse.Namespace, *, with_drive: bool = True) -> CheckOptions:
    """The options object (:class:`~wavecheck.engine.options.CheckOptions`) of the mapping,
    capture, rule and configuration options of ``args`` (read each time: a command builds it
    once, before any capture). ``with_drive=False``: a command without a drive (``measure``).

    Raises:
        UsageError: a malformed option (the axes are checked against the capture later).
    """
    from wavecheck.cli._capture_args import resolution_from_args
    from wavecheck.cli._stepgen_args import latency_ns, stepgen_config
    from wavecheck.drives.library import load_drive

    drives: dict[str | None, Drive] = {}
    if with_drive:
        loaded: dict[str, Drive] = {}
        for axis, ref in split_per_axis(args.drive, "--drive").items():
            if ref not in loaded:
                loaded[ref] = load_drive(ref)
            drives[axis] = loaded[ref]
    types = {
        axis: _int_option(text, "--type")
        for axis, text in split_per_axis(args.type, "--type").items()
    }
    forward = {
        axis: _forward(text)
        for axis, text in split_per_axis(args.dir_forward, "--dir-forward").items()
    }
    block = WHOLE if getattr(args, "no_stream", False) else getattr(args, "block_edges", None)
    return CheckOptions(
        drive=drives,
        axes=tuple(parse_axes(args.map)) if args.map else (),
        invert=tuple(args.invert),
        step_type=types,
        forward_level=forward,
        user_table=user_table(args),
        pulse_level=pulse_level(args),
        active_edge=args.active_edge,
        resolution=resolution_from_args(args),
        limits=tuple(getattr(args, "limit", None) or ()),
        margin=getattr(args, "margin", None),
        stepgen=stepgen_config(args) if with_drive else None,
        latency_ns=latency_ns(args) if with_drive else None,
        keep_violations=kept_violations(args),
        block_edges=CheckOptions.block_edges if block is None else block,
        pictures=any(getattr(args, k, None) for k in ("plot", "html", "gtkw", "pulseview")),
        require=required(args),
    )


def kept_violations(args: argparse.Namespace) -> int:
    """Violations kept per rule: enough for every output's list."""
    from wavecheck.report.json import DEFAULT_VIOLATION_CAP
    from wavecheck.report.text import DEFAULT_TEXT_VIOLATIONS

    given = getattr(args, "max_violations", None) or 0
    return max(DEFAULT_VIOLATION_CAP, DEFAULT_TEXT_VIOLATIONS, given)
