"""The closed loop (pid + stepgen / servo plant) and ``stepgen tune``: the integrator's claims.

Plants: a "stiff" servo (J = 2e-4, B = 0.02: τ = 10 ms) and a "sluggish" one (J = 0.05, B = 1:
τ = 50 ms), Kt = 1, servo period 1 ms. Their ultimate gain is computed independently here from
the eigenvalues of the sampled linear loop (zero-order hold, u_k = −P·x_k).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from stepgen.loop import ferror_check, oscillation, run_loop, step_metrics
from stepgen.motion import Motion, parse_moves
from stepgen.pid import PidGains
from stepgen.plant import ServoParams, ServoPlant, StepgenPlant, quadrature_edges
from stepgen.reference import StepgenConfig
from stepgen.tune import find_ultimate_gain, tune

T_NS = 1_000_000
T = 1e-3
STIFF = ServoParams(inertia=2e-4, viscous=0.02, load=0.05)
SLUGGISH = ServoParams(inertia=0.05, viscous=1.0, load=0.5)


def eigen_ku(p: ServoParams) -> float:
    """The P at which the sampled P-only loop's spectral radius reaches 1 (bisection)."""
    a = p.viscous / p.inertia
    d = math.exp(-a * T)
    phi = (1 - d) / a
    ad = np.array([[1.0, phi], [0.0, d]])
    bd = p.torque_constant / p.inertia * np.array([(T - phi) / a, phi])

    def rho(gain: float) -> float:
        return float(max(abs(np.linalg.eigvals(ad - np.outer(bd, [gain, 0.0])))))

    lo, hi = 1e-6, 1e9
    for _ in range(200):
        mid = math.sqrt(lo * hi)
        lo, hi = (lo, mid) if rho(mid) >= 1 else (mid, hi)
    return hi


def response(p: ServoParams, gains: PidGains, n: int = 3000, step: float = 0.01):
    cmd = np.full(n, step)
    cmd[0] = 0.0
    return run_loop(ServoPlant(p, T_NS), gains, cmd, stop_if_diverged=10.0)


def test_stepgen_pid_follows_a_trapezoid_with_linuxcnc_s_usual_gains() -> None:
    """pncconf's gains for a velocity-mode stepgen (P = 1/T = 1000, FF1 = 1, maxerror 0.0127):
    a 10-unit move at 20 units/s, 200 units/s² (stepgen limits 1.25× that, as pncconf sets).

    Why these figures: with FF1 = 1 and previous-target mode the command's own velocity is fed
    forward, so at cruise the error is 0 (< 1e-8 here, float residue); while accelerating the
    stepgen reaches each new velocity a·T by ramping at maxaccel inside the period, which loses
    (a·T)·(a·T/maxaccel)/2 = 8e-5 units per period, and P = 1/T removes it in one period: the
    error stays within twice that (at a change of acceleration the two add). Without FF1 the
    loop lags by v/P = 0.02 units at cruise. All far below MIN_FERROR (0.5): the check passes."""
    a, v, amax = 200.0, 20.0, 250.0
    cfg = StepgenConfig(
        base_period_ns=25_000,
        mode="velocity",
        position_scale=200,
        maxvel=25,
        maxaccel=amax,
        thread_order="pulses-first",
    )
    motion = Motion("moves", segments=parse_moves("10", v, a))
    n = int(motion.natural_duration_s * 1000)
    cmd = motion.commands(n, T_NS, "position")
    plant = StepgenPlant(cfg)
    r = run_loop(plant, PidGains(Pgain=1000.0, FF1=1.0, maxerror=0.0127), cmd)
    lag = (a * T) * (a * T / amax) / 2
    worst, _ = r.max_ferror()
    assert lag / 2 < worst <= 2 * lag + 1e-9
    cruise = (r.t_s > 0.2) & (r.t_s < 0.45)
    assert np.abs(r.ferror[cruise]).max() < 1e-8
    assert abs(r.feedback[-1] - 10.0) < 1 / 200
    assert ferror_check(r, 1.0, 0.5, 20.0).ok
    r0 = run_loop(StepgenPlant(cfg), PidGains(Pgain=1000.0), cmd)
    assert np.abs(r0.ferror[cruise]).max() == pytest.approx(v / 1000.0, rel=0.01)


def test_ferror_limit_scales_between_min_ferror_and_ferror() -> None:
    """Reference §4.4: limit = max(FERROR·|v|/MAX_VELOCITY, MIN_FERROR); a lagging loop (P only)
    fails a tight FERROR at speed and passes at a standstill's MIN_FERROR."""
    cfg = StepgenConfig(base_period_ns=25_000, mode="velocity", position_scale=200, maxvel=25)
    cmd = 10.0 * T * np.arange(400)  # 10 units/s ramp: lag 10/P = 0.01 with P = 1000
    r = run_loop(StepgenPlant(cfg), PidGains(Pgain=1000.0), cmd)
    assert not ferror_check(r, 0.01, 0.001, 20.0).ok  # limit at 10 u/s: 0.005 < 0.01
    assert ferror_check(r, 0.03, 0.001, 20.0).ok  # limit 0.015
    assert ferror_check(r, 1.0, None, 20.0).min_ferror == 1.0  # MIN_FERROR defaults to FERROR


@pytest.mark.parametrize("name,plant", [("stiff", STIFF), ("sluggish", SLUGGISH)])
def test_tune_finds_the_ultimate_gain_and_keeps_its_promises(name: str, plant: ServoParams) -> None:
    """stepgen tune: Ku within 10 % of the eigenvalue value; the final gains remove the load's
    offset within the settling time asked and overshoot less than P = Ku/2 alone."""
    settle = {"stiff": 0.3, "sluggish": 1.0}[name]
    window = {"stiff": 1.0, "sluggish": 4.0}[name]
    res = tune(lambda: ServoPlant(plant, T_NS), step=0.01, settle_s=settle, window_s=window)
    assert res.ku == pytest.approx(eigen_ku(plant), rel=0.10)
    half = next(s for s in res.stages if s.name.startswith("2"))
    assert half.gains.Pgain == pytest.approx(res.ku / 2)
    final = res.stages[-1]
    assert final.metrics.settling_s is not None and final.metrics.settling_s <= settle
    assert abs(final.metrics.steady_state_error) < 0.02 * 0.01
    assert final.metrics.overshoot < half.metrics.overshoot
    assert not final.osc.sustained


def test_p_alone_leaves_an_offset_under_load_and_i_removes_it() -> None:
    """Claim: P alone settles at an offset load/(Kt·P) (the force balance), I removes it."""
    p = 10.0
    r = response(STIFF, PidGains(Pgain=p))
    offset = r.command[-1] - r.feedback[-1]
    assert offset == pytest.approx(STIFF.load / (STIFF.torque_constant * p), rel=1e-3)
    r = response(STIFF, PidGains(Pgain=p, Igain=100.0))
    assert abs(r.command[-1] - r.feedback[-1]) < 1e-6


def test_too_much_p_or_i_is_unstable() -> None:
    """Claim: too much P (above Ku) or too much I makes the loop unstable."""
    ku = eigen_ku(STIFF)
    for gains in (PidGains(Pgain=1.2 * ku), PidGains(Pgain=ku / 2, Igain=50 * ku)):
        r = response(STIFF, gains)
        assert r.diverged or oscillation(r.ferror, T_NS, 2e-4).ratio > 1.0
    r = response(STIFF, PidGains(Pgain=0.8 * ku))
    assert not r.diverged and abs(r.ferror[-1]) < 0.01


def test_d_reduces_the_overshoot_that_i_causes() -> None:
    """Claim: adding I raises the overshoot; D brings it down."""
    ku = eigen_ku(STIFF)
    ov = [
        step_metrics(r.t_s, r.feedback, 0.0, 0.01).overshoot
        for r in (
            response(STIFF, PidGains(Pgain=ku / 2)),
            response(STIFF, PidGains(Pgain=ku / 2, Igain=300.0)),
            response(STIFF, PidGains(Pgain=ku / 2, Igain=300.0, Dgain=0.03)),
        )
    ]
    assert ov[1] > ov[0] and ov[2] < ov[1] / 2


def test_an_overdamped_loop_needs_p_well_below_half_ku() -> None:
    """Claim: no overshoot needs P significantly less than half the oscillating P (here the
    largest P without overshoot is near critical damping, B²/(4·J·Kt) = 0.5 ≈ Ku/80)."""
    plant = ServoParams(inertia=2e-4, viscous=0.02)
    ku = eigen_ku(plant)
    no_overshoot = []
    for f in np.geomspace(1e-3, 0.5, 40):
        r = response(plant, PidGains(Pgain=f * ku))
        if step_metrics(r.t_s, r.feedback, 0.0, 0.01).overshoot < 1e-3:
            no_overshoot.append(f)
    assert no_overshoot and max(no_overshoot) < 0.1


def test_stepgen_ultimate_gain_is_2_over_t_without_accel_limit() -> None:
    """Reference §3: an ideal velocity actuator oscillates at P = 2/T; the velocity-mode stepgen
    without an acceleration limit is close to it (within 10 %)."""
    cfg = StepgenConfig(base_period_ns=25_000, mode="velocity", position_scale=200, maxvel=25)
    ku, _, _ = find_ultimate_gain(lambda: StepgenPlant(cfg), 0.1, 0.3)
    assert ku == pytest.approx(2 / T, rel=0.10)


def test_quadrature_round_trip() -> None:
    """The encoder's A/B follows stepgen type 2's table: decoding the edges gives the counts."""
    plant = ServoPlant(
        ServoParams(counts_per_unit=1000, inertia=1e-3, viscous=0.05), T_NS, record=True
    )
    for u in [0.5] * 50 + [-0.5] * 100:
        plant.advance(u)
    t, counts = plant.count_changes()
    assert len(counts) > 10 and np.all(np.abs(np.diff(counts)) == 1)
    edges, init = quadrature_edges(t, counts)
    table = [1, 3, 2, 0]
    state = {"A": init["phase-A"], "B": init["phase-B"]}
    events = sorted([(int(x), p[-1]) for p in ("phase-A", "phase-B") for x in edges[p]])
    pos = 0
    for _, p in events:
        state[p] ^= 1
        s = table.index(state["A"] | state["B"] << 1)
        delta = (s - pos) % 4
        assert delta in (1, 3)
        pos = s
    assert pos == counts[-1] % 4


def test_readme_servo_block_runs(tmp_path, monkeypatch, capsys) -> None:
    """README "Servo loops": both commands run as written and report what the section says."""
    import shlex

    from stepgen.cli import main
    from tests.doc_pages import marked

    block = marked("servo")
    monkeypatch.chdir(tmp_path)
    for line in block.strip().splitlines():
        assert main(shlex.split(line)[1:]) == 0
    out = capsys.readouterr().out
    assert "following-error check pass" in out
    # issue 26: the run's length said as one ("(650 servo periods)" read as the time of the max)
    assert "following error: max 0.000149262 units at 0.005 s, in a run of 0.65 s " in out
    assert "(650 servo periods of 1 ms)" in out
    assert "[JOINT_0]" in out and "setp pid.0.Pgain [JOINT_0]P" in out
    assert (tmp_path / "loop.vcd").stat().st_size > 0
    page = (tmp_path / "tune.html").read_text()
    assert "data:image/png;base64," in page
    # issue 26: the Ku response decays in its plot, and the page says so (not "sustains")
    assert "sustains oscillation" not in page and "sustains oscillation" not in out
    assert "its swing decays from 0.0182 to 0.00484 units over the 1 s window (×0.981" in page


def test_swing_words_follow_the_curve() -> None:
    """The words of stage 1 describe the response's swing over the window, as its plot shows."""
    from stepgen.loop import LoopResult
    from stepgen.tune import swing_words

    n, period = 1001, 20  # 1 ms servo periods, a 20 ms oscillation
    t = np.arange(n)

    def result(per_cycle: float) -> LoopResult:
        fb = 1 + 0.5 * per_cycle ** (t / period) * np.sin(2 * np.pi * t / period)
        z = np.zeros(n)
        return LoopResult(1_000_000, np.ones(n), fb, z, 1 - fb, z.astype(bool))

    assert "swing decays" in swing_words(result(0.97), 0.02)
    assert "(×0.970 per cycle)" in swing_words(result(0.97), 0.02)
    assert "swing keeps its size" in swing_words(result(1.0), 0.02)
    assert "swing grows" in swing_words(result(1.02), 0.02)
    assert swing_words(result(0.97), float("nan")) == "no full cycles to compare"
