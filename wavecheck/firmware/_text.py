"""Small helpers the firmware readers share: bounded reading, exact bounded numbers,
``file:line``."""

from __future__ import annotations

import os
import re
from fractions import Fraction

from wavecheck.config_text import MAX_CONFIG_BYTES, is_file, read_text
from wavecheck.errors import ConfigError, UnitError
from wavecheck.units import exact_number, shown

__all__ = ["MAX_CONFIG_BYTES", "is_file", "number", "read_text", "where"]

_SUFFIX = re.compile(r"(.*[\d.])[fFlLuU]+")


def number(
    text: str,
    place: str,
    what: str,
    *,
    low: Fraction | int | None = None,
    high: Fraction | int | None = None,
    unit: str = "",
) -> Fraction:
    """``text`` as an exact number (``"333.3333"``, ``"1e-6"``, ``"1000."``, C's ``2.5f``),
    within ``low``..``high`` when given.

    Raises:
        ConfigError: ``place: what 'text' …`` — not a number, NaN/inf, more than 40 digits or
            an exponent beyond ±40, or out of the range (the range is named).
    """
    raw = text.strip()
    suffixed = _SUFFIX.fullmatch(raw)
    try:
        value = exact_number(suffixed.group(1) if suffixed else raw)
    except UnitError as err:
        raise ConfigError(f"{place}: {what} {err}") from None
    if (low is not None and value < low) or (high is not None and value > high):
        span = f"{low if low is not None else '-inf'} .. {high if high is not None else 'inf'}"
        raise ConfigError(
            f"{place}: {what} {shown(raw)} is out of range ({span}{' ' + unit if unit else ''})"
        )
    return value


def where(path: str | os.PathLike[str], line: int) -> str:
    """``path:line``."""
    return f"{path}:{line}"
