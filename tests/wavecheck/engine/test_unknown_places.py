"""Unknown places counted exactly (issue 26): what touches an ``x``/``z`` stretch is left out and
counted, a stretch no interval touches counts where an interval of the rule may hide in it, and
nothing else does."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.engine_probe import run_check
from tests.wavecheck.waves import drive
from wavecheck.capture.open import open_capture

HEAD = (
    "$timescale 1 us $end\n$scope module t $end\n$var wire 1 ! step $end\n"
    '$var wire 1 " dir $end\n$upscope $end\n$enddefinitions $end\n'
)


def _vcd(tmp_path: Path, body: str) -> Path:
    p = tmp_path / "u.vcd"
    p.write_text(HEAD + body)
    return p


def test_a_pulse_across_an_unknown_stretch_is_not_measured(tmp_path: Path) -> None:
    """STEP high at 10, x at 12, high again at 14, low at 20: the 10 us 'pulse' may be two
    pulses; it is left out and counted, never measured as 10 us (it was, before)."""
    body = '#0\n0!\n0"\n#10\n1!\n#12\nx!\n#14\n1!\n#20\n0!\n#30\n1!\n#31\n0!\n#40\n'
    r = run_check(open_capture(_vcd(tmp_path, body)), drive("rising", step_high=3000))
    high = r.rule("step_high")
    assert high is not None and high.measured_ticks.tolist() == [1] and high.unknown == 1
    assert high.unknown_ticks.tolist() == [10]


def test_a_pulse_that_began_unknown_is_counted(tmp_path: Path) -> None:
    """x → 1 at 5 → 0 at 7: the first pulse's start is hidden; it counts as one unknown place
    of step_high (it was dropped without a word)."""
    body = '#0\nx!\n0"\n#5\n1!\n#7\n0!\n#10\n1!\n#13\n0!\n#40\n'
    r = run_check(open_capture(_vcd(tmp_path, body)), drive("rising", step_high=1000))
    high = r.rule("step_high")
    assert high is not None and high.checked == 1 and high.unknown == 1
    assert high.unknown_ticks.tolist() == [0]


@pytest.mark.parametrize("rule", ["dir_setup", "dir_hold"])
def test_step_unknown_until_its_first_write_hides_no_dir_interval(
    tmp_path: Path, rule: str
) -> None:
    """A Pluto-P run: STEP is x until its first write, DIR known throughout and changing once,
    after some steps. The one DIR interval of each kind is known and judged: no unknown place
    (each reported one at 0 s)."""
    body = (
        '#0\nx!\n0"\n#5\n0!\n#10\n1!\n#12\n0!\n#20\n1!\n#22\n0!\n#30\n1"\n#40\n1!\n#42\n0!\n#60\n'
    )
    d = drive("rising", step_high=1000, step_low=1000, dir_setup=1000, dir_hold=1000)
    r = run_check(open_capture(_vcd(tmp_path, body)), d)
    res = r.rule(rule)
    assert res is not None and res.checked == 1 and res.unknown == 0


def test_step_unknown_before_a_dir_change_that_no_step_precedes_may_hide_a_hold(
    tmp_path: Path,
) -> None:
    """STEP x until 10, DIR changing at 8 before any step: a hidden active edge before 8 would
    make a DIR hold interval: one unknown place of dir_hold, none of dir_setup (its interval
    from 8 to the first step is measured)."""
    body = '#0\nx!\n0"\n#8\n1"\n#10\n0!\n#20\n1!\n#22\n0!\n#60\n'
    d = drive("rising", step_high=1000, step_low=1000, dir_setup=1000, dir_hold=1000)
    r = run_check(open_capture(_vcd(tmp_path, body)), d)
    hold, setup = r.rule("dir_hold"), r.rule("dir_setup")
    assert hold is not None and hold.unknown == 1 and hold.checked == 0
    assert setup is not None and setup.unknown == 1  # 8 -> 20 touches the x up to 10


def test_no_step_rate_from_an_interval_touching_unknown_and_position_unknown_from_there(
    tmp_path: Path,
) -> None:
    """Issue 33: steps 10 us apart, STEP x from 33 to 36 (a step may hide there), then steps
    again. The step at 36 (where STEP comes back high) is 6 us after the last before the x: that
    interval touches the unknown and gives no rate (the known ones give 100 kHz, not 166.7 kHz);
    the final position is unknown from 33 us, not +6."""
    body = (
        '#0\n0!\n0"\n#10\n1!\n#12\n0!\n#20\n1!\n#22\n0!\n#30\n1!\n#32\n0!\n#33\nx!\n'
        "#36\n1!\n#38\n0!\n#48\n1!\n#50\n0!\n#58\n1!\n#60\n0!\n#80\n"
    )
    r = run_check(open_capture(_vcd(tmp_path, body)), drive("rising", step_high=1000))
    assert r.report.rates.observed == 100_000  # 1 / 10 us, exact hertz
    assert r.steps.counts.lost_from == 33 and r.steps.counts.final_position is None
    assert r.steps.counts.count == 6  # the steps seen; one more may hide in 33..36


def test_a_leading_unknown_stretch_leaves_the_position_exact(tmp_path: Path) -> None:
    """x until the first write (a simulator's reset): the position counts from there."""
    body = '#0\nx!\n0"\n#5\n0!\n#10\n1!\n#12\n0!\n#20\n1!\n#22\n0!\n#40\n'
    r = run_check(open_capture(_vcd(tmp_path, body)), drive("rising", step_high=1000))
    assert r.steps.counts.lost_from is None and r.steps.counts.final_position == 2
