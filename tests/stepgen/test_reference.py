"""The reference model against the documented facts of shared/reference/stepgen-linuxcnc.md."""

from __future__ import annotations

import numpy as np
import pytest

from stepgen.fast import run_fast
from stepgen.reference import (
    Component,
    StepgenConfig,
    hal_thread_period,
    run_reference,
    ulceil,
)
from tests.stepgen.helpers import counts_per_period, levels
from tests.stepgen.test_fast import assert_same as assert_same_run
from wavecheck.errors import ConfigError

# §8: tests/stepgen.0 — one 100 µs thread, update-freq first, position mode
STEPGEN0 = StepgenConfig(
    step_type=0,
    base_period_ns=100_000,
    servo_period_ns=100_000,
    mode="position",
    position_scale=32000,
    maxvel=0.15,
    maxaccel=2,
    thread_order="update-first",
)


@pytest.mark.parametrize("engine", [run_reference, run_fast])
def test_stepgen0_golden_facts(engine) -> None:
    """§8 tests/stepgen.0: 1280 single-period pulses, DIR always 0, first rising edge at 39."""
    run = engine(STEPGEN0, [0.04], 3500)
    step = levels(run, "step")
    assert run.steps == 1280
    rising = np.flatnonzero(np.diff(np.concatenate(([0], step))) == 1)
    assert len(rising) == 1280
    assert rising[0] == 39  # depends on the P = 50 µs first-cycle constants (§3 start-up quirk)
    assert not np.any(step[1:] & step[:-1])  # never two high samples in a row
    assert len(run.toggles["dir"]) == 0
    assert counts_per_period(run)[-1] == 1280
    assert run.final["counts"] == 1280


def test_stepgen0_needs_the_startup_quirk() -> None:
    """§3/§8: with make-pulses first (no quirk) the first edge is NOT at 39 — the quirk matters."""
    run = run_reference(
        StepgenConfig(**{**STEPGEN0.__dict__, "thread_order": "pulses-first"}), [0.04], 3500
    )
    first = int(run.toggles["step"][0])
    assert first != 39


@pytest.mark.parametrize("engine", [run_reference, run_fast])
def test_stepgen1_quadrature_decodes_to_counts(engine) -> None:
    """§8 tests/stepgen.1: type 2, A leading B = +1, decoded position == counts every period."""
    cfg = StepgenConfig(**{**STEPGEN0.__dict__, "step_type": 2})
    run = engine(cfg, [0.04], 3500)
    a, b = levels(run, "phase-A"), levels(run, "phase-B")
    assert (a[0], b[0]) == (1, 0)  # state 0 pattern from the first call
    table = [1, 3, 2, 0]  # quadrature states, phase A = bit 0
    state = [table.index(int(x) | (int(y) << 1)) for x, y in zip(a, b, strict=True)]
    pos = [0]
    for prev, cur in zip(state, state[1:], strict=False):
        d = (cur - prev) % 4
        assert d in (0, 1, 3), "non-neighbour quadrature transition"
        pos.append(pos[-1] + {0: 0, 1: 1, 3: -1}[d])
    np.testing.assert_array_equal(np.array(pos), counts_per_period(run))
    assert pos[-1] == 1280


def test_ulceil_rounds_up_to_multiples() -> None:
    """§3: ceil_to_multiple(v, P) = 0 if v == 0 else P·(floor((v−1)/P) + 1)."""
    assert ulceil(0, 25000) == 0
    assert ulceil(1, 25000) == 25000
    assert ulceil(25000, 25000) == 25000
    assert ulceil(25001, 25000) == 50000
    assert ulceil(20000, 16000) == 32000  # [HAL] example


def test_hal_servo_period_rounding() -> None:
    """§1 [HL]: BASE 30 000, SERVO 1 000 000 → 990 000 (round-half-up to n·base)."""
    assert hal_thread_period(30_000, 1_000_000) == 990_000
    assert hal_thread_period(25_000, 1_000_000) == 1_000_000
    assert hal_thread_period(20_000, 30_000) == 40_000  # 1.5 rounds half up
    assert StepgenConfig(base_period_ns=30_000, servo_period_ns=1_000_000).servo_ns == 990_000
    with pytest.raises(ConfigError):
        hal_thread_period(30_000, 20_000)


def _component(steplen: int, base: int, order: str = "update-first") -> Component:
    return Component([StepgenConfig(steplen=steplen, base_period_ns=base, thread_order=order)])  # type: ignore[arg-type]


def test_rounding_is_written_back_and_never_shrinks() -> None:
    """§3: rounded values are written back; a base-period change re-rounds from them (never shrinks)."""
    comp = _component(5000, 50_000)
    ch = comp.channels[0]
    comp.make_pulses(50_000)
    comp.update_freq(1_000_000)
    assert ch.step_len == 50_000  # written back
    comp.make_pulses(25_000)
    comp.update_freq(1_000_000)
    assert ch.step_len == 50_000  # not back to 25 000: the request 5000 is lost
    comp.make_pulses(30_000)
    comp.update_freq(1_000_000)
    assert ch.step_len == 60_000


def test_steplen_zero_becomes_one_period_and_dirhold_nonzero_for_types_0_1() -> None:
    """§3 rules 1 and 4: steplen 0 → 1 period; dirhold+dirsetup 0 → 1 period for types < 2 only."""
    for t, expect_hold in ((0, 25_000), (1, 25_000), (2, 0)):
        comp = Component(
            [
                StepgenConfig(
                    step_type=t,
                    steplen=0,
                    dirsetup=0,
                    dirhold=0,
                    dirdelay=0,
                    base_period_ns=25_000,
                    thread_order="pulses-first",
                )
            ]
        )
        comp.make_pulses(25_000)
        comp.update_freq(1_000_000)
        ch = comp.channels[0]
        assert ch.step_len == 25_000
        assert ch.dir_hold_dly == expect_hold


@pytest.mark.parametrize(
    ("base", "order", "expected"),
    [
        (25_000, "update-first", 50_000),  # quirk: 2 periods, not 1
        (30_000, "update-first", 60_000),
        (25_000, "pulses-first", 25_000),  # no quirk
    ],
)
def test_startup_quirk(base: int, order: str, expected: int) -> None:
    """§3 start-up quirk: update-freq before the first make-pulses rounds with P = 50 µs first."""
    run = run_reference(
        StepgenConfig(
            steplen=5000, base_period_ns=base, servo_period_ns=base * 40, thread_order=order
        ),  # type: ignore[arg-type]
        [0.0],
        200,
    )
    assert run.final["steplen"] == expected


def test_maxvel_too_high_is_clamped_and_written_back() -> None:
    """§4 step 6: maxvel·|scale| > max_freq → warning once, maxvel := max_freq/|scale|."""
    cfg = StepgenConfig(
        base_period_ns=25_000,
        servo_period_ns=1_000_000,
        position_scale=-100,
        maxvel=1000,
        mode="velocity",
        thread_order="pulses-first",
    )
    run = run_reference(cfg, [5.0], 400)
    max_freq = 1.0 / (50_000 * 0.000000001)  # steplen + stepspace = 2 periods
    assert run.final["maxvel"] == max_freq / 100
    assert len(run.warnings) == 1 and "too high" in run.warnings[0]


def test_maxaccel_too_high_is_clamped_and_written_back() -> None:
    """§4 step 7: maxaccel·|scale| > max_freq/dt → maxaccel := max_ac/|scale|."""
    cfg = StepgenConfig(
        base_period_ns=25_000,
        servo_period_ns=1_000_000,
        position_scale=10,
        maxaccel=1e9,
        mode="velocity",
        thread_order="pulses-first",
    )
    run = run_reference(cfg, [1.0], 400)
    max_ac = (1.0 / (50_000 * 0.000000001)) * (1.0 / (1_000_000 * 0.000000001))
    assert run.final["maxaccel"] == max_ac / 10


def test_bad_settings_are_config_errors() -> None:
    """Bad settings refuse to run with one-line ConfigErrors."""
    bad = [
        {"base_period_ns": 0},
        {"position_scale": 0.0},
        {"steplen": -1},
        {"maxvel": -1.0},
        {"step_type": 16},
    ]
    for kw in bad:
        with pytest.raises(ConfigError) as err:
            StepgenConfig(**kw).validate()  # type: ignore[arg-type]
        assert "\n" not in str(err.value)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"base_period_ns": 2 * 10**9}, r"base period 2\.000e\+9 ns is longer than 1 s"),
        ({"servo_period_ns": 10**400}, r"servo period 1\.000e\+400 ns is longer than 1 s"),
    ],
)
def test_thread_periods_longer_than_a_second_are_refused(kwargs: dict, message: str) -> None:
    with pytest.raises(ConfigError, match=message):
        StepgenConfig(**kwargs).validate()


@pytest.mark.parametrize("order", ["update-first", "pulses-first"])
def test_steplen_longer_than_the_servo_period_runs_as_in_linuxcnc(order: str) -> None:
    """§3/§4: steplen is any u32 ns, rounded up to base periods; update-freq has no limit tied to
    the servo period (only max_freq = 1e9/(steplen + stepspace) follows from it). So a steplen
    longer than the servo period runs, with pulses of ceil(steplen/P) periods, in both engines.
    With update-first the start-up quirk rounds at 50 µs first (100 000 → 100 000 → 120 000 at
    P = 30 µs), also above 50 000 ns."""
    cfg = StepgenConfig(
        base_period_ns=30_000,
        servo_period_ns=90_000,
        mode="velocity",
        steplen=100_000,
        thread_order=order,  # type: ignore[arg-type]
    )
    cfg.validate()
    ref = run_reference(cfg, [2000.0, -2000.0, 2000.0], 300)
    assert_same_run(ref, run_fast(cfg, [2000.0, -2000.0, 2000.0], 300))
    assert ref.final["steplen"] == 120_000  # both orders: ceil to 30 µs (from 100 000 or 50 µs·2)
    step = levels(ref, "step")
    rises = np.flatnonzero(np.diff(np.concatenate(([0], step))) == 1)
    falls = np.flatnonzero(np.diff(np.concatenate(([0], step))) == -1)
    assert len(rises) > 3
    assert np.all(falls[: len(rises) - 1] - rises[: len(rises) - 1] == 4)  # 120 000 / 30 000


def test_validate_steplen_quirk_is_not_limited_to_50us() -> None:
    """§3 start-up quirk: the first rounding at P = 50 µs applies to every value, not only to
    1..50 000 ns: at base 25 µs, 60 000 ns → 100 000 (then stays), not 75 000."""
    cfg = StepgenConfig(base_period_ns=25_000, servo_period_ns=1_000_000, steplen=60_000)
    assert run_reference(cfg, [0.0], 100).final["steplen"] == 100_000
