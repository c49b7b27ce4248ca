"""wavecheck latency: the base-thread lattice read back from stepgen captures (issue 17).

Documented facts checked: every edge software stepgen makes lies at k·P + l_k (l_k ≥ 0, the
invocation's lateness; stepgen/latency.py); P is recovered exactly, the worst lateness within one
sample period plus the resolution, the spike times found, under every latency model, from VCD
and .sr at several sample rates; hardware-timed captures (grbl, Smoothieware) are recognised.
"""

from __future__ import annotations

import os
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest

from stepgen.model import StepgenConfig
from stepgen.motion import Motion, parse_moves
from stepgen.simulate import Trace, simulate
from stepgen.vcdout import write_vcd
from wavecheck.capture.open import open_capture
from wavecheck.capture.srzip import write_sr_edges
from wavecheck.cli import main as wavecheck_main
from wavecheck.lattice import analyse, analyse_times, simplest_between

CAPTURES = (
    Path(__file__).resolve().parents[3] / "shared" / "captures" / "sigrok-dumps" / "stepper_motor"
)
if not CAPTURES.exists():
    CAPTURES = Path("/work/shared/captures/sigrok-dumps/stepper_motor")

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
RATES = [10**9, 100_000_000, 12_000_000, 3_300_000, 1_000_000]  # 25 us = 82.5 samples at 3.3 MHz


@pytest.mark.parametrize("latency", MODELS)
def test_every_model_every_rate_period_exact_lateness_within_a_sample(
    latency: str, tmp_path: Path
) -> None:
    trace = _run(latency, tmp_path)
    ns = np.unique(np.concatenate([trace.edges[p] for p in trace.pins]))
    spread, _ = _visible_lateness(trace)
    for rate in RATES:
        tick = Fraction(10**9, rate)
        ticks = np.unique(-((-ns * rate) // 10**9))  # an analyzer sees an edge at the next sample
        res = tick if rate < 10**9 else Fraction(0)
        r = analyse_times(ticks, tick_ns=tick, resolution_ns=res)
        assert r.lattice, (latency, rate, r.reason)
        assert r.period_ns == P_NS, (latency, rate)
        assert r.max_lateness_ns is not None
        assert abs(r.max_lateness_ns - spread) <= tick + res, (
            latency,
            rate,
            r.max_lateness_ns,
            spread,
        )
        if rate == 3_300_000:
            assert r.fit is not None and r.fit.period == Fraction(165, 2)  # not whole samples


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
    assert not r.lattice
    assert r.reason.startswith("edges do not lie on a periodic lattice: hardware-timed stepping")
    assert r.max_lateness_ns is None


def test_simplest_between() -> None:
    assert simplest_between(Fraction(24999, 1), Fraction(25001)) == 24999
    assert simplest_between(Fraction(8249, 100), Fraction(8251, 100)) == Fraction(165, 2)
    assert simplest_between(Fraction(1, 3), Fraction(1, 3)) == Fraction(1, 3)


def test_cli_text_json_plot_html(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    trace = _run("spike:15us@50ms", tmp_path)
    write_vcd(trace, tmp_path / "run.vcd")
    code = wavecheck_main(["latency", str(tmp_path / "run.vcd"), "--format", "json"])
    assert code == 0
    import json

    doc = json.loads(capsys.readouterr().out)
    assert doc["lattice"] and doc["base_period_ns"] == P_NS
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
