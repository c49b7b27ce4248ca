"""The README's ``measure`` / ``--steps-csv`` example, run exactly as written (readme-test: measure)."""

from __future__ import annotations

import csv
import json
import shlex
import shutil
from fractions import Fraction
from pathlib import Path

import pytest

from tests.test_readme import _block
from wavecheck.cli import main

REPO = Path(__file__).resolve().parent.parent


def test_measure_block(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    shutil.copytree(REPO / "captures" / "examples", tmp_path / "captures" / "examples")
    monkeypatch.chdir(tmp_path)
    lines = _block("measure").replace("\\\n", " ").strip().splitlines()
    codes = [main(shlex.split(line)[1:]) for line in lines]
    out = capsys.readouterr().out
    assert codes == [0, 0]
    assert "  dir_hold      1      9 us" in out  # the README's words: axis x's DIR hold
    data = json.loads((tmp_path / "measure.json").read_text())
    x = next(a for a in data["axes"] if a["name"] == "x")
    # ... the figure check fails against the G202 (its own dir_hold shortest, to the tick)
    main(["check", "captures/examples/two-axis.vcd", "--drive", "gecko-g202", "--format", "json"])
    checked = json.loads(capsys.readouterr().out)
    hold = next(r for r in checked["axes"][0]["rules"] if r["id"] == "dir_hold")
    assert x["intervals"]["dir_hold"]["min_ns"] == hold["min_measured_ns"] == 9000
    assert hold["verdict"] == "fail"
    assert (tmp_path / "measure.png").read_bytes()[:4] == b"\x89PNG"
    with open(tmp_path / "steps.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    for a in data["axes"]:
        mine = [r for r in rows if r["axis"] == a["name"]]
        assert len(mine) == a["steps"]["count"]
        assert sum(int(r["direction"]) for r in mine) == a["steps"]["final_position"]
        assert Fraction(mine[-1]["position_units"]) == Fraction(a["steps"]["final_position"], 200)
