"""Options that ``simulate grbl`` and ``simulate klipper`` share: source trees and time bounds."""

from __future__ import annotations

import argparse
import os
from fractions import Fraction
from pathlib import Path

from wavecheck.errors import UsageError
from wavecheck.units import parse_time

__all__ = ["seconds", "source"]

#: Where the project's tests keep the public sources (a user names their own checkout).
_SHARED = Path("..") / "shared" / "firmware-src"
_DEFAULTS = {
    "grbl_src": ("WAVECHECK_GRBL_SRC", _SHARED / "grbl-1.1h"),
    "simavr_src": ("WAVECHECK_SIMAVR_SRC", _SHARED / "simavr"),
    "klipper_src": ("WAVECHECK_KLIPPER_SRC", _SHARED / "klipper"),
}


def source(args: argparse.Namespace, name: str) -> Path:
    """The source tree ``--NAME`` names, else ``$WAVECHECK_NAME``, else the shared copy."""
    given = getattr(args, name)
    env, default = _DEFAULTS[name]
    path = Path(given or os.environ.get(env) or default)
    if not path.is_dir():
        option = "--" + name.replace("_", "-")
        raise UsageError(f"{path}: no such folder: give the source tree with {option} or ${env}")
    return path


def seconds(text: str, option: str) -> Fraction:
    """A positive time option, in seconds."""
    value = parse_time(text)
    if value <= 0:
        raise UsageError(f"{option} {text}: must be more than 0")
    return value
