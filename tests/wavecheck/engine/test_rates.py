"""Max step rates: drive, observed, headroom."""

from __future__ import annotations

from fractions import Fraction

import pytest

from tests.engine_probe import run_check
from tests.wavecheck.waves import capture, drive, g202, pulses

US = 1000


def test_drive_rate_is_the_smaller_of_max_rate_and_pulse_sum() -> None:
    assert g202().step_rate() == (Fraction(200_000), "max_rate")  # 1/(4.5+0.5 µs) = 200 kHz too
    assert drive(max_rate_hz=500_000, step_high=1900, step_low=1900).step_rate() == (
        Fraction(10**9, 3800),
        "pulse",
    )
    assert drive(step_high=1).step_rate() == (None, None)


def test_observed_and_headroom_rising_edge() -> None:
    # high (active) times 3, 3 and 4 µs: typical (median) 3 µs; step_low minimum 2 µs → 1/(3+2 µs)
    step = pulses([10 * US, 30 * US, 38 * US], 3 * US)
    step[-1] += 1 * US  # last pulse 4 µs
    d = drive("rising", step_high=1 * US, step_low=2 * US, max_rate_hz=1_000_000)
    rates = run_check(capture({"S": (0, step)}), d, {"step": "S"}).rates
    assert rates.observed == Fraction(10**9, 8 * US) and rates.observed_at_s == Fraction(30, 10**6)
    assert rates.longest_pulse_ns == 4 * US and rates.typical_pulse_ns == 3 * US
    assert rates.idle_min_ns == 2 * US
    assert rates.headroom == Fraction(10**9, 5 * US) and rates.headroom_limited_by == "gap"
    assert rates.drive == Fraction(10**9, 3 * US)


def test_headroom_falling_edge_drive_not_inverted_uses_the_generator_pulse() -> None:
    # G202 with stepgen's high pulses (STEP not inverted, the stepper-tuning chapter's reading):
    # the active (low) level is the gap, up to 200 µs here; the generator's pulse is the 5 µs high.
    step = pulses([10 * US, 110 * US, 310 * US], 5 * US)
    rates = run_check(capture({"S": (0, step)}), g202(), {"step": "S"}).rates
    assert rates.pulse_level == 1 and rates.longest_pulse_ns == 5 * US
    assert rates.idle_min_ns == 500 and rates.headroom == Fraction(10**9, 5500)


@pytest.mark.parametrize(
    ("initial", "edges", "invert", "level"),
    [
        # the capture shows stepgen's high pulses (1 and 2 µs); an inverter feeds the drive low ones
        (0, [10 * US, 11 * US, 100 * US, 102 * US, 300 * US, 302 * US], ["step"], 1),
        # the capture shows low pulses at the drive; the generator makes low pulses
        (1, [10 * US, 11 * US, 100 * US, 102 * US, 300 * US, 302 * US], [], 0),
    ],
)
def test_headroom_low_pulses_at_the_drive(
    initial: int, edges: list[int], invert: list[str], level: int
) -> None:
    # low pulses 1, 2, 2 µs: median 2 µs; the gaps must keep step_high 4.5 µs → 1/(2 + 4.5 µs)
    r = run_check(
        capture({"S": (initial, edges)}), g202(), {"step": "S"}, invert, pulse_level=level
    )
    assert r.rates.pulse_level == 0 and r.rates.typical_pulse_ns == 2 * US
    assert r.rates.headroom == Fraction(10**9, 6500)


def test_headroom_is_capped_by_the_drive() -> None:
    step = pulses([10 * US, 110 * US], 100)  # 1/(0.1 + 0.5 µs) = 1.67 MHz > 200 kHz
    d = drive("rising", max_rate_hz=200_000, step_high=100, step_low=500)
    rates = run_check(capture({"S": (0, step)}), d, {"step": "S"}).rates
    assert rates.headroom == 200_000 and rates.headroom_limited_by == "max_rate"


def test_pulses_longer_than_the_gaps_are_still_the_pulses() -> None:
    # 5 µs high pulses with 1 µs gaps (a 166.7 kHz burst), rising-edge drive with step_low 4 µs:
    # duty-cycle statistics took the 1 µs gaps for the pulses (1/(1 + 4 µs)...); the pulses are
    # the highs, so no rate above 1/(5 + 4 µs) = 111.1 kHz leaves the gaps their 4 µs.
    step = pulses([0, 6 * US, 12 * US, 18 * US], 5 * US)
    d = drive("rising", step_high=1 * US, step_low=4 * US)
    r = run_check(capture({"S": (0, step)}), d, {"step": "S"})
    assert r.rates.pulse_level == 1 and r.rates.typical_pulse_ns == 5 * US
    assert r.rates.headroom == Fraction(10**9, 9 * US)
    assert r.rule("step_low").verdict == "fail"  # the 1 µs gaps themselves


def test_no_headroom_when_the_pulses_fail_their_own_minimum() -> None:
    # 3 µs high pulses into a G202 (4.5 µs '1' time): no rate makes them pass
    step = pulses([10 * US, 110 * US, 210 * US], 3 * US)
    r = run_check(capture({"S": (0, step)}), g202(), {"step": "S"})
    assert r.rule("step_high").verdict == "fail"
    assert (
        r.rates.headroom is None
        and r.rates.headroom_note == "the pulses fail step_high at any rate"
    )


def test_one_latency_stretched_pulse_does_not_decide_the_headroom() -> None:
    # nine 5 µs pulses and one stretched to 229 µs by a latency spike: the typical pulse is 5 µs
    starts = [k * 1000 * US for k in range(10)]
    step = pulses(starts, 5 * US)
    step[9] += 224 * US  # the fifth pulse ends 224 µs late
    r = run_check(capture({"S": (0, step)}), g202(), {"step": "S"})
    assert r.rates.longest_pulse_ns == 229 * US and r.rates.typical_pulse_ns == 5 * US
    assert r.rates.headroom == Fraction(10**9, 5500)


def test_no_headroom_for_both_edge_stepping_or_phases() -> None:
    step = pulses([10 * US, 110 * US], 5 * US)
    r = run_check(capture({"S": (0, step)}), g202(), {"step": "S"}, active_edge="both")
    assert r.rates.headroom is None and "both edges" in (r.rates.headroom_note or "")
