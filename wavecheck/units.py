"""The one units helper: ``"4.5us"``, ``"200 ns"``, ``"2 MHz"``, ``"31kHz"`` to exact values.

Every option, rule file and stepgen setting goes through here. Values are exact
:class:`fractions.Fraction` in SI base units (seconds or hertz); nothing is a float until printed.

>>> parse_time("4.5us")
Fraction(9, 2000000)
>>> time_ns("200 ns")
Fraction(200, 1)
>>> parse_frequency("31kHz")
Fraction(31000, 1)
"""

from __future__ import annotations

import re
from decimal import Decimal, InvalidOperation
from fractions import Fraction
from typing import Literal

from wavecheck.errors import UnitError

__all__ = [
    "Dimension",
    "exact_ns",
    "format_frequency",
    "format_ns",
    "format_rate",
    "format_time",
    "json_number",
    "parse_frequency",
    "parse_quantity",
    "parse_time",
    "time_ns",
]

Dimension = Literal["time", "frequency"]

_TIME_UNITS: dict[str, Fraction] = {
    "s": Fraction(1),
    "sec": Fraction(1),
    "ms": Fraction(1, 10**3),
    "us": Fraction(1, 10**6),
    "µs": Fraction(1, 10**6),  # micro sign U+00B5
    "μs": Fraction(1, 10**6),  # Greek mu U+03BC
    "ns": Fraction(1, 10**9),
    "ps": Fraction(1, 10**12),
    "fs": Fraction(1, 10**15),
}
_FREQ_UNITS: dict[str, Fraction] = {
    "hz": Fraction(1),
    "khz": Fraction(10**3),
    "mhz": Fraction(10**6),
    "ghz": Fraction(10**9),
}
_NUMBER = r"[+-]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?"
_QUANTITY = re.compile(rf"^\s*({_NUMBER})\s*([A-Za-zµμ]*)\s*$")
_KNOWN = "s, ms, us (µs), ns, ps, fs, Hz, kHz, MHz, GHz"


def _exact(number: str, text: str) -> Fraction:
    try:
        return Fraction(Decimal(number))
    except (InvalidOperation, ValueError):
        raise UnitError(f"cannot read the number in {text!r}") from None


def parse_quantity(
    text: str | int | Fraction, default_unit: str | None = None
) -> tuple[Fraction, Dimension]:
    """Parse ``text`` into an exact value in SI base units and its dimension.

    Args:
        text: a number with a unit (``"4.5us"``, ``"31 kHz"``); an int or Fraction is taken as
            a bare number.
        default_unit: unit for a bare number (e.g. ``"ns"``); without it a bare number is an error.

    Raises:
        UnitError: unknown unit, missing unit, or unreadable number.
    """
    if isinstance(text, (int, Fraction)) and not isinstance(text, bool):
        number, unit = Fraction(text), ""
    elif isinstance(text, str):
        match = _QUANTITY.match(text)
        if not match:
            raise UnitError(f"cannot read {text!r} as a quantity (write e.g. '4.5us' or '31 kHz')")
        number, unit = _exact(match.group(1), text), match.group(2)
    else:
        raise UnitError(f"expected a quantity such as '4.5us', got {text!r}")
    if not unit:
        if default_unit is None:
            raise UnitError(f"{text!r} has no unit (write e.g. '{text}us' or '{text} kHz')")
        unit = default_unit
    if unit in _TIME_UNITS:
        return number * _TIME_UNITS[unit], "time"
    if unit.lower() in _FREQ_UNITS:
        return number * _FREQ_UNITS[unit.lower()], "frequency"
    raise UnitError(f"unknown unit {unit!r} in {text!r} (known units: {_KNOWN})")


def parse_time(text: str | int | Fraction, default_unit: str | None = None) -> Fraction:
    """Parse a duration; returns exact seconds. A frequency is refused (say which you meant)."""
    value, dim = parse_quantity(text, default_unit)
    if dim != "time":
        raise UnitError(f"{text!r} is a frequency where a time is expected (write e.g. '5us')")
    return value


def time_ns(text: str | int | Fraction, default_unit: str | None = None) -> Fraction:
    """Parse a duration; returns exact nanoseconds."""
    return parse_time(text, default_unit) * 10**9


def parse_frequency(text: str | int | Fraction, default_unit: str | None = None) -> Fraction:
    """Parse a frequency (``"2 MHz"``) or a period (``"500 ns"`` → 2 MHz); returns exact hertz."""
    value, dim = parse_quantity(text, default_unit)
    if dim == "time":
        if value <= 0:
            raise UnitError(f"period {text!r} must be positive to give a frequency")
        return 1 / value
    return value


_SCALES: tuple[tuple[Fraction, str], ...] = (
    (Fraction(1), "s"),
    (Fraction(1, 10**3), "ms"),
    (Fraction(1, 10**6), "us"),
    (Fraction(1, 10**9), "ns"),
    (Fraction(1, 10**12), "ps"),
    (Fraction(1, 10**15), "fs"),
)


def format_time(seconds: Fraction | int | float, digits: int = 4) -> str:
    """Format a duration for people: ``Fraction(9, 2000000)`` → ``"4.5 us"``."""
    value = Fraction(seconds) if not isinstance(seconds, float) else Fraction(seconds)
    if value == 0:
        return "0 s"
    for scale, unit in _SCALES:
        if abs(value) >= scale:
            return f"{float(value / scale):.{digits}g} {unit}"
    return f"{float(value / _SCALES[-1][0]):.{digits}g} fs"


def format_frequency(hz: Fraction | int | float, digits: int = 6) -> str:
    """Format a frequency for people: ``31250`` → ``"31.25 kHz"``."""
    value = float(hz)
    for scale, unit in ((1e9, "GHz"), (1e6, "MHz"), (1e3, "kHz")):
        if abs(value) >= scale:
            return f"{value / scale:.{digits}g} {unit}"
    return f"{value:.{digits}g} Hz"


def format_ns(ns: Fraction | None, *, signed: bool = False, missing: str = "-") -> str:
    """Format exact nanoseconds for a report cell: ``Fraction(4500)`` → ``"4.5 us"``.

    ``signed`` puts a ``+`` on positive values (margins); ``missing`` stands for None.
    """
    if ns is None:
        return missing
    text = format_time(Fraction(ns) / 10**9)
    return "+" + text if signed and ns > 0 else text


def format_rate(hz: Fraction | None, *, missing: str = "-") -> str:
    """Format a rate in Hz for a report cell (``missing`` stands for None)."""
    return missing if hz is None else format_frequency(hz)


def exact_ns(ns: Fraction | int) -> str:
    """Exact ns for tables of ns: ``11000``, ``15500``; a non-integer value to 6 digits
    (``10636.4``)."""
    v = Fraction(ns)
    return str(v.numerator) if v.denominator == 1 else f"{float(v):.6g}"


def json_number(value: Fraction | int | float | None) -> int | float | None:
    """A JSON number: an exact integer when the value is whole, else a float; None stays None."""
    if value is None:
        return None
    v = Fraction(value)
    return v.numerator if v.denominator == 1 else float(v)
