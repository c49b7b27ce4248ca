"""The docs blocks of issue 34 (files read right, outputs never clobbered, reports that say
exactly what happened), run as written and held to what their pages say they give."""

from __future__ import annotations

import json
import os
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from tests.doc_pages import marked
from wavecheck.cli import main

REPO = Path(__file__).resolve().parent.parent


def _lines(name: str) -> list[list[str]]:
    """The commands of a block, continued lines joined, as argument lists (``wavecheck`` off)."""
    text = marked(name).replace("\\\n", " ")
    return [shlex.split(c)[1:] for c in text.splitlines() if c.strip()]


def test_saleae_range_block(capsys: pytest.CaptureFixture[str], monkeypatch) -> None:
    monkeypatch.chdir(REPO)
    ((*args,),) = _lines("saleae-range")
    assert main(args) == 0
    out = capsys.readouterr().out
    assert "sample rate 500 kHz" in out and "resolution  2 us" in out
    assert (
        "note: line 2 (time 9.893632465 s, the export's start) is off the 2 us sample grid" in out
    )
    assert "note: line 83 (time 9.896558777 s, the export's end)" in out


def test_grouped_block(tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch) -> None:
    shutil.copytree(REPO / "captures" / "real", tmp_path / "captures" / "real")
    monkeypatch.chdir(tmp_path)
    text_run, json_run = _lines("grouped")
    assert main(text_run) == 1
    out = capsys.readouterr().out
    assert (
        "  5054 × step_high  measured 9.5 us  limit 10 us  margin -500 ns  "
        "first at 6.047505500 s, last at 44.426116500 s"
    ) in out
    assert "more" not in out.split("violations:")[1].split("\n\n")[0]
    assert main(json_run) == 1
    doc = json.loads((tmp_path / "grbl-violations.json").read_text())
    assert (doc["violations_listed"], doc["violations_total"]) == (1000, 5054)
    assert doc["violations_truncated"] is True


def test_compare_both_fail_block(capsys: pytest.CaptureFixture[str], monkeypatch) -> None:
    monkeypatch.chdir(REPO)
    ((*args,),) = _lines("compare-both-fail")
    assert main(args) == 0
    first = capsys.readouterr().out.splitlines()[0]
    page = (REPO / "docs" / "verdicts.md").read_text(encoding="utf-8")
    said = first.removeprefix("verdict: ")
    assert " ".join(f"`verdict: {said}`".split()) in " ".join(page.split())


def test_stdout_csv_block(tmp_path: Path) -> None:
    """The CSV whole, then the report, in the one file the shell redirected stdout to."""
    shutil.copytree(REPO / "captures" / "golden", tmp_path / "captures" / "golden")
    alone = tmp_path / "alone.csv"
    main(["check", "captures/golden/stepgen0.vcd", "--drive", "gecko-g202", "-q",
          "--steps-csv", str(alone), "-o", str(tmp_path / "r.txt")])  # fmt: skip
    bin_dir = Path(sys.executable).parent  # the environment's wavecheck
    done = subprocess.run(
        ["bash", "-c", marked("stdout-csv")], cwd=tmp_path, check=False,
        env={**os.environ, "PATH": f"{bin_dir}{os.pathsep}{os.environ.get('PATH', '')}"},
    )  # fmt: skip
    assert done.returncode == 0
    text = (tmp_path / "steps-and-report.txt").read_text()
    csv = alone.read_text()
    assert (
        len(csv.splitlines()) > 1000
        and text.startswith(csv)
        and text[len(csv) :].startswith("verdict: PASS")
    )
