"""The one units helper: exact values from '4.5us', '200 ns', '2 MHz', '31kHz'."""

from fractions import Fraction

import pytest

from wavecheck.errors import UnitError
from wavecheck.units import (
    check_finite,
    finite_float,
    format_frequency,
    format_time,
    parse_frequency,
    parse_int,
    parse_number,
    parse_time,
    time_ns,
)


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
    [
        ("2 MHz", 2_000_000),
        ("31kHz", 31_000),
        ("12.5 MHz", 12_500_000),
        ("1 GHz", 10**9),
        ("200 khz", 200_000),
        ("500 ns", 2_000_000),
    ],
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


# -- the one policy for options (README "Numbers and units") -----------------------------------
@pytest.mark.parametrize(
    ("text", "dimension", "message"),
    [
        ("16", "time", "--x 16: give a unit, e.g. 16us or 16000ns"),
        ("0.5", "time", "--x 0.5: give a unit, e.g. 0.5us or 500ns"),
        ("12", "frequency", "--x 12: give a unit, e.g. 12MHz or 12kHz"),
        ("1e400", "time", "--x 1e400: give a unit"),
        ("3 parsecs", "time", "--x 3 parsecs: unknown unit 'parsecs'"),
        ("31kHz", "time", "--x 31kHz: a frequency where a time is expected"),
        ("fast", "frequency", "--x fast: not a quantity"),
    ],
)
def test_parse_option_needs_a_unit(text: str, dimension: str, message: str) -> None:
    from wavecheck.units import parse_option

    with pytest.raises(UnitError) as info:
        parse_option(text, "--x", dimension)  # type: ignore[arg-type]
    assert str(info.value).startswith(message)


@pytest.mark.parametrize(
    ("text", "value"),
    [("0", 0), ("-0", 0), ("0.0", 0), ("16us", Fraction(16, 10**6)), ("2 MHz", 2_000_000)],
)
def test_parse_option_values(text: str, value: Fraction) -> None:
    from wavecheck.units import parse_option

    dimension = "frequency" if "Hz" in text else "time"
    assert parse_option(text, "--x", dimension) == value  # type: ignore[arg-type]


BIG = "1" * 400


@pytest.mark.parametrize(
    ("call", "text"),
    [
        (parse_time, "1e400us"),
        (parse_time, "1e-400 s"),
        (parse_time, BIG + "us"),
        (parse_time, "0." + "0" * 400 + "1 s"),
        (parse_time, "1e10 s"),  # past 1e9 s
        (parse_time, "0.1 fs"),  # below 1 fs
        (parse_frequency, "1e-400 Hz"),
        (parse_frequency, "1e400Hz"),
        (parse_frequency, "1e16 Hz"),
        (parse_frequency, "1e-400"),  # as a .sr file's bare Hz
        (time_ns, "1e999999999 ns"),  # not computed: refused from its exponent
    ],
)
def test_out_of_range_is_a_short_unit_error(call, text: str) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(UnitError, match="out of range") as info:
        call(text, default_unit="Hz") if call is parse_frequency else call(text)
    assert len(str(info.value)) < 120 and "1111111111111111" not in str(info.value)


def test_rule_file_values_out_of_range_are_clean() -> None:
    from wavecheck.units import parse_quantity

    with pytest.raises(UnitError, match="out of range"):
        parse_quantity("1e400us")


def test_plausibility_refuses_and_warns() -> None:
    from wavecheck.units import BASE_PERIOD, LATENCY, SAMPLE_RATE, check_plausible, parse_option

    with pytest.raises(UnitError, match=r"--base-period 999ns: 999 ns is below 1 us"):
        parse_option("999ns", "--base-period", "time", BASE_PERIOD)
    assert parse_option("1us", "--base-period", "time", BASE_PERIOD) == Fraction(1, 10**6)
    with pytest.raises(UnitError, match=r"--samplerate 999Hz: 999 Hz is below 1 kHz"):
        parse_option("999Hz", "--samplerate", "frequency", SAMPLE_RATE)
    assert parse_option("1ms", "--samplerate", "frequency", SAMPLE_RATE) == 1000  # a period
    warned: list[str] = []
    assert parse_option("99ns", "--latency", "time", LATENCY, warned.append) == Fraction(99, 10**9)
    assert len(warned) == 1 and "99 ns is below 100 ns" in warned[0]
    parse_option("100ns", "--latency", "time", LATENCY, warned.append)
    parse_option("0", "--latency", "time", LATENCY, warned.append)  # 0 is never judged
    check_plausible(Fraction(0), "--base-period", "0", BASE_PERIOD)
    assert len(warned) == 1


@pytest.mark.parametrize(
    ("text", "value"),
    [("1", Fraction(1)), (" -2.5 ", Fraction(-5, 2)), ("1e15", Fraction(10**15)), ("0", 0)],
)
def test_parse_number_exact(text: str, value: Fraction) -> None:
    assert parse_number(text, "--scale") == value
    assert finite_float(text, "--scale") == float(value)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("nan", "nan/inf is not a number here"),
        ("-Infinity", "nan/inf is not a number here"),
        ("1e308", "out of range"),
        ("1.1e15", "at most 1e15 in magnitude"),
        ("9" * 5000, "out of range"),
        ("0x10", "not a number"),
        ("1,5", "not a number"),
    ],
)
def test_parse_number_refuses_in_one_short_line(text: str, message: str) -> None:
    with pytest.raises(UnitError, match=message) as info:
        parse_number(text, "--scale")
    assert str(info.value).startswith("--scale ") and len(str(info.value)) < 120


@pytest.mark.parametrize(
    ("text", "ok"),
    [("12", True), ("-3", True), ("+7", True), ("1.0", False), ("٣", False), ("9" * 5000, False)],
)
def test_parse_int_counts_digits_first(text: str, ok: bool) -> None:
    if ok:
        assert parse_int(text, "line 1:") == int(text)
    else:
        with pytest.raises(UnitError, match="line 1:"):
            parse_int(text, "line 1:", limit=10**12)


def test_check_finite_names_the_first_bad_value() -> None:
    check_finite([0.0, -1e15, 1e15], lambda i: f"row {i}")
    for values, place in (([1.0, float("nan"), float("inf")], "row 1"), ([2e15], "row 0")):
        with pytest.raises(UnitError, match=place):
            check_finite(values, lambda i: f"row {i}")
