"""Issue 33: a lattice is reported only with positive evidence, else "not established" (exit 3).

Facts checked: a base thread runs every P and is never a period late (stepgen reference §2.1,
stepgen/lateness.py), so part of each period holds no edges; an analyzer's sample grid puts every
edge on it, which is no thread's lattice; a step generator's DDS steps every ⌊1/v⌋ or ⌈1/v⌉
invocations and its rate ramps (§2.1 steps 2–3, §4), so its step intervals change gradually,
which a sensor's frame clock does not show; one capture, one answer (``latency`` and ``stepgen
plan --latency-from`` read the same report).
"""

from __future__ import annotations

from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest

from stepgen.cli import main as stepgen_main
from stepgen.vcdout import write_vcd
from tests.conftest import shared_capture
from tests.wavecheck.lattice.captures import roles, run
from tests.wavecheck.lattice.sweep import grid_capture
from wavecheck.cli import main as wavecheck_main
from wavecheck.lattice import analyse, analyse_times, common_period
from wavecheck.lattice.evidence import MIN_MOTION_SHARE, motion_share, steady_pulse
from wavecheck.lattice.period import exact
from wavecheck.lattice.reading import evaluate, widest_gap


def _ramp_timer(n: int = 3000, seed: int = 1) -> np.ndarray:
    """A step timer's edges (grbl-like: a ramp of step intervals, a 10 us pulse), exact ns."""
    rng = np.random.default_rng(seed)
    iv = np.linspace(400_000, 30_000, n).astype(np.int64) + rng.integers(0, 700, n)
    rise = np.cumsum(iv)
    return np.unique(np.concatenate([rise, rise + 10_000]))


def test_a_timer_on_an_unstated_sample_grid_is_no_lattice() -> None:
    # a 500 kHz analyzer exported with 1 ns times: every edge on a 2 us grid; before issue 33
    # the grid made a lattice of P = 6 us (3 samples)
    grid = -(-_ramp_timer() // 2000) * 2000
    r = analyse_times(np.unique(grid), tick_ns=Fraction(1), resolution_ns=Fraction(0))
    assert not r.lattice and not r.established
    period, _ = common_period(np.unique(grid), Fraction(1), Fraction(0))
    assert period is None


def test_a_thread_on_an_unstated_sample_grid_reads_at_the_grid_s_resolution() -> None:
    trace = run(25_000, "uniform:6us", 2)
    r = analyse(grid_capture(trace), list(trace.pins), roles=roles(trace))
    # 25 us is 12.5 samples of 2 us: the grid is the analyzer's, taken as the resolution
    assert r.established and r.period_ns == 25_000 and r.resolution_ns == 2000
    assert any("sample period" in n for n in r.notes)


def test_widest_gap_allows_a_few_late_spikes() -> None:
    lat = np.concatenate([np.arange(0, 300), [900, 950]])  # 2 spikes in a 1000-unit period
    assert widest_gap(lat, 1000) == 1000 - 299  # from 299 to the next period's 0
    assert widest_gap(np.arange(0, 1000, 10), 1000) == 10 * 3  # c = 2 edges inside


def test_no_empty_arc_is_no_lattice() -> None:
    # phases over the whole period: whatever P is given, no thread's lattice
    rng = np.random.default_rng(3)
    k = np.sort(rng.choice(200_000, 4000, replace=False))
    times = np.unique(k * 25_000 + rng.integers(0, 24_900, 4000))
    r = analyse_times(
        times, tick_ns=Fraction(1), resolution_ns=Fraction(0), period_ns=Fraction(25_000)
    )
    assert not r.lattice and not r.established and "no empty arc" in " ".join(r.notes)


def test_exact_without_an_uncertainty_keeps_the_period() -> None:
    # issue 33: OverflowError: cannot convert Infinity to integer ratio (the common-timer note)
    times = np.array([0, 10**9], np.int64)
    assert exact(25_000.25, float("inf"), times) == Fraction(100001, 4)
    with pytest.raises(ValueError, match="finite"):
        exact(float("inf"), 1.0, times)


def test_too_few_edges_exit_3_and_plan_refuses(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # issue 34: "latency with too few edges exits 0"; README: exit 3
    trace = run(25_000, "uniform:5us", 1, moves="0.012", periods=3000)
    vcd = tmp_path / "few.vcd"
    write_vcd(trace, vcd)
    assert wavecheck_main(["latency", "-q", str(vcd)]) == 3
    out = capsys.readouterr().out
    assert "not established (only" in out and "plan from no figure here" in out
    assert stepgen_main(["plan", "--drive", "gecko-g202", "--latency-from", str(vcd)]) == 2
    assert "no latency to plan from: only" in capsys.readouterr().err


def test_a_sensor_frame_clock_is_no_thread(capsys: pytest.CaptureFixture[str]) -> None:
    # issue 33: the ADNS-2051 optical mouse sensor's quadrature outputs (sigrok-dumps) lie on a
    # 487.8 us lattice, its frame clock; no line has pulses of one length in periods, and 79 %
    # of successive intervals change gradually (a hand's motion): exit 3, nothing to plan from
    path = shared_capture(
        "sigrok-dumps/mouse_sensors/avago_adns_2051/avago_adns_2051_move_mouse_left_right.sr"
    )
    assert wavecheck_main(["latency", "-q", str(path)]) == 3
    out = capsys.readouterr().out
    assert "not shown to be a step generator's thread" in out and "plan from no figure" in out


def _dds(rates: np.ndarray) -> np.ndarray:
    """The invocations at which a DDS accumulator at ``rates`` (steps per invocation, one per
    invocation) steps (stepgen-linuxcnc.md §2.1 step 3: a step when the accumulator passes a
    whole number)."""
    acc = np.cumsum(rates)
    return np.flatnonzero(np.diff(np.floor(acc)) > 0) + 1


@pytest.mark.parametrize(
    ("rates", "gradual"),
    [
        (np.full(20_000, 0.3), True),  # a constant rate: intervals 3 and 4 invocations
        (np.linspace(0.01, 0.5, 20_000), True),  # a ramp
        (np.concatenate([np.linspace(0.01, 0.4, 8000), np.linspace(0.4, 0.01, 8000)]), True),
    ],
)
def test_a_step_generator_s_intervals_change_gradually(rates: np.ndarray, gradual: bool) -> None:
    k = _dds(rates)
    share, pairs = motion_share(k, np.ones(len(k), np.int64), 1)
    assert pairs == len(k) - 2 and (share >= MIN_MOTION_SHARE) == gradual


def test_intervals_that_jump_are_no_motion() -> None:
    # a frame clock's outputs: each step 2 to 9 frames after the last, at random
    k = np.cumsum(np.random.default_rng(5).integers(2, 10, 2000))
    share, _ = motion_share(k, np.ones(len(k), np.int64), 1)
    assert share < MIN_MOTION_SHARE
    # and each kind is read on its own: rises and falls of one pulse train interleave
    both = np.sort(np.concatenate([k, k + 1]))  # a pulse one invocation long
    bits = np.where(np.isin(both, k), 1, 2).astype(np.int64)
    assert motion_share(both, bits, 2)[0] == share


def test_a_binned_fold_counts_double_writes_across_the_period_end() -> None:
    # 34 us on a 2 us grid folded in bins of 3 ticks (2^14 bins, the last one tick short):
    # pairs that crossed the end of the period were counted a bin early, so the true anchor
    # (lateness 0 at phase 0, the first edge's) showed double writes (20 in a sweep case)
    rng = np.random.default_rng(2)
    k = np.sort(rng.choice(np.arange(3, 60_000, 3), 4000, replace=False))
    late = rng.integers(0, 9, 8000) * 2000
    t = np.unique(np.concatenate([[0], np.concatenate([k, k + 1]) * 34_000 + late]))
    for bins in (1 << 14, 1 << 20):
        ev = evaluate(t, Fraction(34_000), 2000, None, bins)
        assert ev.readings[0].collisions == 0, bins


def test_p_is_simplest_in_samples() -> None:
    times = np.array([0, 10**9], np.int64)
    # within 1.5 ns of 34000.4 ns every whole ns is as simple; 17 samples of 2 us is simpler
    assert exact(34_000.4, 1.5, times) == 34_000
    assert exact(34_000.9, 1.5, times) == 34_001
    assert exact(34_000.9, 1.5, times, 2000) == 34_000
    assert exact(25_000.9, 1.5, times, 2000) == 25_000  # 12.5 samples


def _kinds_of(rise: np.ndarray, fall: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(invocations, kind bits) of one line's rises (bit 1) and falls (bit 0)."""
    k = np.concatenate([rise, fall])
    bits = np.concatenate([np.full(len(rise), 2), np.full(len(fall), 1)]).astype(np.int64)
    order = np.argsort(k, kind="stable")
    return k[order], bits[order]


def test_step_pulses_of_steplen_periods_are_a_step_generator_s() -> None:
    # types 0/1: STEP high for exactly steplen periods at every rate (timer1 = steplen), the
    # spaces following the ramp
    rise = _dds(np.linspace(0.02, 0.3, 20_000))  # at most 1 / (steplen + stepspace)
    for steplen in (1, 2):
        k, bits = _kinds_of(rise, rise + steplen)
        assert steady_pulse(k, bits, 1) == (0, 1, steplen)
    # a quadrature line (A of a pair: high for two steps, low for two) has no such level
    steps = _dds(np.linspace(0.02, 0.4, 20_000))
    k, bits = _kinds_of(steps[0::4], steps[2::4])
    assert steady_pulse(k, bits, 1) is None
    # nor a square wave at one rate: its spaces do not vary
    k, bits = _kinds_of(np.arange(0, 4000, 4), np.arange(2, 4000, 4))
    assert steady_pulse(k, bits, 1) is None
