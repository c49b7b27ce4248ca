"""Exact ticks: conversions round in the direction asked, or refuse."""

from fractions import Fraction

import pytest

from wavecheck.errors import UsageError
from wavecheck.timebase import Timebase


def test_samplerate_tick_is_exact() -> None:
    tb = Timebase.from_samplerate(12_000_000)
    assert tb.tick_s == Fraction(1, 12_000_000)
    assert tb.ns_to_ticks(1000, "exact") == 12
    assert tb.ns_to_ticks(4500, "floor") == 54
    assert tb.ns_to_ticks(4501, "floor") == 54
    assert tb.ns_to_ticks(4501, "ceil") == 55
    with pytest.raises(UsageError, match="not a whole number"):
        tb.ns_to_ticks(4501, "exact")


@pytest.mark.parametrize(
    ("mag", "unit", "tick"),
    [
        (1, "ns", Fraction(1, 10**9)),
        (10, "ps", Fraction(1, 10**11)),
        (100, "s", Fraction(100)),
        (1, "fs", Fraction(1, 10**15)),
    ],
)
def test_timescale(mag: int, unit: str, tick: Fraction) -> None:
    assert Timebase.from_timescale(mag, unit).tick_s == tick


def test_bad_timebase() -> None:
    with pytest.raises(UsageError):
        Timebase.from_samplerate(0)
    with pytest.raises(UsageError):
        Timebase.from_timescale(1, "xs")
