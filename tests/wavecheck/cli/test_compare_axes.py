"""``wavecheck compare`` with several axes (issue 13): each axis of the capture against the
same-named axis of the golden, the worst verdict, one unnamed axis unchanged."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from tests.conftest import write_vcd
from wavecheck.capture.open import open_capture
from wavecheck.cli import main

REPO = Path(__file__).resolve().parents[3]
TWO_AXIS = REPO / "captures" / "examples" / "two-axis.vcd"
MAPS = ["--map", "x.step=x_step,x.dir=x_dir", "--map", "y.step=y_step,y.dir=y_dir"]


def _without_last_step(axis: str, path: Path) -> Path:
    """The two-axis example with the last pulse of ``axis``'s STEP removed."""
    cap = open_capture(TWO_AXIS)
    signals = {}
    for ch in cap.channels:
        edges = [int(t) for t in ch.edges]
        if ch.name == f"{axis}_step":
            edges = edges[:-2]
        signals[ch.name] = (ch.initial, edges)
    return write_vcd(path, signals, end=cap.end)


def _run(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str]:
    code = main(["compare", *argv])
    return code, capsys.readouterr().out


def test_the_example_against_itself_passes(capsys: pytest.CaptureFixture[str]) -> None:
    code, out = _run(capsys, str(TWO_AXIS), str(TWO_AXIS), "--drive", "gecko-g202", *MAPS)
    # issue 34: the line says what was compared (the example's golden fails dir_hold on x)
    assert code == 0 and out.startswith("verdict: PASS (2 axes; each axis matches its golden trace")
    assert "== axis x ==" in out and "== axis y ==" in out
    # x fails dir_hold in both files: a golden failing a rule is matched by the capture failing it
    x = out.split("== axis x ==")[1].split("== axis y ==")[0]
    assert "dir_hold     fail (1)  fail (1)" in x


def test_one_axis_short_of_a_step_fails_naming_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    cap = _without_last_step("y", tmp_path / "c.vcd")
    code, out = _run(
        capsys, str(cap), str(TWO_AXIS), "--drive", "gecko-g202", *MAPS, "--format", "json"
    )
    data = json.loads(out)
    assert code == 1 and data["verdict"] == "fail"
    assert set(data) == {"capture", "golden", "axes", "failures", "said", "verdict"}
    assert {a["name"]: a["verdict"] for a in data["axes"]} == {"x": "pass", "y": "fail"}
    y = next(a for a in data["axes"] if a["name"] == "y")
    assert y["steps"]["count"] == {"capture": 3, "golden": 4}
    assert "axis y: step count 3 vs 4" in data["failures"]
    assert not any(f.startswith("axis x") for f in data["failures"])
    code, out = _run(capsys, str(cap), str(TWO_AXIS), "--drive", "gecko-g202", *MAPS)
    assert code == 1 and out.startswith("verdict: FAIL (2 axes; axis y: step count 3 vs 4")


def test_golden_map_and_per_axis_drive(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The golden's channels named otherwise (--golden-map), y against another drive."""
    cap = open_capture(TWO_AXIS)
    renamed = write_vcd(
        tmp_path / "g.vcd",
        {f"G{ch.index}": (ch.initial, [int(t) for t in ch.edges]) for ch in cap.channels},
        end=cap.end,
    )
    index = {ch.name: ch.index for ch in cap.channels}
    gmap = [
        "--golden-map",
        f"x.step=G{index['x_step']},x.dir=G{index['x_dir']}",
        "--golden-map",
        f"y.step=G{index['y_step']},y.dir=G{index['y_dir']}",
    ]
    code, out = _run(
        capsys,
        str(TWO_AXIS),
        str(renamed),
        "--drive",
        "gecko-g202",
        "--drive",
        "y=leadshine-dm542",
        *MAPS,
        *gmap,
        "--format",
        "json",
    )
    data = json.loads(out)
    assert code == 0, data["failures"]
    assert {a["name"]: a["drive"] for a in data["axes"]} == {
        "x": "gecko-g202",
        "y": "leadshine-dm542",
    }


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (
            ["--golden-map", "x.step=x_step,x.dir=x_dir"],
            "the capture's axes (x, y) and the golden's (x) differ",
        ),
        (["--drive", "z=leadshine-dm542"], "no axis 'z' is mapped"),
        (["--invert", "z.step"], "no axis 'z' is mapped"),
        (["--golden-map", "x.step=x_step,x.dir=x_dir", "--golden-map", "y.step=nope"], "golden"),
    ],
)
def test_mismatched_axes_are_usage_errors(
    capsys: pytest.CaptureFixture[str], extra: list[str], message: str
) -> None:
    code = main(["compare", str(TWO_AXIS), str(TWO_AXIS), "--drive", "gecko-g202", *MAPS, *extra])
    assert code == 2 and message in capsys.readouterr().err


def test_an_axis_without_a_drive(capsys: pytest.CaptureFixture[str]) -> None:
    code = main(["compare", str(TWO_AXIS), str(TWO_AXIS), "--drive", "x=gecko-g202", *MAPS])
    assert code == 2 and "axis y has no drive" in capsys.readouterr().err


def test_one_axis_keeps_todays_output(capsys: pytest.CaptureFixture[str]) -> None:
    """An unnamed axis: the plain comparison (no sections, no 'axes' key)."""
    argv = [
        str(TWO_AXIS),
        str(TWO_AXIS),
        "--drive",
        "gecko-g202",
        "--map",
        "step=y_step,dir=y_dir",
        "--golden-map",
        "step=y_step,dir=y_dir",
    ]
    code, out = _run(capsys, *argv)
    assert code == 0 and out.startswith("verdict: PASS (matches the golden trace: ")
    assert "\ncapture: " in out and "== axis" not in out
    code, out = _run(capsys, *argv, "--format", "json")
    assert set(json.loads(out)) == {
        "capture",
        "golden",
        "drive",
        "steps",
        "timing",
        "rules",
        "failures",
        "said",
        "verdict",
    }
