"""Latency models: grid, worst case n·P − J, ordering, spikes, files (§10)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from stepgen.latencyfiles import read_histogram, read_latency_file
from stepgen.lateness import invocation_clock, invocation_times, parse_latency
from stepgen.motion import Motion, parse_moves
from stepgen.reference import StepgenConfig
from stepgen.simulate import simulate
from wavecheck.errors import ConfigError

P = 16_000
CFG = StepgenConfig(
    base_period_ns=P,
    servo_period_ns=1_008_000,
    position_scale=1000,
    maxvel=20,
    maxaccel=400,
    thread_order="pulses-first",
)
MOVE = Motion("moves", segments=parse_moves("0.3, pause 5ms, 0, pause 5ms, 0.2", 20, 400))
N = 60_000
# velocity mode at near full speed (31.25 kHz max), reversing at 30 ms: the shortest intervals
VCFG = StepgenConfig(
    base_period_ns=P,
    servo_period_ns=1_008_000,
    position_scale=1000,
    mode="velocity",
    thread_order="pulses-first",
)
VMOVE = Motion("csv", csv_times=np.array([0.0, 0.03]), csv_values=np.array([30.0, -30.0]))


def _trace(latency: str, **kw):  # type: ignore[no-untyped-def]
    return simulate(CFG, MOVE, latency, n_periods=N, **kw)


def test_none_puts_every_edge_on_the_grid() -> None:
    """Latency none: invocation k at k·P, so every edge is a multiple of P."""
    tr = _trace("none")
    assert tr.steps > 100
    for pin in tr.pins:
        assert len(tr.edges[pin]) and np.all(tr.edges[pin] % P == 0)


def test_worst_step_high_is_exactly_P_minus_J() -> None:
    """Issue 4 / [TWK]: worst:11us:step_high at P = 16 µs → shortest high time 16 − 11 = 5 µs."""
    tr = _trace("worst:11us:step_high")
    e = tr.edges["step"]
    high = e[1::2] - e[0::2]
    assert high.min() == 5_000
    assert np.all(high == 5_000)  # steplen 1 period: every pulse is the worst
    low = e[2::2] - e[1:-1:2]
    assert low.min() >= 2 * P - 5_000  # the step_low intervals are lengthened, not shortened


def test_worst_step_low_and_period() -> None:
    """step_low intervals end on time (n·P − J); step_period alternates late/on time."""
    e = _trace("worst:11us:step_low").edges["step"]
    low = e[2::2] - e[1:-1:2]
    assert np.all((low + 11_000) % P == 0)  # every low time is n·P − J
    e = simulate(VCFG, VMOVE, "worst:11us:step_low", n_periods=4000).edges["step"]
    low = e[2::2] - e[1:-1:2]
    assert low.min() == P - 11_000
    e = simulate(VCFG, VMOVE, "worst:11us:step_period", n_periods=4000).edges["step"]
    rises = e[0::2]
    per = np.diff(rises)
    assert per.min() == 2 * P - 11_000  # steplen + stepspace = 2 periods at full speed


def test_worst_dir_hold_from_falling_edge_g202_story() -> None:
    """DESIGN G202 story: pin not inverted, drive steps on the falling edge; dirhold 2 periods
    at P = 16 µs, J = 11 µs → hold from the active (falling) edge = 2·16 − 11 = 21 µs."""
    cfg = StepgenConfig(**{**VCFG.__dict__, "dirhold": 2 * P})
    tr = simulate(cfg, VMOVE, "worst:11us:dir_hold", n_periods=4000, active_edge="falling")
    falls = tr.edges["step"][1::2]
    dirs = tr.edges["dir"]
    assert len(dirs) == 1  # one reversal at 30 ms
    prev_fall = falls[np.searchsorted(falls, dirs, side="left") - 1]
    hold = dirs - prev_fall
    # the falling edge runs J late and the DIR change on time: every hold is n·P − J ...
    assert np.all(hold % P == P - 11_000)
    # ... and n >= dirhold periods (2): a decelerating reversal here gives 13 periods
    assert hold.min() >= 2 * P - 11_000


def test_worst_dir_setup_ends_on_the_first_active_edge() -> None:
    """dir_setup: DIR change late, first active edge after it on time → n·P − J."""
    cfg = StepgenConfig(**{**CFG.__dict__, "dirsetup": 2 * P})
    tr = simulate(cfg, MOVE, "worst:5us:dir_setup", n_periods=N)
    rises = tr.edges["step"][0::2]
    dirs = tr.edges["dir"]
    nxt = rises[np.searchsorted(rises, dirs, side="left")]
    assert ((nxt - dirs) % P == P - 5_000).all()


def test_latency_never_reorders_and_spike_catches_up() -> None:
    """spike:300us@64s-style: the late invocation and the overdue ones after it stay in order."""
    tr = _trace("spike:300us@0.2s", catchup_ns=1000)
    times = invocation_times(parse_latency("spike:300us@0.2s"), tr.run, catchup_ns=1000)
    assert times is not None
    assert np.all(np.diff(times) >= 1000)
    k = -(-200_000_000 // P)
    assert times[k] == k * P + 300_000
    assert times[k + 1] == times[k] + 1000  # overdue: runs right after


def test_random_models_are_seeded_and_bounded() -> None:
    a = _trace("uniform:11us", seed=3)
    b = _trace("uniform:11us", seed=3)
    c = _trace("uniform:11us", seed=4)
    np.testing.assert_array_equal(a.edges["step"], b.edges["step"])
    assert not np.array_equal(a.edges["step"], c.edges["step"])
    off = a.edges["step"] - (a.run.toggles["step"] * P)
    assert off.min() >= 0 and off.max() <= 11_000
    n = _trace("normal:2us,5us", seed=1)
    off = n.edges["step"] - n.run.toggles["step"] * P
    assert off.max() <= 5_000


@pytest.mark.parametrize(
    "bad",
    [
        "sometimes",
        "uniform",
        "uniform:-3us",
        "worst:11us:step_wide",
        "spike:300us@0",
        "normal:2us",
        "histogram:/nonexistent",
    ],
)
def test_bad_models_are_one_line_config_errors(bad: str) -> None:
    with pytest.raises(ConfigError) as err:
        parse_latency(bad)
    assert "\n" not in str(err.value)


CYCLICTEST_H = """# /dev/cpu_dma_latency set to 0us
# Histogram
000000 000000\t000000
000001 000500\t000400
000002 000300\t000100
000007 000001\t000000
# Total: 000000801 000000500
# Min Latencies: 00001 00001
# Avg Latencies: 00001 00001
# Max Latencies: 00007 00002
# Histogram Overflows: 00000 00000
"""
NOX = """    1 s   base min:  -11.300 us max:   14.200 us sdev:    0.900 us
    1 s  servo min:   -3.000 us max:    4.000 us sdev:    0.500 us
    2 s   base min:  -12.100 us max:   13.000 us sdev:    1.000 us
"""


def test_latency_files(tmp_path: Path) -> None:
    """§10: ~/.latency (ns), cyclictest -h footer (µs), cyclictest summary Max:, latency-histogram --nox."""
    (tmp_path / "latency").write_text("15234\n")
    assert read_latency_file(tmp_path / "latency")[0] == 15234
    (tmp_path / "h.txt").write_text(CYCLICTEST_H)
    assert read_latency_file(tmp_path / "h.txt")[0] == 7000
    (tmp_path / "s.txt").write_text(
        "policy: fifo: loadavg: 0.1 0.1 0.1 1/100 1\n"
        "T: 0 ( 1234) P:80 I:1000 C:  10000 Min:      2 Act:    3 Avg:    3 Max:      15\n"
        "T: 1 ( 1235) P:80 I:1500 C:   6667 Min:      2 Act:    3 Avg:    3 Max:      21\n"
    )
    assert read_latency_file(tmp_path / "s.txt")[0] == 21_000
    (tmp_path / "n.txt").write_text(NOX)
    assert read_latency_file(tmp_path / "n.txt")[0] == 14_200
    hist = read_histogram(tmp_path / "h.txt")
    assert set(hist.values_ns.tolist()) == {0, 1000, 2000, 7000}
    assert abs(hist.weights.sum() - 1) < 1e-12
    assert read_histogram(tmp_path / "n.txt").half_normal == (1000, 14_200)
    (tmp_path / "junk.txt").write_text("hello\n")
    with pytest.raises(ConfigError):
        read_latency_file(tmp_path / "junk.txt")


def test_histogram_model_draws_only_binned_values(tmp_path: Path) -> None:
    (tmp_path / "h.txt").write_text(CYCLICTEST_H)
    tr = _trace(f"histogram:{tmp_path / 'h.txt'}", seed=2)
    off = tr.edges["step"] - tr.run.toggles["step"] * P
    assert set(np.unique(off).tolist()) <= {0, 1000, 2000, 7000}


def _updown_reversals() -> tuple[StepgenConfig, Motion]:
    cfg = StepgenConfig(
        step_type=1,
        base_period_ns=P,
        servo_period_ns=P,
        mode="velocity",
        position_scale=1.0,
        dirdelay=2 * P,
        thread_order="pulses-first",
    )
    t = np.arange(8) * 40 * P * 1e-9
    v = np.where(np.arange(8) % 2 == 0, 25_000.0, -25_000.0)
    return cfg, Motion("csv", csv_times=t, csv_values=v)


@pytest.mark.parametrize("edge", ["rising", "falling"])
def test_worst_dir_delay_ends_on_the_active_edge_of_the_first_pulse(edge: str) -> None:
    """DESIGN 'Worst case, precisely' (both active edges) / reference §2.3 (types 1: the opposite
    step comes >= L + D periods later): under worst:J:dir_delay the active edge of the first
    pulse on the other line runs on time, every other edge J late."""
    cfg, motion = _updown_reversals()
    tr = simulate(cfg, motion, "worst:5us:dir_delay", n_periods=8 * 40 + 20, active_edge=edge)  # type: ignore[arg-type]
    first = 0 if edge == "rising" else 1
    ups, downs = tr.edges["up"][first::2], tr.edges["down"][first::2]
    at = np.concatenate([ups, downs])
    line = np.concatenate([np.zeros(len(ups)), np.ones(len(downs))])
    order = np.argsort(at, kind="stable")
    at, line = at[order], line[order]
    switch = np.flatnonzero(line[1:] != line[:-1]) + 1
    assert len(switch) >= 5
    assert np.all(at[switch] % P == 0)  # on time
    others = np.setdiff1d(np.concatenate([tr.edges["up"], tr.edges["down"]]), at[switch])
    assert np.all(others % P == 5_000)  # J late


def test_worst_step_period_applies_to_phase_types() -> None:
    """Issue 4 lists step_period among the worst-case rules and the validator checks step_period
    on phase types (successive state changes): worst:J:step_period alternates state changes."""
    cfg = StepgenConfig(**{**VCFG.__dict__, "step_type": 2})
    tr = simulate(cfg, VMOVE, "worst:11us:step_period", n_periods=4000)
    changes = np.unique(np.concatenate([tr.edges[p] for p in tr.pins]))
    assert np.all(changes[1::2] % P == 0) and np.all(changes[0::2] % P == 11_000)
    held = np.diff(changes)[0::2]  # late start, on-time end: n·P − J
    assert np.all(held % P == P - 11_000)
    assert held.min() == 2 * P - 11_000  # 30 kHz at P = 16 µs: a state every ~2 periods


@pytest.mark.parametrize(
    "latency",
    ["none", "uniform:10us", "uniform:15500ns", "normal:2us,20us", "spike:300us@0.2s",
     "worst:11us:step_high", "worst:15800ns:dir_hold"],
)  # fmt: skip
@pytest.mark.parametrize("catchup", [None, 100, 5000])
def test_the_clock_gives_every_invocation_time(latency: str, catchup: int | None) -> None:
    """The trace's clock (offsets only while no catch-up can act, else every t_k) gives the
    times of :func:`invocation_times`, the plain definition, at every invocation."""
    run = _trace("none").run
    model = parse_latency(latency)
    want = invocation_times(model, run, seed=3, catchup_ns=catchup)
    clock = invocation_clock(model, run, seed=3, catchup_ns=catchup)
    k = np.arange(run.n_periods)
    got = clock.at(k)
    np.testing.assert_array_equal(got, k * P if want is None else want)
    assert clock.times is None or model.j_ns > P - (catchup or 1000)  # the short way when it can
