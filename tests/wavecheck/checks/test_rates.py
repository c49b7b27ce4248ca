"""Max step rates: drive, observed, headroom."""

from __future__ import annotations

from fractions import Fraction

from tests.wavecheck.waves import capture, drive, g202, pulses
from wavecheck.checks.rates import drive_rate
from wavecheck.engine import run_check

US = 1000


def test_drive_rate_is_the_smaller_of_max_rate_and_pulse_sum() -> None:
    assert drive_rate(g202()) == (Fraction(200_000), "max_rate")  # 1/(4.5+0.5 µs) = 200 kHz too
    assert drive_rate(drive(max_rate_hz=500_000, step_high=1900, step_low=1900)) == (
        Fraction(10**9, 3800),
        "pulse",
    )
    assert drive_rate(drive(step_high=1)) == (None, None)


def test_observed_and_headroom_rising_edge() -> None:
    # high (active) times 3 µs and 4 µs; step_low minimum 2 µs → headroom 1/(4+2 µs)
    step = pulses([10 * US, 30 * US, 38 * US], 3 * US)
    step[-1] += 1 * US  # last pulse 4 µs
    d = drive("rising", step_high=1 * US, step_low=2 * US, max_rate_hz=1_000_000)
    rates = run_check(capture({"S": (0, step)}), d, {"step": "S"}).rates
    assert rates.observed == Fraction(10**9, 8 * US) and rates.observed_at_s == Fraction(30, 10**6)
    assert rates.longest_pulse_ns == 4 * US and rates.idle_min_ns == 2 * US
    assert rates.headroom == Fraction(10**9, 6 * US)
    assert rates.drive == Fraction(10**9, 3 * US)


def test_headroom_falling_edge_drive_not_inverted_uses_the_generator_pulse() -> None:
    # G202 with stepgen's high pulses (STEP not inverted): the active (low) level is the gap,
    # up to 200 µs here; the generator's pulse is the 5 µs high. Headroom 1/(5 + 0.5 µs).
    step = pulses([10 * US, 110 * US, 310 * US], 5 * US)
    rates = run_check(capture({"S": (0, step)}), g202(), {"step": "S"}).rates
    assert rates.pulse_level == 1 and rates.longest_pulse_ns == 5 * US
    assert rates.idle_min_ns == 500 and rates.headroom == Fraction(10**9, 5500)


def test_headroom_falling_edge_drive_inverted_reading() -> None:
    # low pulses of 1 µs and 2 µs (the active level), long highs: 1/(2 + 4.5 µs)
    edges = [10 * US, 11 * US, 100 * US, 102 * US, 300 * US]
    rates = run_check(capture({"S": (1, edges)}), g202(), {"step": "S"}).rates
    assert rates.pulse_level == 0 and rates.longest_pulse_ns == 2 * US
    assert rates.headroom == Fraction(10**9, 6500)


def test_headroom_is_capped_by_the_drive() -> None:
    step = pulses([10 * US, 110 * US], 100)  # 1/(0.1 + 0.5 µs) = 1.67 MHz > 200 kHz
    rates = run_check(capture({"S": (0, step)}), g202(), {"step": "S"}).rates
    assert rates.headroom == 200_000
