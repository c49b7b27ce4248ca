"""Exact time: integer ticks and the rational length of one tick.

Edges are ``numpy.int64`` tick counts. A :class:`Timebase` knows what a tick is (an exact
:class:`~fractions.Fraction` of a second: the sample period of a ``.sr``, the ``$timescale`` of a
VCD) and converts limits to ticks with an explicit rounding direction, so a verdict can be kept
conservative. Seconds and nanoseconds appear only when printing.
"""

from __future__ import annotations

from fractions import Fraction
from functools import cached_property
from typing import TYPE_CHECKING, Literal

import numpy as np

from wavecheck.errors import UsageError
from wavecheck.record import record
from wavecheck.units import SI_TIME

if TYPE_CHECKING:
    import numpy.typing as npt

__all__ = ["Rounding", "Timebase"]

Rounding = Literal["floor", "ceil", "exact"]

_TIMESCALE_UNITS = dict(SI_TIME)


@record(frozen=True)
class Timebase:
    """The length of one tick, in exact seconds."""

    tick_s: Fraction

    def __post_init__(self) -> None:
        if self.tick_s <= 0:
            raise UsageError(f"a tick must be a positive time, got {self.tick_s} s")

    @classmethod
    def from_samplerate(cls, hz: Fraction | int) -> Timebase:
        """Tick = one sample period of a capture sampled at ``hz``."""
        hz = Fraction(hz)
        if hz <= 0:
            raise UsageError(f"sample rate must be positive, got {hz} Hz")
        return cls(1 / hz)

    @classmethod
    def from_timescale(cls, magnitude: int, unit: str) -> Timebase:
        """Tick = a VCD ``$timescale`` such as ``(10, "ns")``."""
        if unit not in _TIMESCALE_UNITS:
            raise UsageError(
                f"unknown timescale unit {unit!r} (known: {', '.join(_TIMESCALE_UNITS)})"
            )
        return cls(Fraction(magnitude) * Fraction(10) ** _TIMESCALE_UNITS[unit])

    @cached_property
    def tick_ns(self) -> Fraction:
        """One tick in exact nanoseconds."""
        return self.tick_s * 10**9

    @property
    def samplerate_hz(self) -> Fraction:
        """Ticks per second."""
        return 1 / self.tick_s

    def to_ticks(self, seconds: Fraction | int, rounding: Rounding) -> int:
        """Convert an exact duration in seconds to whole ticks.

        ``rounding="exact"`` raises if the duration is not a whole number of ticks.
        """
        ticks = Fraction(seconds) / self.tick_s
        if ticks.denominator == 1:
            return int(ticks)
        if rounding == "floor":
            return ticks.numerator // ticks.denominator
        if rounding == "ceil":
            return -((-ticks.numerator) // ticks.denominator)
        raise UsageError(
            f"{float(seconds * 10**9):g} ns is not a whole number of {float(self.tick_ns):g} ns ticks"
        )

    def ns_to_ticks(self, ns: Fraction | int, rounding: Rounding) -> int:
        """Convert exact nanoseconds to whole ticks (see :meth:`to_ticks`)."""
        return self.to_ticks(Fraction(ns) / 10**9, rounding)

    def seconds(self, ticks: int) -> Fraction:
        """Exact seconds of a tick count."""
        return ticks * self.tick_s

    def ns(self, ticks: int) -> Fraction:
        """Exact nanoseconds of a tick count."""
        return ticks * self.tick_ns

    def ns_array(self, ticks: npt.NDArray[np.int64]) -> npt.NDArray[np.float64]:
        """Nanoseconds of many tick counts as floats, for printing and plotting only."""
        return np.asarray(ticks, dtype=np.float64) * float(self.tick_ns)

    def describe(self) -> str:
        """Human text for the tick: ``"500 ns (2 MHz)"``."""
        from wavecheck.units import format_frequency, format_time

        return f"{format_time(self.tick_s)} ({format_frequency(self.samplerate_hz)})"
