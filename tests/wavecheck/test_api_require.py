"""``require=`` in the Python entry points (issue 26): the same option as ``--require``, on
:class:`~wavecheck.engine.options.CheckOptions`; a required rule that is not decided raises
:class:`~wavecheck.errors.RequirementError` (exit code 4), which holds the whole report."""

from __future__ import annotations

from pathlib import Path

import pytest

import wavecheck
from wavecheck.engine import CheckOptions
from wavecheck.errors import RequirementError, UsageError
from wavecheck.options import options_from_keywords

REPO = Path(__file__).resolve().parents[2]
TWO_AXES = REPO / "captures" / "examples" / "two-axis.vcd"
GOLDEN = REPO / "captures" / "golden" / "g202-p20-worst-dirhold.vcd"


def test_options_check_the_rule_ids() -> None:
    assert CheckOptions(require=("all", "dir_hold")).require == ("all", "dir_hold")
    with pytest.raises(UsageError, match="'dir_hld' is not a rule"):
        CheckOptions(require=("dir_hld",))
    assert options_from_keywords(keywords={"require": "dir_setup, dir_hold"}).require == (
        "dir_setup",
        "dir_hold",
    )


def test_check_raises_when_a_required_rule_is_not_checked() -> None:
    with pytest.raises(RequirementError) as err:
        wavecheck.check(TWO_AXES, "gecko-g202", map={"step": "x_step"}, require="dir_setup")
    assert err.value.exit_code == 4
    assert str(err.value) == (
        f"{TWO_AXES}: required but not decided: dir_setup not checked: no DIR channel"
    )
    report = err.value.report
    assert isinstance(report, wavecheck.Report) and report.verdict == "pass"
    assert [u.rule for u in err.value.unmet] == ["dir_setup"]  # type: ignore[attr-defined]


def test_check_returns_when_the_required_rules_are_decided() -> None:
    report = wavecheck.check(GOLDEN, "gecko-g202", require=["all"])
    assert report.verdict == "fail"  # every rule decided; dir_hold fails


def test_check_axes_names_the_axis() -> None:
    axes = {"x": {"step": "x_step", "dir": "x_dir"}, "y": {"step": "y_step"}}
    with pytest.raises(RequirementError, match=r"y\.dir_hold not checked: no DIR channel"):
        wavecheck.check_axes(TWO_AXES, axes, "gecko-g202", require="dir_hold")
    machine = wavecheck.check_axes(TWO_AXES, axes, "gecko-g202", require="step_high")
    assert [a.axis for a in machine.axes] == ["x", "y"]
