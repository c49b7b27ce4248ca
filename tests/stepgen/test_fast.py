"""The fast engine gives exactly the reference model's edges, counts and final state."""

from __future__ import annotations

from unittest import mock

import numpy as np
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from stepgen import fast
from stepgen.fast import run_fast
from stepgen.reference import InvocationRun, StepgenConfig, run_reference


def assert_same(a: InvocationRun, b: InvocationRun) -> None:
    assert a.pins == b.pins
    for pin in a.pins:
        np.testing.assert_array_equal(a.toggles[pin], b.toggles[pin], err_msg=pin)
    np.testing.assert_array_equal(a.counts_at, b.counts_at)
    np.testing.assert_array_equal(a.counts_val, b.counts_val)
    assert a.steps == b.steps
    assert a.final == b.final


@st.composite
def scenarios(draw):  # type: ignore[no-untyped-def]
    base = draw(st.sampled_from([10_000, 16_000, 25_000, 30_000, 50_000, 100_000]))
    servo = draw(st.sampled_from([base, base * 4, 1_000_000, 990_000]))
    stype = draw(st.sampled_from([0, 0, 1, 2, 3, 9, 14, 15]))
    mode = draw(st.sampled_from(["position", "velocity"]))
    scale = draw(st.sampled_from([1.0, 200.0, -320.0, 1000.0, 32000.0]))
    tmax = 200_000
    cfg = StepgenConfig(
        step_type=stype,
        user_step_type=(1, 3, 2, 6, 4) if stype == 15 else (),
        base_period_ns=base,
        servo_period_ns=servo,
        mode=mode,
        position_scale=scale,
        maxvel=draw(st.sampled_from([0.0, 1e3, 1e4, 1e5])) / abs(scale),  # steps/s → units/s
        maxaccel=draw(st.sampled_from([0.0, 1e4, 1e6, 1e8])) / abs(scale),
        steplen=draw(st.one_of(st.integers(0, base * 2), st.integers(0, tmax))),
        stepspace=draw(st.one_of(st.integers(0, base * 2), st.integers(0, tmax))),
        dirsetup=draw(st.integers(0, tmax)),
        dirhold=draw(st.integers(0, tmax)),
        dirdelay=draw(st.integers(0, tmax)),
        thread_order=draw(st.sampled_from(["update-first", "pulses-first"])),
    )
    n_servo = draw(st.integers(2, 30))
    # command amplitude in steps (position) or steps/s (velocity), converted to position units
    steps = draw(
        st.sampled_from([3.0, 30.0, 300.0] if mode == "position" else [300.0, 3000.0, 30000.0])
    )
    amp = steps / abs(scale)
    values = draw(st.lists(st.floats(-1, 1), min_size=1, max_size=8))
    hold = draw(st.integers(1, 6))
    cmds = np.repeat(np.array(values) * amp, hold)[:n_servo].tolist()
    n_periods = n_servo * (cfg.servo_ns // base) + draw(st.integers(0, 7))
    return cfg, cmds, n_periods


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(scenarios())
def test_fast_equals_reference(scenario) -> None:  # type: ignore[no-untyped-def]
    cfg, cmds, n = scenario
    try:
        cfg.validate()
    except Exception:
        return
    assert_same(run_reference(cfg, cmds, n), run_fast(cfg, cmds, n))


def test_fast_equals_reference_with_small_blocks() -> None:
    """Pass 2's block boundaries carry the STEP timer, the phase state and the levels across."""
    cfg = StepgenConfig(
        step_type=0,
        base_period_ns=25_000,
        servo_period_ns=1_000_000,
        mode="velocity",
        position_scale=1000.0,
        steplen=100_000,
        stepspace=25_000,
    )
    cmds = list(np.sin(np.arange(40) / 3) * 6)
    ref = run_reference(cfg, cmds, 40 * 40)
    assert_same(ref, run_fast(cfg, cmds, 40 * 40))
    cfg2 = StepgenConfig(**{**cfg.__dict__, "step_type": 9})
    assert_same(run_reference(cfg2, cmds, 1600), run_fast(cfg2, cmds, 1600))


def test_fast_uses_the_fast_path_in_steady_motion() -> None:
    """Most servo periods of a steady move go through the closed form, not the exact loop."""
    cfg = StepgenConfig(
        base_period_ns=25_000, servo_period_ns=1_000_000, mode="velocity", position_scale=1000.0
    )
    run = run_fast(cfg, [5.0], 40 * 500)
    assert run.exact_chunks <= 3 < run.fast_chunks


@st.composite
def fast_chunks(draw):  # type: ignore[no-untyped-def]
    """One fast chunk as pass 1 describes it: addval ramps from a0 toward target by deltalim and
    stays in [−2^28, 2^28] on one side of 0; the accumulator anywhere in its 64-bit range."""
    one = 1 << 28
    sign = draw(st.sampled_from([1, -1]))
    a0 = sign * draw(st.integers(0, one))
    target = draw(st.integers(-(2 * one), 2 * one))
    deltalim = draw(st.integers(0, one) | st.integers(0, 100))
    m = draw(st.integers(1, 3000))
    accum = draw(st.integers(-(1 << 60), 1 << 60) | st.integers(-(one * 8), one * 8))
    sgn, span = (1, target - a0) if target >= a0 else (-1, a0 - target)
    d_eff = deltalim if deltalim else span
    adds = [a0 + sgn * min(i * d_eff, span) for i in range(1, m + 1)]
    assume(all((a >= 0) == (a0 >= 0) and -one <= a <= one for a in adds))
    return (7, m, a0, sgn, d_eff, span, 1, 1, accum), adds


@settings(max_examples=300, deadline=None)
@given(
    st.lists(fast_chunks(), min_size=1, max_size=4),
    st.sampled_from([None, 0.0, 1e9]),
    st.sampled_from([1, 3, fast._STEPS_BLOCK]),
)
def test_fast_steps_are_where_counts_change(chunks, bad_root, block) -> None:  # type: ignore[no-untyped-def]
    """The closed-form steps of pass 2 are the periods where accum >> 28 changes, period by
    period. The float root is only a guess, checked exactly: with it wrong everywhere
    (``bad_root``) the binary search finds the same steps. Solved ``block`` steps at a time
    (whole chunks), the steps are the same."""
    cols = np.array([c for c, _ in chunks], dtype=np.int64).T
    with mock.patch.object(fast, "_STEPS_BLOCK", block):
        if bad_root is None:
            at, chunk, count = fast._fast_steps(cols)
        else:
            with mock.patch.object(fast, "_float_root", lambda *a: np.full(len(a[0]), bad_root)):
                at, chunk, count = fast._fast_steps(cols)
    want_at, want_chunk, want_count = [], [], []
    for ci, (desc, adds) in enumerate(chunks):
        accum = desc[8]
        for i, a in enumerate(adds):
            if (accum + a) >> 28 != accum >> 28:
                want_at.append(desc[0] + i)
                want_chunk.append(ci)
                want_count.append((accum + a) >> 28)
            accum += a
    assert at.tolist() == want_at
    assert chunk.tolist() == want_chunk
    assert count.tolist() == want_count


@st.composite
def tracking_scenarios(draw):  # type: ignore[no-untyped-def]
    """Position-mode runs long enough for pass 1's tracking loop (:func:`fast._track`): a
    command of velocity segments at, just under, just over and far beyond maxvel, and jumps
    that make the follower accelerate at maxaccel (its clamps and the bang-bang branch), so
    stretches where a clamp acts and where none does alternate."""
    base = draw(st.sampled_from([20_000, 25_000, 50_000]))
    servo = draw(st.sampled_from([base * 4, 1_000_000, 990_000]))
    scale = draw(st.sampled_from([1.0, 250.0, -1000.0, 3200.0]))
    vmax = draw(st.sampled_from([0.0, 2e3, 1e4, 1.9e4]))  # steps/s (0: the step-rate limit)
    amax = draw(st.sampled_from([0.0, 1e4, 1e5, 3e6]))  # steps/s²
    cfg = StepgenConfig(
        base_period_ns=base,
        servo_period_ns=servo,
        position_scale=scale,
        maxvel=vmax / abs(scale),
        maxaccel=amax / abs(scale),
        steplen=draw(st.integers(0, 2 * base)),
        stepspace=draw(st.integers(0, 2 * base)),
        dirsetup=draw(st.integers(0, 3 * base)),
        dirhold=draw(st.integers(0, 3 * base)),
        thread_order=draw(st.sampled_from(["update-first", "pulses-first"])),
    )
    limit = vmax or 1e9 / (2 * base)  # about the step-rate limit when maxvel is 0
    dt = servo * 1e-9
    vel: list[float] = []
    for _ in range(draw(st.integers(1, 6))):
        f = draw(st.sampled_from([0.0, 0.3, -0.7, 0.999, 1.0, -1.0, 1.001, 2.0, -3.0]))
        vel += [f * limit] * draw(st.integers(1, 120))
    pos = np.cumsum(np.array(vel) * dt)
    jumps = draw(
        st.lists(st.tuples(st.integers(0, len(pos) - 1), st.floats(-300, 300)), max_size=3)
    )
    for at, size in jumps:
        pos[at:] += size
    cmds = (pos / scale).tolist()
    n_periods = len(cmds) * (cfg.servo_ns // base) + draw(st.integers(0, 7))
    return cfg, cmds, n_periods


@settings(max_examples=120, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(tracking_scenarios())
def test_tracking_loop_equals_the_general_loop(scenario) -> None:  # type: ignore[no-untyped-def]
    """Pass 1's tracking loop (follow_position inlined, the chunk's closed form, descriptors
    made afterwards with numpy) gives exactly what the general per-period loop gives: the same
    toggles, counts, final state (freq, accum, addval … bit for bit) and warnings, where the
    maxvel/maxaccel clamps act and where they do not."""
    cfg, cmds, n = scenario
    try:
        cfg.validate()
    except Exception:
        return
    with mock.patch.object(fast, "_TRACK", False):
        general = run_fast(cfg, cmds, n)
    tracked = run_fast(cfg, cmds, n)
    assert_same(general, tracked)
    assert general.warnings == tracked.warnings
    assert (general.fast_chunks, general.exact_chunks) == (
        tracked.fast_chunks,
        tracked.exact_chunks,
    )


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(tracking_scenarios())
def test_tracking_loop_equals_the_reference(scenario) -> None:  # type: ignore[no-untyped-def]
    """The same runs against the plain per-period model (stepgen.reference)."""
    cfg, cmds, n = scenario
    try:
        cfg.validate()
    except Exception:
        return
    assume(n <= 12_000)
    assert_same(run_reference(cfg, cmds, n), run_fast(cfg, cmds, n))


def test_tracking_loop_runs_a_steady_sine() -> None:
    """A sine followed within its limits goes through the tracking loop, nearly every servo
    period (the rest: the start, before the clamps settle, and the reversals' exact chunks)."""
    cfg = StepgenConfig(base_period_ns=25_000, servo_period_ns=1_000_000, position_scale=1000.0,
                        maxvel=15.0, maxaccel=100.0, thread_order="pulses-first")  # fmt: skip
    cmds = (10 * np.sin(np.arange(4000) * 1e-3)).tolist()
    runs: list[tuple[int, int]] = []
    track = fast._track

    def spy(*a):  # type: ignore[no-untyped-def]
        out = track(*a)
        runs.append((a[1], out[0]))
        return out

    with mock.patch.object(fast, "_track", spy):
        run = run_fast(cfg, cmds, 4000 * 40)
    assert sum(b - a for a, b in runs) >= 3900
    with mock.patch.object(fast, "_TRACK", False):
        assert_same(run_fast(cfg, cmds, 4000 * 40), run)
