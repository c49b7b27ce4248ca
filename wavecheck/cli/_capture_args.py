"""Capture options shared by info, check, compare and crosscheck.

``--samplerate 12MHz``, ``--resolution 500ns``, ``--input-format csv``; values go through the
one units helper (:mod:`wavecheck.units`).
"""

from __future__ import annotations

import argparse
import os

from wavecheck.capture.model import Capture
from wavecheck.capture.open import open_capture
from wavecheck.errors import UnitError
from wavecheck.units import parse_frequency, parse_time

__all__ = ["add_capture_arguments", "capture_from_args"]


def add_capture_arguments(parser: argparse.ArgumentParser) -> None:
    """Add ``--samplerate``, ``--resolution`` and ``--input-format`` to ``parser``."""
    group = parser.add_argument_group("capture")
    group.add_argument(
        "--samplerate",
        metavar="RATE",
        help="sample rate of the capture (e.g. 12MHz); needed when the file has none, "
        "overrides the file's",
    )
    group.add_argument(
        "--resolution",
        metavar="TIME",
        help="time resolution of the capture (e.g. 500ns); default: one sample period "
        "(0 for a simulator VCD)",
    )
    group.add_argument(
        "--input-format",
        metavar="FMT",
        help="sr, vcd, or a sigrok-cli input format with options (csv, binary:numchannels=4, "
        "chronovu-la8, logicport, ...); default: detected",
    )


def capture_from_args(
    args: argparse.Namespace, path: str | os.PathLike[str], *, require_time: bool = True
) -> Capture:
    """Open ``path`` with the options added by :func:`add_capture_arguments`.

    Raises:
        UnitError: a bad ``--samplerate``/``--resolution`` value.
        CaptureError: the file cannot be read.
    """
    rate = getattr(args, "samplerate", None)
    res = getattr(args, "resolution", None)
    try:
        samplerate = parse_frequency(rate, default_unit="Hz") if rate else None
    except UnitError as err:
        raise UnitError(f"--samplerate: {err}") from None
    try:
        resolution_s = parse_time(res) if res else None
    except UnitError as err:
        raise UnitError(f"--resolution: {err}") from None
    return open_capture(
        path,
        samplerate=samplerate,
        resolution_s=resolution_s,
        input_format=getattr(args, "input_format", None),
        require_time=require_time,
    )
