"""Several axes in one run (issue 13): one read of the capture, a section per axis, one verdict."""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from wavecheck.cli import main
from wavecheck.errors import UsageError
from wavecheck.steps.mapping import parse_axes, per_axis, split_invert

SMOOTHIE = ["--map", "x.step=5,x.dir=6", "--map", "y.step=3,y.dir=4"]


def _json(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, dict]:
    code = main(["check", *argv, "--format", "json"])
    return code, json.loads(capsys.readouterr().out)


@pytest.mark.parametrize(
    ("items", "axes"),
    [
        (["step=5,dir=6"], [(None, {"step": "5", "dir": "6"})]),
        (
            ["x.step=5,x.dir=6", "y.step=3,y.dir=4"],
            [("x", {"step": "5", "dir": "6"}), ("y", {"step": "3", "dir": "4"})],
        ),
        # a role without an axis is shared by every axis (one ENABLE for the machine)
        (
            ["x.step=5,y.step=3,enable=EN"],
            [("x", {"step": "5", "enable": "EN"}), ("y", {"step": "3", "enable": "EN"})],
        ),
        # channel names keep their commas and dots
        (["x.step=STEP (X, 1),x.dir=a.b"], [("x", {"step": "STEP (X, 1)", "dir": "a.b"})]),
    ],
)
def test_parse_axes(items: list[str], axes: list[tuple[str | None, dict[str, str]]]) -> None:
    assert [(a.name, a.roles) for a in parse_axes(items)] == axes


@pytest.mark.parametrize(
    ("items", "words"),
    [
        (["x.step=5,x.step=6"], "mapped twice"),
        (["x.step=5,y.step=5"], "one channel has one role on one axis"),
        (["x.step=5,dir=6"], "every role but enable names its axis"),
        (["x!.step=5"], "axis name"),
    ],
)
def test_parse_axes_refuses(items: list[str], words: str) -> None:
    with pytest.raises(UsageError, match=words):
        parse_axes(items)


def test_per_axis_options() -> None:
    assert per_axis(["gecko-g202", "y=leadshine-dm542"], "--drive", ["x", "y"]) == {
        "x": "gecko-g202",
        "y": "leadshine-dm542",
    }
    with pytest.raises(UsageError, match="no axis 'z'"):
        per_axis(["z=a4988"], "--drive", ["x", "y"])
    assert split_invert(["x.step", "enable"], ["x", "y"]) == {
        "x": ["step", "enable"],
        "y": ["enable"],
    }


def test_two_axes_equal_two_single_runs(
    smoothie_sr: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code, both = _json(capsys, str(smoothie_sr), "--drive", "gecko-g202", *SMOOTHIE)
    assert code == 1 and set(both) == {
        "capture",
        "axes",
        "cross_axis",
        "verdict",
        *("verdict_line", "unchecked", "required", "exit_code"),  # issue 26: what it claims
    }
    assert [a["name"] for a in both["axes"]] == ["x", "y"]
    for axis, mapping in (("x", "step=5,dir=6"), ("y", "step=3,dir=4")):
        _, single = _json(capsys, str(smoothie_sr), "--drive", "gecko-g202", "--map", mapping)
        mine = next(a for a in both["axes"] if a["name"] == axis)
        for key in ("rules", "steps", "max_step_rate_hz", "violations_total", "verdict"):
            assert mine[key] == single[key], (axis, key)
    assert both["cross_axis"]["steps"] == {"x": 739, "y": 739}
    assert "common periodic lattice" in both["cross_axis"]["notes"][0]


def test_the_capture_is_read_once(
    smoothie_sr: Path, monkeypatch: pytest.MonkeyPatch, capsys
) -> None:
    from wavecheck.cli import _capture_args

    calls = []
    real = _capture_args.open_source

    def counting(*a, **k):  # type: ignore[no-untyped-def]
        source = real(*a, **k)
        blocks = source.blocks
        calls.append(0)

        def counted():  # type: ignore[no-untyped-def]
            calls[-1] += 1
            return blocks()

        source.blocks = counted
        return source

    monkeypatch.setattr(_capture_args, "open_source", counting)
    main(["check", str(smoothie_sr), "--drive", "gecko-g202", *SMOOTHIE])
    assert calls == [1]  # one source, its blocks read once for both axes


def test_each_axis_its_own_drive(smoothie_sr: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code, d = _json(
        capsys,
        str(smoothie_sr),
        "--drive",
        "x=gecko-g202",
        "--drive",
        "y=leadshine-dm542",
        *SMOOTHIE,
    )
    drives = {a["name"]: a["drive"]["id"] for a in d["axes"]}
    assert drives == {"x": "gecko-g202", "y": "leadshine-dm542"}
    # the G202 needs 4.5 us '1' times (3.7 us here): x fails; the DM542's 2.5 us passes on y
    assert {a["name"]: a["verdict"] for a in d["axes"]} == {"x": "fail", "y": "pass"}
    assert d["verdict"] == "fail" and code == 1


def test_an_axis_without_a_drive_is_a_usage_error(smoothie_sr: Path, capsys) -> None:
    assert main(["check", str(smoothie_sr), "--drive", "x=gecko-g202", *SMOOTHIE]) == 2
    assert "axis y has no drive" in capsys.readouterr().err


def test_junit_html_and_plots_cover_every_axis(smoothie_sr: Path, tmp_path: Path, capsys) -> None:
    out = tmp_path / "r.xml"
    argv = ["check", str(smoothie_sr), "--drive", "leadshine-dm542", *SMOOTHIE]
    main(
        [
            *argv,
            "--format",
            "junit",
            "-o",
            str(out),
            "--html",
            str(tmp_path / "r.html"),
            "--plot",
            str(tmp_path / "r.png"),
        ]
    )
    suites = ET.parse(out).getroot().findall("testsuite")
    assert len(suites) == 2
    html = (tmp_path / "r.html").read_text()
    assert html.count("<section") == 2 and "axis x" in html and "axis y" in html
    stem = smoothie_sr.stem
    assert (tmp_path / f"r-{stem}-x.png").stat().st_size > 0
    assert (tmp_path / f"r-{stem}-y.png").stat().st_size > 0


def test_without_map_the_waveforms_give_the_axes(smoothie_sr: Path, capsys) -> None:
    code, d = _json(capsys, str(smoothie_sr), "--drive", "leadshine-dm542")
    maps = sorted(tuple(sorted(a["map"].items())) for a in d["axes"])
    assert maps == [(("dir", "4"), ("step", "3")), (("dir", "6"), ("step", "5"))]
    assert "channels mapped from their waveforms" in " ".join(d["capture"]["notes"])


def test_text_report_has_a_section_per_axis(smoothie_sr: Path, capsys) -> None:
    main(["check", str(smoothie_sr), "--drive", "gecko-g202", *SMOOTHIE])
    out = capsys.readouterr().out
    assert out.startswith(  # issue 26: the verdict line names what was not checked, and why
        "verdict: FAIL (2 axes; dir_setup, dir_hold not checked: DIR never changes; "
        "enable_setup not checked: drive gecko-g202 states no figure)\n"
    )
    assert "== axis x ==" in out and "== axis y ==" in out
