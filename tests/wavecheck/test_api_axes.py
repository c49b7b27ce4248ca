"""``wavecheck.check_axes``: several axes from one reading of a capture, each equal to a
single-axis ``wavecheck.check`` (issue 13)."""

from __future__ import annotations

from pathlib import Path

import pytest

import wavecheck
from wavecheck import Axis, MachineReport, UsageError, check, check_axes

REPO = Path(__file__).resolve().parents[2]
TWO_AXIS = REPO / "captures" / "examples" / "two-axis.vcd"
X = {"step": "x_step", "dir": "x_dir"}
Y = {"step": "y_step", "dir": "y_dir"}


def _figures(r: wavecheck.Report) -> tuple[object, ...]:
    rules = [(x.rule, x.verdict, x.violations, x.min_margin_ns) for x in r.rules]
    return (r.verdict, r.steps.count, r.steps.final_position, rules, r.rates.named())


def _position(mapping: dict[str, str]) -> int | None:
    return check(TWO_AXIS, "gecko-g202", map=mapping).steps.final_position


def test_each_axis_equals_a_single_check() -> None:
    m = check_axes(TWO_AXIS, {"x": X, "y": Axis(Y)}, "gecko-g202")
    assert isinstance(m, MachineReport)
    assert [r.axis for r in m.axes] == ["x", "y"]
    assert (m.verdict, m.axis("x").verdict, m.axis("y").verdict) == ("fail", "fail", "pass")
    for name, mapping in (("x", X), ("y", Y)):
        assert _figures(m.axis(name)) == _figures(check(TWO_AXIS, "gecko-g202", map=mapping))


def test_the_capture_is_read_once(monkeypatch: pytest.MonkeyPatch) -> None:
    import wavecheck.capture.open as opener

    calls = []
    real = opener.open_source

    def counting(*a, **k):  # type: ignore[no-untyped-def]
        source = real(*a, **k)
        blocks = source.blocks
        calls.append(0)

        def counted():  # type: ignore[no-untyped-def]
            calls[-1] += 1
            return blocks()

        source.blocks = counted
        return source

    monkeypatch.setattr(opener, "open_source", counting)
    check_axes(TWO_AXIS, {"x": X, "y": Y}, "gecko-g202")
    assert calls == [1]  # one source, its blocks read once for both axes


def test_an_axis_takes_its_own_drive_and_options(smoothie_sr: Path) -> None:
    m = check_axes(
        smoothie_sr,
        {
            "x": {"step": "5", "dir": "6"},
            "y": Axis({"step": "3", "dir": "4"}, drive="leadshine-dm542"),
        },
        "gecko-g202",
    )
    assert {r.axis: r.drive.id for r in m.axes} == {"x": "gecko-g202", "y": "leadshine-dm542"}
    assert (m.axis("x").rule("step_high").verdict, m.axis("y").verdict) == ("fail", "pass")
    # an axis's own invert and DIR polarity: y's reversed direction, x unchanged
    flipped = check_axes(TWO_AXIS, {"x": X, "y": Axis(Y, forward_level=1)}, "gecko-g202")
    assert flipped.axis("y").steps.final_position == -_position(Y)
    assert flipped.axis("x").steps.final_position == _position(X)


@pytest.mark.parametrize(
    ("axes", "kwargs", "message"),
    [
        ({"x": X, "y": Y}, {}, "axis x has no drive"),
        ({"x": X, "y": {"step": "x_step"}}, {"drive": "gecko-g202"}, "mapped as x.step and y.step"),
        ({"x": X}, {"drive": "gecko-g202", "map": {"dir": "y_dir"}}, "every role but enable"),
        ({}, {"drive": "gecko-g202"}, "no axis given"),
    ],
)
def test_bad_axes_are_usage_errors(axes: dict, kwargs: dict, message: str) -> None:
    with pytest.raises(UsageError, match=message):
        check_axes(TWO_AXIS, axes, **kwargs)


def test_check_points_axis_roles_to_check_axes() -> None:
    with pytest.raises(UsageError, match="check_axes"):
        check(TWO_AXIS, "gecko-g202", map={"x.step": "x_step"})
