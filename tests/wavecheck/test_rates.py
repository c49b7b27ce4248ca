"""Max step rates: drive, observed, headroom."""

from __future__ import annotations

from fractions import Fraction

from tests.wavecheck.waves import capture, drive, g202, pulses
from wavecheck.engine import run_check
from wavecheck.rates import drive_rate

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
    assert rates.longest_active_ns == 4 * US and rates.idle_min_ns == 2 * US
    assert rates.headroom == Fraction(10**9, 6 * US)
    assert rates.drive == Fraction(10**9, 3 * US)


def test_headroom_falling_edge_uses_low_time_and_is_capped() -> None:
    # G202: active level = low; longest low 1 µs, idle (high) minimum 4.5 µs → 1/5.5 µs = 181.8 kHz
    step = pulses([10 * US, 20 * US, 26 * US], 5 * US)  # lows: 15-20 (5 µs), 25-26 (1 µs)
    rates = run_check(capture({"S": (0, step)}), g202(), {"step": "S"}).rates
    assert rates.longest_active_ns == 5 * US
    assert rates.headroom == Fraction(10**9, 9500)
    short = pulses([10 * US, 20 * US], 5 * US)
    short[2] = short[1] + 100  # low 100 ns: 1/(0.1 + 4.5 µs) > 200 kHz → capped at drive
    rates = run_check(capture({"S": (0, short)}), g202(), {"step": "S"}).rates
    assert rates.headroom == 200_000
