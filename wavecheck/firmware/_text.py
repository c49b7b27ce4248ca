"""Small helpers the firmware readers share: exact numbers, reading a file, ``file:line``."""

from __future__ import annotations

import os
from decimal import Decimal, InvalidOperation
from fractions import Fraction
from pathlib import Path

from wavecheck.errors import ConfigError

__all__ = ["MAX_BYTES", "number", "read_text", "where"]

#: Configuration files are small; anything larger is not one (bounded memory on hostile input).
MAX_BYTES = 8 * 1024 * 1024


def read_text(path: str | os.PathLike[str]) -> str:
    """The file as text (undecodable bytes replaced); ConfigError when unreadable or huge."""
    p = Path(path)
    try:
        size = p.stat().st_size
        if size > MAX_BYTES:
            raise ConfigError(f"{path}: {size} bytes is too large for a configuration file")
        return p.read_text(encoding="utf-8", errors="replace")
    except OSError as err:
        raise ConfigError(f"{path}: cannot read: {err.strerror or err}") from None


def number(text: str, place: str, what: str) -> Fraction:
    """``text`` as an exact number (``"333.3333"``, ``"1e-6"``, ``"1000."``)."""
    try:
        value = Fraction(Decimal(text.strip().rstrip("fFlLuU")))
    except (InvalidOperation, ValueError, OverflowError):
        raise ConfigError(f"{place}: {what} {text.strip()!r} is not a number") from None
    return value


def where(path: str | os.PathLike[str], line: int) -> str:
    """``path:line``."""
    return f"{path}:{line}"
