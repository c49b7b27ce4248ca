"""``wavecheck measure`` end to end: check's own figures without a drive, every axis of a capture."""

from __future__ import annotations

import json
import tomllib
from pathlib import Path

import pytest

from wavecheck.cli import main
from wavecheck.drives.library import load_drive

REPO = Path(__file__).resolve().parents[3]
GOLDEN = REPO / "captures" / "golden"
SMOOTHIE = ["--map", "x.step=5,x.dir=6", "--map", "y.step=3,y.dir=4"]
#: golden traces that name a drive (their .toml's [wavecheck] section)
CHECKED = sorted(
    p.stem for p in GOLDEN.glob("*.toml") if "wavecheck" in tomllib.loads(p.read_text())
)


def _json(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, dict]:
    code = main([*argv, "--format", "json"])
    return code, json.loads(capsys.readouterr().out)


def test_golden_traces_name_drives() -> None:
    assert len(CHECKED) >= 5


@pytest.mark.parametrize("name", CHECKED)
def test_shortest_intervals_are_checks(name: str, capsys: pytest.CaptureFixture[str]) -> None:
    """The documented fact: measure gives the shortest intervals check reports, to the tick."""
    vcd = str(GOLDEN / f"{name}.vcd")
    drive = tomllib.loads((GOLDEN / f"{name}.toml").read_text())["wavecheck"]["drive"]
    _, checked = _json(capsys, "check", vcd, "--drive", drive)
    code, measured = _json(capsys, "measure", vcd, "--active-edge", load_drive(drive).active_edge)
    assert code == 0
    (axis,) = measured["axes"]
    compared = 0
    for r in checked["rules"]:
        if r["limit_ns"] is None:
            continue
        got = axis["intervals"][r["id"]]
        assert got["count"] == r["checked"]
        assert got["min_ns"] == r["min_measured_ns"]
        if r["checked"]:
            assert got["min_at_s"] == r["min_margin_at_s"]
            compared += 1
    assert compared >= 3
    assert axis["steps"]["count"] == checked["steps"]["count"]
    assert measured["resolution_ns"] == 0 and "every figure is exact" in measured["resolution"]


def test_two_axes_of_the_smoothieware_capture(
    smoothie_sr: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code, m = _json(capsys, "measure", str(smoothie_sr), *SMOOTHIE)
    assert code == 0
    _, c = _json(
        capsys,
        "check",
        str(smoothie_sr),
        *SMOOTHIE,
        "--drive",
        "gecko-g202",
        "--active-edge",
        "rising",
    )
    assert [a["name"] for a in m["axes"]] == ["x", "y"]
    assert [a["map"] for a in m["axes"]] == [{"step": "5", "dir": "6"}, {"step": "3", "dir": "4"}]
    for a, ca in zip(m["axes"], c["axes"], strict=True):
        assert a["steps"]["count"] == ca["steps"]["count"] == 739
        assert a["steps"]["final_position"] == 739 and a["steps"]["reversals"] == 0
        for r in ca["rules"]:
            assert a["intervals"][r["id"]]["min_ns"] == r["min_measured_ns"]
        rate = a["step_rate_hz"]
        assert rate["min"] <= rate["median"] <= rate["max"]
        assert rate["max"] == pytest.approx(1e9 / a["intervals"]["step_period"]["min_ns"])
        assert set(a["intervals"]) == {
            "step_high",
            "step_low",
            "step_period",
            "dir_setup",
            "dir_hold",
            "enable_setup",
        }
    assert m["resolution_ns"] == pytest.approx(83.333333, rel=1e-6)
    assert m["capture"]["tick_s"] == "1/12000000" and m["capture"]["samplerate_hz"] == 12_000_000


def test_text_says_what_bounds_the_figures(
    smoothie_sr: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["measure", str(smoothie_sr), *SMOOTHIE]) == 0
    out = capsys.readouterr().out
    assert "resolution: T = 83.33 ns (one sample period at 12 MHz)" in out
    assert "axis x: step='5', dir='6'" in out and "axis y: step='3', dir='4'" in out
    assert "steps:      x 739 (+739), y 739 (+739)" in out
    assert "  step_high     739    3.667 us  0.000012500 s" in out  # check's shortest for x


def test_axes_found_from_the_waveforms(capsys: pytest.CaptureFixture[str]) -> None:
    code, m = _json(capsys, "measure", str(REPO / "captures" / "examples" / "two-axis.vcd"))
    assert code == 0 and len(m["axes"]) == 2
    assert any("mapped from their waveforms" in n for n in m["notes"])


@pytest.mark.parametrize("name", ["updown-uniform", "stepgen1-quadrature"])
def test_other_step_types(name: str, capsys: pytest.CaptureFixture[str]) -> None:
    code, m = _json(capsys, "measure", str(GOLDEN / f"{name}.vcd"))
    (axis,) = m["axes"]
    kinds = {"updown-uniform": ("dir_delay", 1), "stepgen1-quadrature": ("state_hold", 2)}
    rule, number = kinds[name]
    assert code == 0 and axis["step_type"] == number and axis["intervals"][rule]["count"] > 0
    assert axis["steps"]["sequence_errors"] == 0


def test_plot_and_html(
    tmp_path: Path, smoothie_sr: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    png, page = tmp_path / "m.png", tmp_path / "m.html"
    code = main(
        ["measure", str(smoothie_sr), *SMOOTHIE, "--plot", str(png), "--html", str(page), "-q"]
    )
    capsys.readouterr()
    assert code == 0
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    text = page.read_text()
    assert text.count('class="intervals"') == 2 and "data:image/png;base64," in text
    assert "http" not in text.replace("http-equiv", "")  # self-contained


def test_output_never_overwrites_the_capture(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    vcd = tmp_path / "g.vcd"
    vcd.write_bytes((GOLDEN / "stepgen0.vcd").read_bytes())
    before = vcd.read_bytes()
    assert main(["measure", str(vcd), "--steps-csv", str(vcd)]) == 2
    assert "--steps-csv" in capsys.readouterr().err and vcd.read_bytes() == before


def test_report_file(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "m.json"
    assert main(["measure", str(GOLDEN / "stepgen0.vcd"), "--format", "json", "-o", str(out)]) == 0
    assert "report written to" in capsys.readouterr().out
    assert json.loads(out.read_text())["axes"][0]["steps"]["count"] == 1280
