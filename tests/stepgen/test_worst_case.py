"""``worst:J:RULE`` as a proof: the catch-up run time never hides n·P − J, and the worst-case
motion makes every interval of every rule at its fewest periods.

Facts checked (shared/reference/stepgen-linuxcnc.md):
- §9 [TWK]: an interval stepgen makes n periods long is only n·P − J long when one edge is J late
  and the next on time; n per interval as :func:`wavecheck.linuxcnc.timing.evaluate` lists them.
- §2.3: DIR changes dirhold periods after the pulse ends and the first opposite step comes
  dirsetup periods after the DIR change when the reversal is requested before timer2 expires; the
  gap across a reversal is dirhold + dirsetup and the step period steplen + dirhold + dirsetup;
  at the full rate steps come steplen + stepspace periods apart.
"""

from __future__ import annotations

from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest

import wavecheck
from stepgen.cli import main
from stepgen.motion import worst_motion
from stepgen.reference import StepgenConfig, run_reference, update_schedule
from stepgen.simulate import simulate
from tests.wavecheck.waves import drive
from wavecheck.linuxcnc.timing import evaluate

P, J = 20_000, 11_000
# A: the same-direction intervals are the shortest of step_low / step_period;
# B: those across a reversal are (dirhold + dirsetup < stepspace).
PERIODS = {
    "A": {"steplen": 2, "stepspace": 1, "dirsetup": 2, "dirhold": 3},
    "B": {"steplen": 1, "stepspace": 4, "dirsetup": 1, "dirhold": 1},
}
RULES = ("step_high", "step_low", "step_period", "dir_setup", "dir_hold")


def _cli_args(periods: dict[str, int]) -> list[str]:
    out = ["--base-period", f"{P}ns", "--servo-period", "1ms"]
    for name, n in periods.items():
        out += [f"--{name}", f"{n * P}ns"]
    return out


@pytest.mark.parametrize("edge", ["rising", "falling"])
@pytest.mark.parametrize("which", sorted(PERIODS))
@pytest.mark.parametrize("rule", RULES)
def test_worst_case_run_reaches_n_P_minus_J_for_every_rule(
    tmp_path: Path, rule: str, which: str, edge: str
) -> None:
    """§9 + §2.3: with no motion given, ``worst:J:RULE`` uses the worst-case motion, and the
    shortest RULE interval wavecheck measures is n·P − J with n the fewest periods of any RULE
    interval the parameters allow (evaluate's rows: same direction and across a reversal)."""
    periods = PERIODS[which]
    out = tmp_path / "w.vcd"
    code = main(
        [
            "simulate",
            *_cli_args(periods),
            "--latency",
            f"worst:{J}ns:{rule}",
            "--active-edge",
            edge,
            "-q",
            "-o",
            str(out),
        ]
    )
    assert code == 0
    d = drive(edge, max_rate_hz=10**7, step_high=1, step_low=1, dir_setup=1, dir_hold=1)
    n = min(r.periods for r in evaluate(d, J, P, periods) if r.rule == rule)
    report = wavecheck.check(out, d, resolution="0ns")
    assert report.rule(rule).min_measured_ns == n * P - J


def test_worst_motion_makes_every_interval_at_its_fewest_periods() -> None:
    """§2.3 in whole periods, no latency: the worst-case motion's steps come steplen + stepspace
    apart at full rate, and each reversal changes DIR dirhold periods after the pulse ends with the
    next step dirsetup periods later — on both directions, every time."""
    per = PERIODS["A"]
    cfg = StepgenConfig(
        base_period_ns=P,
        servo_period_ns=1_000_000,
        mode="velocity",
        thread_order="pulses-first",
        **{k: v * P for k, v in per.items()},
    )
    motion = worst_motion(cfg)
    n = int(round(motion.natural_duration_s * 1e9)) // P
    run = run_reference(
        cfg, motion.commands(len(update_schedule(cfg, n)), cfg.servo_ns, "velocity"), n
    )
    rises, dirs = run.toggles["step"][0::2], run.toggles["dir"]
    assert len(dirs) == 4  # WORST_REVERSALS, both ways
    assert np.diff(rises).min() == per["steplen"] + per["stepspace"]
    before = rises[np.searchsorted(rises, dirs) - 1]
    after = rises[np.searchsorted(rises, dirs)]
    assert set(dirs - before) == {per["steplen"] + per["dirhold"]}
    assert set(after - dirs) == {per["dirsetup"]}


def test_default_catchup_does_not_hide_the_bound() -> None:
    """§9: J = 24.5 µs at P = 25 µs, steplen one period: the shortest pulse is P − J = 500 ns.
    With a 1 µs run time the on-time invocation after a late one would start 500 ns late."""
    cfg = StepgenConfig(
        base_period_ns=25_000,
        servo_period_ns=1_000_000,
        mode="velocity",
        thread_order="pulses-first",
    )
    motion = worst_motion(cfg)
    n = int(round(motion.natural_duration_s * 1e9)) // 25_000
    trace = simulate(cfg, motion, "worst:24500ns:step_high", n_periods=n)
    e = trace.edges["step"]
    assert (e[1::2] - e[0::2]).min() == 500
    assert any("P − J = 500 ns" in note for note in trace.notes)


def test_explicit_catchup_that_prevents_the_bound_is_a_one_line_warning(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """§9: an explicit --catchup 2us > P − J = 500 ns is kept; the one-line warning says the
    pulses are (n − 1)·P + G = 2 µs instead of n·P − J."""
    out = tmp_path / "c.vcd"
    code = main(
        [
            "simulate",
            "--mode",
            "velocity",
            "--latency",
            "worst:24.5us:step_high",
            "--catchup",
            "2us",
            "-q",
            "-o",
            str(out),
        ]
    )
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 0
    assert len(err) == 1 and "warning" in err[0] and "(n − 1)·P + 2000 ns" in err[0]
    report = wavecheck.check(out, drive("rising", step_high=1), resolution="0ns")
    assert report.rule("step_high").min_measured_ns == Fraction(2000)


def test_worst_motion_switches_a_position_channel_to_velocity(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The worst-case motion drives velocity-cmd; a position-mode channel is run in velocity mode
    and says so (make-pulses, §2, does not depend on ctrl_type)."""
    code = main(
        [
            "simulate",
            "--latency",
            "worst:11us:dir_hold",
            "--base-period",
            "20us",
            "-q",
            "-o",
            str(tmp_path / "p.vcd"),
        ]
    )
    err = capsys.readouterr().err
    assert code == 0 and "velocity mode" in err
