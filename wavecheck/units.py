"""The one units helper: ``"4.5us"``, ``"200 ns"``, ``"2 MHz"``, ``"31kHz"`` to exact values.

Every option, rule file and stepgen setting goes through here. Values are exact
:class:`fractions.Fraction` in SI base units (seconds or hertz); nothing is a float until printed.

Numbers and units, the one policy of both tools (docs/reference.md "Numbers and units"):

* On the command line and in rule and ``wavecheck.toml`` files a time or a frequency carries its
  unit (``16us``, ``12 MHz``). A bare number is refused with the fix spelled out
  (``--base-period 16: give a unit, e.g. 16us or 16000ns``), see :func:`parse_option`. The one
  exception is ``0``, which is zero in every unit.
* Numbers inside LinuxCNC's own files (INI ``BASE_PERIOD``, HAL ``setp stepgen.0.steplen``) stay
  bare ns, as LinuxCNC reads them; a latency file (cyclictest, ``latency-histogram``,
  ``~/.latency``) and a sigrok ``.sr`` file's metadata keep their own documented units. Their
  readers pass ``default_unit``.
* A value outside what any capture or machine can mean (``1e400us``, ``1e-400 Hz``, a time
  beyond 10^9 s or below 1 fs) is a :class:`~wavecheck.errors.UnitError`; a refused value is
  shown shortened, never as a 400-digit number.
* A plain number (a scale, a gain, a plant figure; a number in a data file) is read by
  :func:`parse_number` / :func:`finite_float` / :func:`parse_int`: NaN, infinity, more than 40
  significant digits, an exponent beyond 40 and a magnitude beyond :data:`MAX_NUMBER` are
  refused in one line (:func:`number_option` is the ``argparse`` type of such options).
* Values that are almost surely a unit slip are judged by :func:`check_plausible` with an
  option's :class:`Plausible` bounds: a base period below 1 us and a sample rate below 1 kHz are
  refused, a latency below 100 ns (other than 0) is warned about on stderr.

>>> parse_time("4.5us")
Fraction(9, 2000000)
>>> time_ns("200 ns")
Fraction(200, 1)
>>> parse_frequency("31kHz")
Fraction(31000, 1)
"""

from __future__ import annotations

import math
import re
import sys
from collections.abc import Callable
from decimal import Decimal, InvalidOperation
from fractions import Fraction
from typing import TYPE_CHECKING, Literal

from wavecheck.errors import UnitError
from wavecheck.record import record

if TYPE_CHECKING:
    import numpy.typing as npt

__all__ = [
    "BASE_PERIOD",
    "LATENCY",
    "SAMPLE_RATE",
    "Dimension",
    "Plausible",
    "check_plausible",
    "check_finite",
    "exact_ns",
    "exact_number",
    "finite_float",
    "format_frequency",
    "format_ns",
    "format_rate",
    "format_time",
    "is_bare_number",
    "is_number",
    "json_number",
    "number_option",
    "option_ns",
    "parse_frequency",
    "parse_int",
    "parse_number",
    "parse_option",
    "parse_quantity",
    "parse_time",
    "shorten",
    "shown",
    "time_ns",
]

Dimension = Literal["time", "frequency"]

#: THE table of time units: name → power of ten of a second, coarsest first (VCD's timescale
#: units; the parser, the formatters, the timebase and the writers all take theirs from it).
SI_TIME: tuple[tuple[str, int], ...] = (
    ("s", 0),
    ("ms", -3),
    ("us", -6),
    ("ns", -9),
    ("ps", -12),
    ("fs", -15),
    ("as", -18),
    ("zs", -21),
)
_TIME_UNITS: dict[str, Fraction] = {
    **{name: Fraction(10) ** exp for name, exp in SI_TIME[:6]},  # options: s down to fs
    "sec": Fraction(1),
    "µs": Fraction(1, 10**6),  # micro sign U+00B5
    "μs": Fraction(1, 10**6),  # Greek mu U+03BC
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


#: Largest decimal exponent a written number may have (before its unit): beyond this it cannot
#: be a time or frequency of a capture or a machine, and exact arithmetic on it would be costly.
_MAX_EXPONENT = 40
#: Most significant digits a written number may have.
_MAX_DIGITS = 40
#: The magnitudes a nonzero quantity may have, in SI base units (1 fs to 10^9 s; 10^-9 Hz to
#: 10^15 Hz, so that every period is a time in range too).
_RANGE: dict[Dimension, tuple[Fraction, Fraction, str]] = {
    "time": (Fraction(1, 10**15), Fraction(10**9), "1 fs to 1e9 s"),
    "frequency": (Fraction(1, 10**9), Fraction(10**15), "1e-9 Hz to 1e15 Hz"),
}


class _Bad(UnitError):
    """A UnitError that also knows its reason without the value (for an option's message)."""

    def __init__(self, message: str, reason: str) -> None:
        super().__init__(message)
        self.reason = reason


def shorten(text: object, limit: int = 24) -> str:
    """``text`` for a message, shortened to about ``limit`` characters (``1111…1111us``)."""
    s = str(text)
    if len(s) <= limit:
        return s
    keep = max(limit // 2 - 2, 4)
    return s[:keep] + "…" + s[-keep:]


def shown(text: object) -> str:
    """``text`` quoted for a message, shortened (:func:`shorten`)."""
    return repr(shorten(text))


def _exact(number: str, text: str) -> Fraction:
    try:
        d = Decimal(number)
    except (InvalidOperation, ValueError):
        raise _Bad(f"cannot read the number in {shown(text)}", "cannot read the number") from None
    if not d.is_finite():
        raise _Bad(f"cannot read the number in {shown(text)}", "cannot read the number")
    if d and (abs(d.adjusted()) > _MAX_EXPONENT or len(d.as_tuple().digits) > _MAX_DIGITS):
        why = "out of range (too many digits or too large an exponent)"
        raise _Bad(f"{shown(text)} is {why}", why)
    return Fraction(d)


def _in_range(value: Fraction, dim: Dimension, text: object) -> None:
    low, high, span = _RANGE[dim]
    if value and not low <= abs(value) <= high:
        why = f"out of range (a {dim} is from {span})"
        raise _Bad(f"{shown(text)} is {why}", why)


_BARE = re.compile(rf"^\s*({_NUMBER})\s*$")


def exact_number(text: str) -> Fraction:
    """A bare number as written in a file (``"333.3333"``, ``"1e-6"``, ``"1000."``), exact, with
    the bounds of every number here: NaN, infinities, more than 40 significant digits and
    exponents beyond ±40 are refused (a :class:`~wavecheck.errors.UnitError` whose ``reason``
    says why), so ``1e999999999`` costs no time.

    >>> exact_number("2.5e-6")
    Fraction(1, 400000)
    """
    match = _BARE.match(text)
    if not match:
        raise _Bad(f"{shown(text)} is not a number", "not a number")
    return _exact(match.group(1), text)


def is_number(text: object) -> bool:
    """True if ``text`` is written as a number, with or without a unit (``"11"``, ``"11us"``,
    ``"1e400 s"``), as opposed to a name such as a file path."""
    return isinstance(text, str) and _QUANTITY.match(text) is not None


def is_bare_number(text: object) -> bool:
    """True if ``text`` is a number written without a unit (``"16"``, ``"1e3"``, ``16``)."""
    if isinstance(text, (int, Fraction)) and not isinstance(text, bool):
        return True
    if not isinstance(text, str):
        return False
    match = _QUANTITY.match(text)
    return match is not None and not match.group(2)


def parse_quantity(
    text: str | int | Fraction, default_unit: str | None = None
) -> tuple[Fraction, Dimension]:
    """Parse ``text`` into an exact value in SI base units and its dimension.

    Args:
        text: a number with a unit (``"4.5us"``, ``"31 kHz"``); an int or Fraction is taken as
            a bare number.
        default_unit: unit for a bare number, only for the fields of files that define one
            (LinuxCNC's bare ns, a ``.sr`` file's bare Hz); without it a bare number is an error.

    Raises:
        UnitError: unknown unit, missing unit, unreadable number, or a value out of range.
    """
    if isinstance(text, (int, Fraction)) and not isinstance(text, bool):
        number, unit = Fraction(text), ""
    elif isinstance(text, str):
        match = _QUANTITY.match(text)
        if not match:
            raise _Bad(
                f"cannot read {shown(text)} as a quantity (write e.g. '4.5us' or '31 kHz')",
                "not a quantity (write e.g. '4.5us' or '31 kHz')",
            )
        number, unit = _exact(match.group(1), text), match.group(2)
    else:
        raise _Bad(
            f"expected a quantity such as '4.5us', got {shown(text)}",
            "not a quantity (write e.g. '4.5us' or '31 kHz')",
        )
    if not unit:
        if default_unit is None:
            raise _Bad(
                f"{shown(text)} has no unit (write e.g. '{text}us' or '{text} kHz')", "no unit"
            )
        unit = default_unit
    dim: Dimension
    if unit in _TIME_UNITS:
        value, dim = number * _TIME_UNITS[unit], "time"
    elif unit.lower() in _FREQ_UNITS:
        value, dim = number * _FREQ_UNITS[unit.lower()], "frequency"
    else:
        raise _Bad(
            f"unknown unit {shown(unit)} in {shown(text)} (known units: {_KNOWN})",
            f"unknown unit {shown(unit)} (known units: {_KNOWN})",
        )
    _in_range(value, dim, text)
    return value, dim


def parse_time(text: str | int | Fraction, default_unit: str | None = None) -> Fraction:
    """Parse a duration; returns exact seconds. A frequency is refused (say which you meant)."""
    value, dim = parse_quantity(text, default_unit)
    if dim != "time":
        why = "a frequency where a time is expected (write e.g. '5us')"
        raise _Bad(f"{shown(text)} is {why}", why)
    return value


def time_ns(text: str | int | Fraction, default_unit: str | None = None) -> Fraction:
    """Parse a duration; returns exact nanoseconds."""
    return parse_time(text, default_unit) * 10**9


def parse_frequency(text: str | int | Fraction, default_unit: str | None = None) -> Fraction:
    """Parse a frequency (``"2 MHz"``) or a period (``"500 ns"`` → 2 MHz); returns exact hertz."""
    value, dim = parse_quantity(text, default_unit)
    if dim == "time":
        if value <= 0:
            why = "a period must be positive to give a frequency"
            raise _Bad(f"period {shown(text)} must be positive to give a frequency", why)
        return 1 / value
    return value


# -- plain numbers -----------------------------------------------------------------------------
#: The largest magnitude of a plain number (no unit): beyond it no scale, gain, plant figure or
#: value in a data file means anything, and float arithmetic on it overflows.
MAX_NUMBER = 10**15


def parse_number(text: object, what: str, *, limit: int | Fraction = MAX_NUMBER) -> Fraction:
    """A plain number (no unit) written in ``text``, exact; ``what`` names it in the message
    (``"--scale"``, ``"line 3"``).

    Raises:
        UnitError: not a number, NaN or infinity, too many digits, or beyond ``limit``.
    """
    t = str(text).strip()
    if not re.fullmatch(_NUMBER, t):
        why = "nan/inf is not a number here" if t.lower().lstrip("+-") in _NON_FINITE else ""
        raise UnitError(f"{what} {shown(t)}: {why or 'not a number'}")
    try:
        value = _exact(t, t)
    except _Bad as err:
        raise UnitError(f"{what} {shown(t)}: {err.reason}") from None
    if abs(value) > limit:
        raise UnitError(f"{what} {shown(t)}: out of range (at most {_magnitude(limit)})")
    return value


def _magnitude(limit: int | Fraction) -> str:
    return f"{float(limit):.3g} in magnitude".replace("e+", "e")


_NON_FINITE = ("nan", "inf", "infinity", "snan")


def finite_float(text: object, what: str, *, limit: int | Fraction = MAX_NUMBER) -> float:
    """:func:`parse_number` as a float (finite, at most ``limit`` in magnitude)."""
    return float(parse_number(text, what, limit=limit))


def parse_int(text: object, what: str, *, limit: int = 2**62) -> int:
    """A whole number written in ``text`` (digits, optional sign), at most ``limit`` in
    magnitude; the digits are counted before any conversion, so a 5,000-digit number costs
    nothing.

    Raises:
        UnitError: not a whole number, or beyond ``limit``.
    """
    t = str(text).strip()
    digits = t.lstrip("+-")
    if not digits.isascii() or not digits.isdigit() or len(t) - len(digits) > 1:
        raise UnitError(f"{what} {shown(t)}: not a whole number")
    if len(digits.lstrip("0")) > len(str(limit)) or abs(int(t)) > limit:
        raise UnitError(f"{what} {shown(t)}: out of range (at most {_magnitude(limit)})")
    return int(t)


def check_finite(
    values: npt.ArrayLike, where: Callable[[int], str], *, limit: int | Fraction = MAX_NUMBER
) -> None:
    """Refuse the first of ``values`` (numbers read with ``float()`` from a data file) that is
    NaN, infinite (an overflowed ``1e999`` too) or beyond ``limit``; ``where(i)`` names the place
    of value ``i`` (``"file: line 7"``).

    Raises:
        UnitError: one line naming the place and the value.
    """
    import numpy as np

    a = np.asarray(values, dtype=np.float64)
    bad = np.flatnonzero(~(np.abs(a) <= float(limit)))  # NaN compares false
    if len(bad):
        i = int(bad[0])
        v = float(a[i])
        why = "not a finite number" if not math.isfinite(v) else f"beyond {_magnitude(limit)}"
        raise UnitError(f"{where(i)}: {shorten(repr(v))} is {why}")


def number_option(text: str) -> float:
    """``argparse`` ``type=`` of a plain-number option: :func:`finite_float` (the option's
    name is added by argparse: ``argument --inertia: '1e308': out of range …``)."""
    import argparse

    try:
        return finite_float(text, "")
    except UnitError as err:
        raise argparse.ArgumentTypeError(str(err).strip()) from None


# -- command-line options ----------------------------------------------------------------------
@record(frozen=True)
class Plausible:
    """Values of an option that are almost surely a unit slip (SI base units: s or Hz).

    A nonzero value below ``refuse_below`` is refused (exit 2), one below ``warn_below`` is
    warned about on stderr; ``typical`` says what real values are. Zero is never judged here
    (it means "none"; each option decides whether it allows it).
    """

    what: str
    typical: str
    refuse_below: Fraction | None = None
    warn_below: Fraction | None = None
    frequency: bool = False


#: LinuxCNC's software base thread cannot run faster than about 1 us: refused below.
BASE_PERIOD = Plausible(
    "a base period", "LinuxCNC base threads run at 10-100 us", refuse_below=Fraction(1, 10**6)
)
#: A logic analyzer below 1 kHz cannot resolve a step pulse: refused below.
SAMPLE_RATE = Plausible(
    "a sample rate",
    "logic analyzers sample at 1-500 MHz",
    refuse_below=Fraction(1000),
    frequency=True,
)
#: A base-thread latency below 100 ns is not a PC's: warned about (the run goes on).
LATENCY = Plausible(
    "a latency", "a PC's base-thread latency is 1-100 us", warn_below=Fraction(100, 10**9)
)


def _stderr(message: str) -> None:
    print(f"warning: {message}", file=sys.stderr)


def _suggest(number: str, dimension: Dimension) -> str:
    """The fix for a bare ``number``: ``16us or 16000ns`` (``12MHz or 12kHz``); empty for a
    number no unit could make sensible."""
    try:
        d = Decimal(number)
    except InvalidOperation:  # pragma: no cover - matched as a number already
        return ""
    if not d.is_finite() or abs(d.adjusted()) > 9:
        return ""
    if dimension == "frequency":
        return f", e.g. {number}MHz or {number}kHz"
    return f", e.g. {number}us or {d.scaleb(3).normalize():f}ns"


def check_plausible(
    value: Fraction,
    option: str,
    text: object,
    bounds: Plausible,
    warn: Callable[[str], None] | None = None,
) -> None:
    """Refuse or warn about ``value`` (of ``option``, written ``text``) when ``bounds`` say it is
    almost surely a unit slip; ``warn`` takes the warning (default: a line on stderr).

    Raises:
        UnitError: below ``bounds.refuse_below``.
    """
    if not value:
        return
    size = abs(value)
    fmt = format_frequency if bounds.frequency else format_time
    if bounds.refuse_below is not None and size < bounds.refuse_below:
        raise UnitError(
            f"{option} {shorten(text)}: {fmt(size)} is below {fmt(bounds.refuse_below)}, "
            f"implausible for {bounds.what} ({bounds.typical}); check the unit"
        )
    if bounds.warn_below is not None and size < bounds.warn_below:
        (warn or _stderr)(
            f"{option} {shorten(text)}: {fmt(size)} is below {fmt(bounds.warn_below)}, "
            f"unusual for {bounds.what} ({bounds.typical}); check the unit"
        )


def parse_option(
    text: str,
    option: str,
    dimension: Dimension,
    plausible: Plausible | None = None,
    warn: Callable[[str], None] | None = None,
) -> Fraction:
    """A command-line or ``wavecheck.toml`` value of ``option``: exact seconds or hertz.

    A time or a frequency needs its unit; a bare number other than ``0`` is refused with the
    fix spelled out. A frequency option also takes a period (``"500ns"`` → 2 MHz). With
    ``plausible``, :func:`check_plausible` judges the value.

    Raises:
        UnitError: one line naming the option: no unit, unknown unit, wrong dimension, out of
            range, or refused as implausible.
    """
    stripped = str(text).strip()
    if is_bare_number(stripped):
        try:
            zero = not Decimal(stripped)
        except InvalidOperation:  # pragma: no cover - matched as a number
            zero = False
        if zero:
            return Fraction(0)
        hint = _suggest(stripped, dimension) if len(stripped) <= 24 else ""
        raise UnitError(f"{option} {shorten(stripped)}: give a unit{hint}")
    try:
        if dimension == "time":
            value = parse_time(stripped)
        else:
            value = parse_frequency(stripped)
    except _Bad as err:
        raise UnitError(f"{option} {shorten(stripped)}: {err.reason}") from None
    if plausible is not None:
        check_plausible(value, option, stripped, plausible, warn)
    return value


def option_ns(
    text: str,
    option: str,
    plausible: Plausible | None = None,
    warn: Callable[[str], None] | None = None,
) -> Fraction:
    """:func:`parse_option` for a time, in exact nanoseconds."""
    return parse_option(text, option, "time", plausible, warn) * 10**9


_SCALES: tuple[tuple[Fraction, str], ...] = tuple(
    (Fraction(10) ** exp, name) for name, exp in SI_TIME[:6]
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
