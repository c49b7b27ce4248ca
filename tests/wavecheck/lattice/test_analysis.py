"""wavecheck.lattice: the base-thread lattice read back from stepgen captures (issues 17, 25).

Documented facts checked: every edge software stepgen makes lies at k·P + l_k (l_k ≥ 0, the
invocation's lateness, shared by every pin it changes; stepgen/lateness.py); P is recovered
exactly, the worst lateness never below the true one and within a sample of it, the spike times
found, under every latency model, from VCD and .sr at several sample rates; LinuxCNC's worst
case (worst:J:RULE) read as J, not P − J, where the capture can tell, and both readings given
where it cannot; a thread a period or more late (a catch-up run) seen as a lower bound and not
planned from; hardware-timed captures (grbl, Smoothieware) recognised. The wide sweep is
tests/wavecheck/lattice/test_sweep.py.
"""

from __future__ import annotations

import json
import os
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest

from stepgen.motion import Motion, parse_moves
from stepgen.reference import StepgenConfig
from stepgen.simulate import Trace, simulate
from stepgen.vcdout import write_vcd
from tests.conftest import SHARED
from tests.wavecheck.lattice.captures import capture, roles, run, true_lateness
from wavecheck.capture.edges import Capture, Channel
from wavecheck.capture.open import open_capture
from wavecheck.capture.srzip import write_sr_edges
from wavecheck.cli import main as wavecheck_main
from wavecheck.lattice import analyse, analyse_times, common_period, simplest_between
from wavecheck.timebase import Timebase

CAPTURES = (
    Path(__file__).resolve().parents[4] / "shared" / "captures" / "sigrok-dumps" / "stepper_motor"
)
if not CAPTURES.exists():
    CAPTURES = SHARED / "captures/sigrok-dumps/stepper_motor"
ROOT = Path(__file__).resolve().parents[3]

P_NS = 25_000
CFG = StepgenConfig(
    base_period_ns=P_NS,
    servo_period_ns=1_000_000,
    position_scale=1000,
    maxvel=15,
    maxaccel=200,
    mode="position",
)


def _run(latency: str, tmp_path: Path, periods: int = 20_000) -> Trace:
    if latency.startswith("histogram:"):
        hist = tmp_path / "hist.txt"
        hist.write_text(
            "# Histogram\n"
            + "".join(f"{b:06d} {c:06d}\n" for b, c in ((0, 50), (1, 30), (3, 15), (9, 5)))
        )
        latency = f"histogram:{hist}"
    motion = Motion("moves", segments=parse_moves("1, pause 10ms, 0.2", 15, 200))
    return simulate(CFG, motion, latency, n_periods=periods, seed=3)


def _visible_lateness(trace: Trace) -> tuple[int, int]:
    """(max − min) of the true lateness t_k − k·P over invocations that made an edge, and its max."""
    idx = np.unique(np.concatenate([trace.run.toggles[p] for p in trace.pins]))
    t = np.unique(np.concatenate([trace.edges[p] for p in trace.pins]))
    late = t - idx * P_NS
    return int(late.max() - late.min()), int(late.max())


MODELS = [
    "none",
    "uniform:11us",
    "normal:2us,20us",
    "spike:15us@50ms",
    "histogram:",
    "worst:11us:step_high",
]
RATES = [None, 100_000_000, 12_000_000, 3_300_000, 1_000_000]  # 25 us = 82.5 samples at 3.3 MHz


@pytest.mark.parametrize("latency", MODELS)
def test_every_model_every_rate_period_exact_lateness_within_a_sample(
    latency: str, tmp_path: Path
) -> None:
    trace = _run(latency, tmp_path)
    spread, _ = _visible_lateness(trace)
    for rate in RATES:
        cap = capture(trace, rate)
        r = analyse(cap, list(trace.pins), roles=roles(trace))
        # a histogram's or a worst case's whole-us latency puts every edge of the exact VCD on a
        # 1 us grid, taken as the resolution (an unstated sample period): the figures widen by it
        sample = r.resolution_ns
        assert sample in (cap.resolution_ns, 1000)
        assert r.lattice and r.established, (latency, rate, r.reason)
        assert r.period_ns == P_NS, (latency, rate)
        assert r.max_lateness_ns is not None and r.max_lateness_bound_ns is not None
        assert abs(r.max_lateness_ns - spread) <= sample, (latency, rate, r.max_lateness_ns)
        assert spread <= r.max_lateness_bound_ns < spread + 2 * sample + (rate is None)
        if rate == 3_300_000:
            assert r.fit is not None and r.fit.period == Fraction(165, 2)  # not whole samples
        if latency.startswith("worst"):
            assert r.rule == "step_high" and r.max_lateness_ns >= 11_000 - sample


def test_spike_times_found(tmp_path: Path) -> None:
    trace = _run("spike:15us@5ms", tmp_path)
    idx = np.unique(np.concatenate([trace.run.toggles[p] for p in trace.pins]))
    t = np.unique(np.concatenate([trace.edges[p] for p in trace.pins]))
    true = t[t - idx * P_NS > 0]  # the spikes that hit an invocation making an edge
    assert len(true) >= 3
    r = analyse_times(t, tick_ns=Fraction(1), resolution_ns=Fraction(0))
    spikes = r.spikes()
    assert [int(s.time_ns) for s in spikes] == true.tolist()
    assert all(s.lateness_ns == 15_000 for s in spikes)


def test_vcd_and_sr_files(tmp_path: Path) -> None:
    trace = _run("uniform:8us", tmp_path)
    write_vcd(trace, tmp_path / "run.vcd")
    spread, _ = _visible_lateness(trace)
    r = analyse(open_capture(tmp_path / "run.vcd"), ["step", "dir"])
    assert r.lattice and r.period_ns == P_NS and r.max_lateness_ns == spread
    for rate in (2_000_000, 12_000_000):
        n = trace.end_ns * rate // 10**9 + 1
        edges = [np.unique(-((-trace.edges[p] * rate) // 10**9)) for p in trace.pins]
        write_sr_edges(
            tmp_path / "run.sr", list(trace.pins), edges, [0, 0], int(n), samplerate=rate
        )
        cap = open_capture(tmp_path / "run.sr")
        r = analyse(cap, ["step", "dir"])
        assert r.lattice and r.period_ns == P_NS
        assert r.max_lateness_ns is not None
        assert abs(r.max_lateness_ns - spread) <= 2 * cap.resolution_ns


def test_too_few_edges() -> None:
    r = analyse_times(
        np.array([0, 25_000, 75_000], np.int64), tick_ns=Fraction(1), resolution_ns=Fraction(0)
    )
    assert not r.lattice and "too few edges" in r.reason
    r = analyse_times(
        np.array([0, 25_000, 75_000], np.int64),
        tick_ns=Fraction(1),
        resolution_ns=Fraction(0),
        period_ns=Fraction(P_NS),
    )
    assert r.lattice and r.max_lateness_ns == 0


@pytest.mark.parametrize("seed", [1, 2, 3, 4])
def test_period_longer_than_the_shortest_interval(seed: int) -> None:
    # a late invocation followed by an on-time one: intervals down to P − J, shorter than P.
    # 15 ksteps/s is above this stepgen's maximum rate, so it steps on every second invocation:
    # the edges also fit a lattice at 2P (more tightly, relative to the period); only the few
    # off-pattern edges while the rate ramps up show P, by making a pin change twice in one 2P
    # invocation (seed 1 inferred 2P = 50002 ns before that was taken into account)
    cfg = StepgenConfig(base_period_ns=P_NS, servo_period_ns=1_000_000, mode="velocity")
    trace = simulate(cfg, Motion("velocity", 15_000.0), "uniform:11us", n_periods=8000, seed=seed)
    ns = np.unique(np.concatenate([trace.edges[p] for p in trace.pins]))
    assert np.diff(ns).min() < P_NS
    idx = np.unique(np.concatenate([trace.run.toggles[p] for p in trace.pins]))
    assert np.count_nonzero(np.diff(idx) == 2) > 0.99 * len(idx) - 20  # the 2P pattern
    spread, _ = _visible_lateness(trace)
    r = analyse_times(ns, tick_ns=Fraction(1), resolution_ns=Fraction(0))
    assert r.period_ns == P_NS and r.max_lateness_ns == spread


@pytest.mark.parametrize(
    ("base_ns", "pattern"),
    [(20_000, 3), (40_000, 2), (50_000, 1)],
)
def test_maximum_rate_pattern_is_not_the_thread(base_ns: int, pattern: int) -> None:
    # at the maximum rate stepgen uses every 2nd or 3rd invocation; the thread's own period is
    # found, and a thread at 40 or 50 us is not split into 20 or 25 us (no double writes there)
    cfg = StepgenConfig(base_period_ns=base_ns, servo_period_ns=1_000_000, mode="velocity")
    trace = simulate(cfg, Motion("velocity", 50_000.0), "normal:1us,5us", n_periods=8000, seed=2)
    idx = np.unique(np.concatenate([trace.run.toggles[p] for p in trace.pins]))
    assert np.median(np.diff(idx)) == pattern
    ns = np.unique(np.concatenate([trace.edges[p] for p in trace.pins]))
    r = analyse_times(ns, tick_ns=Fraction(1), resolution_ns=Fraction(0))
    assert r.lattice and r.period_ns == base_ns, (r.period_ns, r.reason)


def test_channels_of_different_densities(tmp_path: Path) -> None:
    trace = _run("normal:1us,5us", tmp_path)
    write_vcd(trace, tmp_path / "run.vcd")
    r = analyse(open_capture(tmp_path / "run.vcd"), ["step", "dir"])
    assert r.edges_per_channel["dir"] < r.edges_per_channel["step"] // 100
    assert r.period_ns == P_NS


def test_given_period_and_misfit(tmp_path: Path) -> None:
    trace = _run("uniform:5us", tmp_path)
    ns = np.unique(np.concatenate([trace.edges[p] for p in trace.pins]))
    r = analyse_times(ns, tick_ns=Fraction(1), resolution_ns=Fraction(0), period_ns=Fraction(P_NS))
    assert r.lattice and r.fit is not None and r.fit.given and not r.notes
    r = analyse_times(
        ns, tick_ns=Fraction(1), resolution_ns=Fraction(0), period_ns=Fraction(25_010)
    )
    assert not r.lattice and any("do not fit the given period" in n for n in r.notes)


@pytest.mark.parametrize(
    ("rel", "channels"),
    [
        ("smoothieware/smoothieware_snippet.sr", ["3", "4", "5", "6"]),
        ("smoothieware/smoothieware_snippet.sr", ["5", "6"]),
        ("grbl_cnc/grbl_cnc_1.sr", ["STEP (Y axis)"]),
    ],
)
def test_real_captures_are_not_lattice_timed(rel: str, channels: list[str]) -> None:
    path = CAPTURES / rel
    if not path.exists():
        if os.environ.get("CI") == "true":
            pytest.fail(f"{path} missing")
        pytest.skip(f"{path} missing")
    r = analyse(open_capture(path), channels)
    assert not r.lattice and not r.established
    assert r.reason.startswith("edges do not lie on a periodic lattice: not a base thread's")
    assert r.max_lateness_ns is None


def test_simplest_between() -> None:
    assert simplest_between(Fraction(24999, 1), Fraction(25001)) == 24999
    assert simplest_between(Fraction(8249, 100), Fraction(8251, 100)) == Fraction(165, 2)
    assert simplest_between(Fraction(1, 3), Fraction(1, 3)) == Fraction(1, 3)


def test_cli_text_json_plot_html(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    trace = _run("spike:15us@50ms", tmp_path)
    write_vcd(trace, tmp_path / "run.vcd")
    code = wavecheck_main(["latency", str(tmp_path / "run.vcd"), "-q", "--format", "json"])
    assert code == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["lattice"] and doc["established"] and doc["base_period_ns"] == P_NS
    assert doc["lateness_ns"]["max_bound"] == doc["lateness_ns"]["max"]  # exact VCD
    code = wavecheck_main(
        [
            "latency",
            str(tmp_path / "run.vcd"),
            "--base-period",
            "25us",
            "--plot",
            str(tmp_path / "l.png"),
            "--html",
            str(tmp_path / "l.html"),
        ]
    )
    assert code == 0 and (tmp_path / "l.png").stat().st_size > 1000
    assert "data:image/png;base64" in (tmp_path / "l.html").read_text()
    out = capsys.readouterr().out
    assert "Max Jitter" in out and "--base-period 25us" in out


def test_real_captures_from_the_command_line(capsys: pytest.CaptureFixture[str]) -> None:
    # the channels are mapped as check maps them: grbl's "STEP (Y axis)" from its waveform,
    # Smoothieware's two axes from theirs (neither names a role), or by --map
    for rel, extra in (
        ("grbl_cnc/grbl_cnc_1.sr", []),
        ("smoothieware/smoothieware_snippet.sr", []),
        ("smoothieware/smoothieware_snippet.sr", ["--map", "x.step=5,x.dir=6"]),
    ):
        path = CAPTURES / rel
        if not path.exists():
            pytest.skip(f"{path} missing")
        code = wavecheck_main(["latency", str(path), "-q", "--format", "json", *extra])
        doc = json.loads(capsys.readouterr().out)
        assert code == 3 and not doc["lattice"] and not doc["established"], rel
        assert "not a base thread's timing" in doc["reason"]
        assert "STEP (Y axis)" in doc["channels"] or "5" in doc["channels"]


def _pulse_timer(period: int, width: int, jitter: int, n: int, seed: int) -> Capture:
    """A hardware step timer: rising edges on a lattice (each a little late, as an interrupt
    is), falling edges a fixed pulse later by a second timer; 1 ns ticks."""
    rng = np.random.default_rng(seed)
    k = np.cumsum(rng.integers(3, 9, n))
    rise = k * period + rng.integers(0, jitter + 1, n)
    edges = np.sort(np.concatenate([rise, rise + width]))
    return Capture(
        path="timer.vcd",
        format="vcd",
        timebase=Timebase(Fraction(1, 10**9)),
        resolution_ticks=0,
        samplerate_hz=None,
        start=0,
        end=int(edges[-1]) + 1,
        channels=[Channel("step", 0, 0, edges.astype(np.int64))],
    )


def test_a_pulse_timer_is_no_thread() -> None:
    # the falls follow the rises by a fixed pulse: lateness that depends on the pin
    r = analyse(_pulse_timer(10_000, 4_000, 300, 2000, 1), ["step"], roles={"step": "step"})
    assert not r.lattice
    assert "differs from the other edges'" in r.reason


def test_a_catch_up_run_is_a_lower_bound(capsys: pytest.CaptureFixture[str]) -> None:
    # spike:300us@50ms at P = 25 us: the late invocation is 12 periods late (300 us, a whole
    # number of periods: on the lattice) and the thread catches up 1 us apart; the wire shows
    # it only where distinct write times share a period, as a lower bound, not to plan from
    path = ROOT / "captures/golden/a4988-spike.vcd"
    r = analyse(open_capture(path), ["step", "dir"], roles={"step": "step", "dir": "dir"})
    assert r.lattice and r.period_ns == 25_000 and not r.established
    assert r.catch_up is not None and r.catch_up.at_least_ns >= 25_000
    assert abs(float(r.catch_up.first_ns) - 50.3e6) < 50_000
    from stepgen.cli import main as stepgen_main

    assert stepgen_main(["plan", "--drive", "a4988", "--latency-from", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "no latency to plan from" in err and "lower bound" in err


@pytest.mark.parametrize(
    ("path", "period", "lateness", "rule"),
    [
        ("captures/golden/g202-p20-worst-dirhold.vcd", 20_000, 11_000, "dir_hold"),
        ("captures/golden/g202-p16-dirhold2-worst.vcd", 16_000, 11_000, "dir_hold"),
    ],
)
def test_golden_worst_case_traces(path: str, period: int, lateness: int, rule: str) -> None:
    # ten edges each (README's G202 story): DIR on time, every step edge 11 us late
    r = analyse(open_capture(ROOT / path), ["step", "dir"], roles={"step": "step", "dir": "dir"})
    assert r.lattice and r.period_ns == period and r.max_lateness_ns == lateness
    assert r.rule == rule and not r.candidates
    assert not r.established  # ten edges: a lattice, but no machine's worst latency


@pytest.mark.parametrize(
    ("latency", "expected"),
    [
        ("uniform:20us", 20_000),
        ("uniform:25us", 25_000),
        ("worst:31us:step_high", 31_000),  # not P − J = 3 us
        ("worst:31us:dir_hold", 31_000),
    ],
)
def test_the_issue_captures_at_34us(latency: str, expected: int) -> None:
    trace = run(34_000, latency, 2)
    truth = true_lateness(trace)
    for rate in (None, 3_300_000):
        r = analyse(capture(trace, rate), list(trace.pins), roles=roles(trace))
        assert r.lattice and r.period_ns == 34_000, (latency, rate, r.reason)
        assert r.max_lateness_bound_ns is not None and r.max_lateness_bound_ns >= truth
        assert abs(float(r.max_lateness_ns or 0) - expected) <= 1_000, (latency, rate)


def test_worst_case_that_cannot_be_told_from_its_mirror() -> None:
    # step_high's worst case with 2-period pulses and no reversal: falls on time and rises J
    # late, or rises on time and falls P − J late (step_low's worst case): no double write and
    # no DIR edge decides, so both readings are reported, the larger first, and the worst
    # lateness is not established (issue 33: exit 3, plan from no figure)
    trace = run(25_000, "worst:8us:step_high", 1, moves="1", steplen_ns=50_000)
    assert len(trace.edges["dir"]) == 0
    r = analyse(capture(trace), list(trace.pins), roles=roles(trace))
    assert r.lattice and r.period_ns == 25_000
    assert not r.established and "cannot tell 2 readings" in r.unestablished
    assert r.max_lateness_ns == 17_000 and r.rule == "step_low"
    assert [(c.period_ns, c.max_lateness_ns) for c in r.candidates] == [(25_000, 8_000)]
    assert "step_high" in r.candidates[0].how


def test_common_period_of_several_axes() -> None:
    trace = run(25_000, "uniform:9us", 1)
    cap = capture(trace)
    ticks = np.unique(cap.channel("step").edges[0::2])
    period, why = common_period(ticks, cap.timebase.tick_ns, Fraction(0))
    assert period is not None and period % 25_000 == 0 and period <= 8 * 25_000 and not why
    rng = np.random.default_rng(2)
    noise = np.unique(np.cumsum(rng.integers(1_000, 90_000, 3000)))
    period, why = common_period(noise, Fraction(1), Fraction(0))
    assert period is None and why
