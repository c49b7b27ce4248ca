"""Issue 33: crosscheck reads every capture wavecheck reads (a Saleae export raised IndexError),
and its downsampling keeps every edge or says how many it lost. Runs sigrok-cli."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest

from tests.conftest import write_vcd
from wavecheck.cli import main as wavecheck_main
from wavecheck.crosscheck.sigrok import merged_edges

pytestmark = pytest.mark.skipif(shutil.which("sigrok-cli") is None, reason="needs sigrok-cli")


def _saleae_csv(path: Path) -> Path:
    rows = ["Time [s],STEP,DIR", "0.000000000,0,0"]
    for i in range(40):
        t = 1e-4 * (i + 1)
        d = int(i > 20)
        rows += [f"{t:.9f},1,{d}", f"{t + 2e-5:.9f},0,{d}"]
    path.write_text("\n".join(rows) + "\n")
    return path


def test_a_saleae_csv_export_is_crosschecked(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    csv = _saleae_csv(tmp_path / "logic2.csv")
    assert wavecheck_main(["crosscheck", str(csv), "--map", "step=STEP,dir=DIR"]) == 0
    out = capsys.readouterr().out
    assert "AGREE" in out and "wavecheck 40, sigrok counter 40" in out


def test_an_edge_on_the_first_sample_is_kept(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # an HDL dump whose STEP rises at time 0 + a tick: downsample 5 put it on sample 0, which
    # sigrok takes for the initial level (the first step was lost, and "no pulse lost" claimed)
    step = [1, 6, 20, 25, 40, 45]
    vcd = write_vcd(tmp_path / "hdl.vcd", {"step": (0, step), "dir": (0, [30])})
    assert wavecheck_main(["crosscheck", str(vcd), "--map", "step=step,dir=dir"]) == 0
    out = capsys.readouterr().out
    assert "wavecheck 3, sigrok counter 3" in out and "one sample later" in out


def test_a_downsample_that_merges_edges_says_how_many(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    step = [10, 12, 40, 42, 70, 72]  # 2-tick pulses: the first two merge at downsample 8
    vcd = write_vcd(tmp_path / "d.vcd", {"step": (0, step), "dir": (0, [30])})
    rc = wavecheck_main(["crosscheck", str(vcd), "--map", "step=step,dir=dir", "--downsample", "8"])
    assert rc == 1
    assert "merges 4 STEP/DIR edge(s)" in capsys.readouterr().out


def test_merged_edges() -> None:
    assert merged_edges(np.array([0, 1, 8, 20, 21, 22]), 4) == 2 + 2  # 0,1 cancel; 20,21,22: 2
    assert merged_edges(np.array([0, 4, 8]), 4) == 0
