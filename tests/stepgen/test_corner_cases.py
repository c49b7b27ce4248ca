"""§2.4: the two documented cases where LinuxCNC's stepgen does not obey dirsetup.

Set-up as in the reference: base 25 µs, servo 1 ms, velocity mode, −0.5 step/s then +200 step/s.
Both engines must reproduce them (the faithful model keeps the quirks). make-pulses runs first,
so servo update u is first seen by base invocation u·N + 1.
"""

from __future__ import annotations

import numpy as np
import pytest

from stepgen.fast import run_fast
from stepgen.reference import StepgenConfig, run_reference
from tests.stepgen.helpers import levels

BASE = 25_000
SERVO = 1_000_000
N = SERVO // BASE


def _config(dirsetup_periods: int) -> StepgenConfig:
    return StepgenConfig(
        step_type=0,
        base_period_ns=BASE,
        servo_period_ns=SERVO,
        mode="velocity",
        position_scale=1.0,
        dirsetup=dirsetup_periods * BASE,
        dirhold=BASE,
        steplen=BASE,
        stepspace=BASE,
        thread_order="pulses-first",  # no start-up quirk: the timing params are exactly 1/1/1/S periods
    )


def _first_negative_step(cfg: StepgenConfig, vel: float) -> int:
    run = run_fast(cfg, [vel], 60_000)
    return int(run.toggles["step"][0])


def _reversal(cfg: StepgenConfig, vel: float, servo_tick: int, engine=run_reference):  # type: ignore[no-untyped-def]
    cmds = [vel] * servo_tick + [200.0] * 10
    return engine(cfg, cmds, (servo_tick + 10) * N)


@pytest.mark.parametrize("engine", [run_reference, run_fast])
def test_case1_reversal_after_timer3_expired_gives_zero_setup(engine) -> None:  # type: ignore[no-untyped-def]
    """§2.4 case 1: no hold (timer3 already 0) → DIR flips and STEP rises in the same period."""
    cfg = _config(dirsetup_periods=1)
    k = _first_negative_step(cfg, -0.5)
    tick = k // N + 1  # reverse at the next servo update: timers long expired, accum just past 0
    assert tick * N + 1 - k > 3  # timer3 (3 periods) has expired
    run = _reversal(cfg, -0.5, tick, engine)
    dir_edges = run.toggles["dir"]
    step_rises = run.toggles["step"][0::2]
    flip_back = int(dir_edges[1])  # DIR went 1 at the negative step, back to 0 at the reversal
    assert flip_back == tick * N + 1
    assert flip_back in set(step_rises.tolist())  # DIR change and STEP rising edge: same period


@pytest.mark.parametrize("engine", [run_reference, run_fast])
def test_case2_reversal_between_timer2_and_timer3_shortens_setup(engine) -> None:  # type: ignore[no-untyped-def]
    """§2.4 case 2 (LinuxCNC issue #2332): hold set, DIR flips at once, DDS released when timer3
    expires → actual setup 1 period instead of the configured dirsetup of 3."""
    cfg = _config(dirsetup_periods=3)
    # find a dwell velocity whose negative step lands 4 periods before a servo update
    for i in range(400):
        vel = -0.5 - i * 0.0005
        k = _first_negative_step(cfg, vel)
        if (k + 4 - 1) % N == 0:
            break
    else:
        pytest.fail("no dwell velocity puts the step 4 periods before a servo update")
    run = _reversal(cfg, vel, (k + 3) // N, engine)
    step = levels(run, "step")
    dirl = levels(run, "dir")
    change = int(run.toggles["dir"][1])
    assert change == k + 4  # timer2 (steplen + dirhold = 2 periods) expired: DIR flips now
    rises = np.flatnonzero((step[1:] == 1) & (step[:-1] == 0)) + 1
    next_rise = int(rises[rises > k][0])
    assert dirl[next_rise] == 0
    assert next_rise - change == 1  # released when timer3 (2 + 3 periods) expires: 1 period, not 3
