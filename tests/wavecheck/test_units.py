"""The one units helper: exact values from '4.5us', '200 ns', '2 MHz', '31kHz'."""

from fractions import Fraction

import pytest

from wavecheck.errors import UnitError
from wavecheck.units import format_frequency, format_time, parse_frequency, parse_time, time_ns


@pytest.mark.parametrize(
    ("text", "seconds"),
    [
        ("4.5us", Fraction(9, 2_000_000)),
        ("200 ns", Fraction(1, 5_000_000)),
        ("4.5 µs", Fraction(9, 2_000_000)),
        ("4.5 μs", Fraction(9, 2_000_000)),
        ("1s", Fraction(1)),
        ("25 ms", Fraction(1, 40)),
        ("1 fs", Fraction(1, 10**15)),
        ("0.1ps", Fraction(1, 10**13)),
        ("1e3 ns", Fraction(1, 10**6)),
        ("0ns", Fraction(0)),
    ],
)
def test_parse_time_exact(text: str, seconds: Fraction) -> None:
    assert parse_time(text) == seconds


@pytest.mark.parametrize(
    ("text", "hz"),
    [("2 MHz", 2_000_000), ("31kHz", 31_000), ("12.5 MHz", 12_500_000), ("1 GHz", 10**9),
     ("200 khz", 200_000), ("500 ns", 2_000_000)],
)
def test_parse_frequency_exact(text: str, hz: int) -> None:
    assert parse_frequency(text) == hz


def test_time_ns_and_default_unit() -> None:
    assert time_ns("4.5us") == 4500
    assert time_ns("11", default_unit="us") == 11_000
    assert time_ns(20000, default_unit="ns") == 20000


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("4.5 furlongs", r"unknown unit 'furlongs' in '4\.5 furlongs'"),
        ("4.5", r"'4\.5' has no unit"),
        ("fast", r"cannot read 'fast' as a quantity"),
        ("31 kHz", r"is a frequency where a time is expected"),
        ("", r"cannot read '' as a quantity"),
    ],
)
def test_bad_units_are_clear_errors(text: str, message: str) -> None:
    with pytest.raises(UnitError, match=message):
        parse_time(text)


def test_format() -> None:
    assert format_time(Fraction(9, 2_000_000)) == "4.5 us"
    assert format_time(Fraction(0)) == "0 s"
    assert format_frequency(31250) == "31.25 kHz"


def test_report_cell_formats() -> None:
    from wavecheck.units import format_ns, format_rate

    assert format_ns(Fraction(4500)) == "4.5 us"
    assert format_ns(Fraction(1000), signed=True) == "+1 us"
    assert format_ns(Fraction(-833), signed=True) == "-833 ns"
    assert format_ns(None) == "-" and format_ns(None, missing="–") == "–"
    assert format_rate(Fraction(31250)) == "31.25 kHz" and format_rate(None) == "-"
