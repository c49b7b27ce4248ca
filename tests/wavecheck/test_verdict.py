"""What a verdict claims (issue 26): the rules not checked, grouped by why, and ``--require``'s
rules that were not decided, with their own exit code (4) — one mechanism for ``check`` and
``config`` (:mod:`wavecheck.verdict`)."""

from __future__ import annotations

import pytest

from wavecheck.errors import RequirementError, UsageError
from wavecheck.rules import RULE_IDS
from wavecheck.verdict import (
    EXIT_FAIL,
    EXIT_INDETERMINATE,
    EXIT_PASS,
    EXIT_REQUIRED,
    EXIT_USAGE,
    RuleStatus,
    Unmet,
    check_require,
    qualified_verdict,
    require_list,
    required_exit_code,
    required_line,
    unchecked_by_reason,
    unmet_requirements,
    verdict_of_exit,
    worst_exit_code,
)

NO_DIR = "no DIR channel"
NO_FIGURE = "drive drv8825 states no figure"


def _axis(axis: str | None, dir_mapped: bool = False) -> list[RuleStatus]:
    dir_verdict = "pass" if dir_mapped else "unchecked"
    why = "" if dir_mapped else NO_DIR
    return [
        RuleStatus("step_high", "pass", axis=axis),
        RuleStatus("step_low", "indeterminate", "3 interval(s) within one sample", axis),
        RuleStatus("dir_setup", dir_verdict, why, axis),
        RuleStatus("dir_hold", dir_verdict, why, axis),
        RuleStatus("enable_setup", "unchecked", NO_FIGURE, axis, stated=False),
    ]


def test_exit_code_4_is_new_and_ranks_between_fail_and_indeterminate() -> None:
    assert EXIT_REQUIRED == 4 == RequirementError.exit_code
    assert EXIT_REQUIRED not in (EXIT_PASS, EXIT_FAIL, EXIT_USAGE, EXIT_INDETERMINATE)
    assert worst_exit_code([0, 3, 4]) == 4
    assert worst_exit_code([4, 1]) == 1 and worst_exit_code([4, 2]) == 2
    assert verdict_of_exit(4) is None  # not a verdict of the rules: the run's requirement


def test_the_verdict_line_names_each_rule_not_checked_by_why() -> None:
    line = qualified_verdict("pass", unchecked_by_reason(_axis(None)))
    assert line == (
        "PASS (dir_setup, dir_hold not checked: no DIR channel; "
        "enable_setup not checked: drive drv8825 states no figure)"
    )
    assert qualified_verdict("fail", {}) == "FAIL"
    assert qualified_verdict("fail", {}, "2 axes") == "FAIL (2 axes)"


def test_over_several_axes_a_rule_of_some_axes_is_named_with_its_axis() -> None:
    rows = _axis("x", dir_mapped=True) + _axis("y")
    assert unchecked_by_reason(rows) == {
        "drive drv8825 states no figure": ("enable_setup",),  # on every axis: named alone
        NO_DIR: ("y.dir_setup", "y.dir_hold"),
    }


@pytest.mark.parametrize(
    ("require", "expected"),
    [
        ((), []),
        (("step_high",), []),  # decided: pass
        (("all",), [("step_low", "3 interval(s)"), ("dir_setup", NO_DIR), ("dir_hold", NO_DIR)]),
        (("enable_setup",), [("enable_setup", NO_FIGURE)]),  # named: required without a figure
        (("state_hold",), [("state_hold", "not a rule of this step type")]),
        (("dir_hold", "all"), [("step_low", "3"), ("dir_setup", NO_DIR), ("dir_hold", NO_DIR)]),
    ],
)
def test_unmet_requirements(require: tuple[str, ...], expected: list[tuple[str, str]]) -> None:
    got = unmet_requirements(_axis(None), require)
    assert [u.rule for u in got] == [rule for rule, _ in expected]
    assert all(u.why.startswith(why) for u, (_, why) in zip(got, expected, strict=True))


def test_required_line_and_exit_code() -> None:
    unmet = unmet_requirements(_axis(None), ("all",))
    assert required_line(unmet) == (
        "required but not decided: step_low indeterminate: "
        "3 interval(s) within one sample; dir_setup, dir_hold not checked: no DIR channel"
    )
    assert required_line(()) == ""
    assert required_exit_code(EXIT_PASS, unmet) == EXIT_REQUIRED
    assert required_exit_code(EXIT_INDETERMINATE, unmet) == EXIT_REQUIRED
    assert required_exit_code(EXIT_FAIL, unmet) == EXIT_FAIL  # a failed rule says more
    assert required_exit_code(EXIT_PASS, ()) == EXIT_PASS


def test_required_line_over_axes() -> None:
    rows = _axis("x") + _axis("y", dir_mapped=True)
    unmet = unmet_requirements(rows, ("dir_hold", "enable_setup"))
    assert unmet[0] == Unmet("dir_hold", "unchecked", NO_DIR, "x")
    line = required_line(unmet, rows)
    assert "x.dir_hold not checked: no DIR channel" in line
    assert "; enable_setup not checked: drive drv8825 states no figure" in line  # every axis


def test_require_list_and_its_check() -> None:
    assert require_list("dir_setup, dir_hold") == ("dir_setup", "dir_hold")
    assert require_list(["all", "dir_hold,all"]) == ("all", "dir_hold")
    assert require_list(None) == ()
    check_require(("all", *RULE_IDS), RULE_IDS)
    with pytest.raises(UsageError, match="--require 'dir_hld' is not a rule"):
        check_require(("dir_hld",), RULE_IDS)
