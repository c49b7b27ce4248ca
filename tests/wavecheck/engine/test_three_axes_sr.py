"""A three-axis .sr checked without --map (issue 33): the roles told from the waveforms, every
axis checked, and the common-timer note said in words. It raised ``OverflowError: cannot
convert Infinity to integer ratio`` in ``lattice/period.exact`` from that note; the note must
name a lattice when one base thread makes the steps and say there is none when not."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from wavecheck.capture.srzip import write_sr_edges
from wavecheck.cli import main

RATE = 1_000_000  # samples a second: 1 us a sample
BASE = 25  # samples: a 25 us base thread


def _axis(t0: int, moves: list[int], lattice: bool) -> tuple[list[int], list[int]]:
    """STEP and DIR edges (sample numbers) of one axis that moves ``moves`` steps each way in
    turn: each move speeds up and slows down, DIR changes in the pause between moves; with
    ``lattice`` every edge lies on the base thread's period."""
    step: list[int] = []
    dirs: list[int] = []
    t = t0
    for n in moves:
        factors = [(3.7, 1.55, 1.2)[min(k, n - 1 - k)] if min(k, n - 1 - k) < 3 else 1.0
                   for k in range(n)]  # fmt: skip
        starts = t + np.cumsum(factors) * 4 * BASE
        if lattice:
            starts = np.round(starts / BASE) * BASE
        for s in starts.astype(int):
            step += [int(s), int(s) + 2 * BASE]
        t = step[-1] + 20 * BASE
        dirs.append(t - 10 * BASE)
    return step, dirs[:-1]


@pytest.mark.parametrize("lattice", [True, False], ids=["one base thread", "no common timer"])
def test_three_axes_sr_is_checked_and_the_timer_note_said(
    tmp_path: Path, lattice: bool, capsys: pytest.CaptureFixture[str]
) -> None:
    names, edges, initial = [], [], []
    for k, (t0, moves) in enumerate([(100, [40, 25, 30]), (1037, [30, 35, 20]), (2011, [50, 45])]):
        step, dirs = _axis(t0 if lattice else t0 + 7 * k, moves, lattice)
        if not lattice:  # off any common lattice: each axis on its own period
            step = [s + (s * (k + 1)) // 97 for s in step]
            dirs = [d + (d * (k + 1)) // 97 for d in dirs]
        names += [f"{2 * k}", f"{2 * k + 1}"]
        edges += [np.asarray(step, np.int64), np.asarray(dirs, np.int64)]
        initial += [0, 0]
    end = max(int(e[-1]) for e in edges) + 1000
    sr = tmp_path / "three.sr"
    write_sr_edges(sr, names, edges, initial, end, samplerate=RATE)
    code = main(["check", str(sr), "--drive", "gecko-g202", "-q", "--format", "json"])
    out = json.loads(capsys.readouterr().out)
    assert code in (0, 1), out
    assert sorted(a["map"]["step"] for a in out["axes"]) == ["0", "2", "4"], out["axes"]
    assert all("dir" in a["map"] for a in out["axes"])
    (note,) = [n for n in out["cross_axis"]["notes"] if "lattice" in n]
    if lattice:
        assert "lie on one common periodic lattice" in note and "P = 25 us" in note, note
    else:
        assert "not on one common periodic lattice" in note, note
