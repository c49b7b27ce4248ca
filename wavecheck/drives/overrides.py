"""Users' changes to a drive's figures: ``--limit RULE=VALUE`` and ``--margin 2x|+500ns``.

A changed :class:`~wavecheck.drives.datasheet.Figure` keeps the datasheet value in ``datasheet`` and
says how it was changed in ``applied``, so reports can show both. ``--limit`` sets one figure
(status ``user``); ``--margin`` tightens every figure the drive states: ``Nx`` multiplies each
minimum time by N (and divides the maximum rate by N), ``+T`` adds T to each minimum time (and
to the shortest step period 1 / max rate). A ``--limit`` figure is taken as given (no margin).
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from fractions import Fraction

from wavecheck.drives.datasheet import Drive, Figure
from wavecheck.errors import UnitError, UsageError
from wavecheck.record import record, replace
from wavecheck.rules import TIME_RULES
from wavecheck.units import parse_frequency, parse_quantity

__all__ = ["Margin", "parse_limit", "parse_margin", "tune_drive"]

_GIGA = Fraction(10**9)


@record(frozen=True)
class Margin:
    """``factor`` × each minimum time, then + ``add_ns``."""

    factor: Fraction = Fraction(1)
    add_ns: Fraction = Fraction(0)
    text: str = ""

    def time(self, ns: Fraction) -> Fraction:
        """A minimum time with the margin."""
        return ns * self.factor + self.add_ns

    def rate(self, hz: Fraction) -> Fraction:
        """A maximum rate with the margin (its period tightened like a time)."""
        return _GIGA / self.time(_GIGA / hz)


def parse_margin(text: str) -> Margin:
    """``"2x"`` → ×2; ``"+500ns"`` → +500 ns (a unit is required)."""
    t = text.strip()
    m = re.fullmatch(r"([0-9.]+)\s*[xX×]", t)
    if m:
        factor = Fraction(m.group(1))
        if factor < 1:
            raise UsageError(f"--margin {text!r}: a factor below 1 would loosen the limits")
        return Margin(factor=factor, text=t)
    if t.startswith("+"):
        value, dim = parse_quantity(t[1:])
        if dim != "time":
            raise UsageError(f"--margin {text!r}: expected a time such as +500ns")
        return Margin(add_ns=value * _GIGA, text=t)
    raise UsageError(f"--margin {text!r}: write a factor (2x) or an added time (+500ns)")


def parse_limit(text: str) -> tuple[str, Fraction]:
    """``"step_high=5us"`` → (rule, ns); ``"max_rate=100kHz"`` → (``max_rate``, Hz)."""
    rule, sep, value = text.partition("=")
    rule = rule.strip()
    allowed = (*TIME_RULES, "max_rate")
    if not sep or rule not in allowed:
        raise UsageError(
            f"--limit {text!r}: write RULE=VALUE with RULE one of {', '.join(allowed)}"
        )
    try:
        if rule == "max_rate":
            hz = parse_frequency(value)
        else:
            v, dim = parse_quantity(value)
    except UnitError as err:  # the value's own message, with the option it came in
        raise UsageError(f"--limit {text!r}: {err}") from None
    if rule == "max_rate":
        if hz <= 0:
            raise UsageError(f"--limit {text!r}: the rate must be positive")
        return rule, hz
    if dim != "time" or v < 0:
        raise UsageError(f"--limit {text!r}: expected a time >= 0 with a unit, e.g. {rule}=5us")
    return rule, v * _GIGA


def tune_drive(drive: Drive, limits: Sequence[str] = (), margin: str | None = None) -> Drive:
    """``drive`` with ``--limit`` texts and a ``--margin`` applied (unchanged when neither)."""
    if not limits and not margin:
        return drive
    m = parse_margin(margin) if margin else None
    figures = dict(drive.limits)
    rate = drive.max_rate
    if m is not None:
        for rule, fig in figures.items():
            figures[rule] = replace(
                fig, value=m.time(fig.value), datasheet=fig.value, applied=f"--margin {m.text}"
            )
        if rate is not None:
            rate = replace(
                rate, value=m.rate(rate.value), datasheet=rate.value, applied=f"--margin {m.text}"
            )
    for text in limits:
        rule, value = parse_limit(text)
        old = rate if rule == "max_rate" else drive.limits.get(rule)
        fig = Figure(
            value,
            "command line",
            "user",
            f"--limit {text}",
            datasheet=old.value if old else None,
            applied=f"--limit {text.strip()}",
        )
        if rule == "max_rate":
            rate = fig
        else:
            figures[rule] = fig
    sources = {**drive.sources, "command line": "wavecheck --limit option"}
    return replace(drive, limits=figures, max_rate=rate, sources=sources)
