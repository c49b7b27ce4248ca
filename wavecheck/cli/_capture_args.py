"""Capture options shared by info, check, compare and crosscheck.

``--samplerate 12MHz``, ``--resolution 500ns``, ``--input-format csv``; values go through the
one units helper (:mod:`wavecheck.units`): a unit is required (a bare ``0`` excepted), and a
sample rate below 1 kHz is refused as a unit slip.
"""

from __future__ import annotations

import argparse
import os
from fractions import Fraction

from wavecheck.capture.blocks import BlockSource
from wavecheck.capture.edges import Capture
from wavecheck.capture.open import open_capture, open_source
from wavecheck.errors import UsageError
from wavecheck.units import SAMPLE_RATE, parse_option

__all__ = [
    "add_capture_arguments",
    "capture_from_args",
    "resolution_from_args",
    "samplerate_from_args",
    "source_from_args",
]


def add_capture_arguments(parser: argparse.ArgumentParser) -> None:
    """Add ``--samplerate``, ``--resolution`` and ``--input-format`` to ``parser``."""
    group = parser.add_argument_group("capture")
    group.add_argument(
        "--samplerate",
        metavar="RATE",
        help="sample rate of the capture, with its unit (e.g. 12MHz); needed when the file has "
        "none, overrides the file's; below 1 kHz is refused as a unit slip",
    )
    group.add_argument(
        "--resolution",
        metavar="TIME",
        help="time resolution of the capture, with its unit (e.g. 500ns, or 0), kept exact; "
        "default: one sample period (0 for a simulator VCD)",
    )
    group.add_argument(
        "--input-format",
        metavar="FMT",
        help="sr, vcd, or a sigrok-cli input format with options (csv, binary:numchannels=4, "
        "chronovu-la8, logicport, ...); default: detected",
    )
    group.add_argument(
        "--channels",
        metavar="NAMES",
        help="names of raw binary samples' channels, bit 0 first, comma-separated "
        "(e.g. EN,STEP,DIR); default sigrok-cli's 0, 1, ...",
    )


def resolution_from_args(args: argparse.Namespace) -> Fraction | None:
    """``--resolution`` in exact seconds (None when not given).

    Raises:
        UnitError: no unit, not a time, out of range, or negative.
    """
    res = getattr(args, "resolution", None)
    if res is None:
        return None
    seconds = parse_option(res, "--resolution", "time")
    if seconds < 0:
        raise UsageError(f"--resolution {res}: must not be negative")
    return seconds


def samplerate_from_args(args: argparse.Namespace) -> Fraction | None:
    """``--samplerate`` in exact Hz (None when not given).

    Raises:
        UnitError: no unit, not a frequency, below 1 kHz, or not positive.
    """
    rate = getattr(args, "samplerate", None)
    if rate is None:
        return None
    samplerate = parse_option(rate, "--samplerate", "frequency", SAMPLE_RATE)
    if samplerate <= 0:
        raise UsageError(f"--samplerate {rate}: must be positive")
    return samplerate


def capture_from_args(
    args: argparse.Namespace,
    path: str | os.PathLike[str],
    *,
    resolution: bool = True,
    require_time: bool = True,
) -> Capture:
    """Open ``path`` with the options added by :func:`add_capture_arguments`.

    ``resolution=False`` leaves ``--resolution`` to the caller (``check`` hands it to the engine,
    which keeps it exact; see :func:`resolution_from_args`).

    Raises:
        UnitError: a bad ``--samplerate``/``--resolution`` value.
        CaptureError: the file cannot be read.
    """
    samplerate = samplerate_from_args(args)
    resolution_s = resolution_from_args(args)
    return open_capture(
        path,
        samplerate=samplerate,
        resolution_s=resolution_s if resolution else None,
        input_format=getattr(args, "input_format", None),
        require_time=require_time,
        channel_names=_channel_names(getattr(args, "channels", None)),
    )


def source_from_args(args: argparse.Namespace, path: str | os.PathLike[str]) -> BlockSource:
    """``path`` as a block source (:func:`wavecheck.capture.open.open_source`) with the options
    added by :func:`add_capture_arguments`; ``--resolution`` is the engine's (exact).

    Raises:
        UnitError: a bad ``--samplerate`` value.
        CaptureError: the file cannot be read.
    """
    return open_source(
        path,
        samplerate=samplerate_from_args(args),
        input_format=getattr(args, "input_format", None),
        channel_names=_channel_names(getattr(args, "channels", None)),
        chunk_bytes=getattr(args, "chunk_bytes", None),
    )


def _channel_names(text: str | None) -> list[str] | None:
    """``--channels "EN,STEP (Y axis)"`` → the names, stripped (None when not given)."""
    if text is None:
        return None
    names = [n.strip() for n in text.split(",")]
    if any(not n for n in names):
        raise UsageError(f"--channels {text!r}: an empty name (give NAME,NAME,...)")
    return names
