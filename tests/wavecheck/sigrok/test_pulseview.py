"""Real PulseView 0.4.2 under Xvfb draws the decoder's violation row (issue 28).

``wavecheck check --pulseview`` writes the session; PulseView opens the capture with it
(``tools/pulseview_shot.py`` starts Xvfb and PulseView and grabs the window). The capture is the
golden G202 trace around its reversal, sampled at 1 MHz: its DIR hold is 9 us against the
G202's 20 us. The same session with ``--limit dir_hold=5us`` has no violation: the first
screenshot must show one annotation row more than the second, and it must be the violation row,
red (the decoder's classes are ordered so that PulseView colours a violation red, pd.py).
"""

from __future__ import annotations

import colorsys
import subprocess
import sys
from pathlib import Path

import pytest

from tests.wavecheck.sigrok.conftest import need
from tools.pulseview_shot import GOLDEN, WINDOW_NS, annotation_rows, sampled_sr, screenshot
from wavecheck.capture.open import open_capture

pytestmark = [pytest.mark.sigrok, pytest.mark.slow]


def _hue(rgb: tuple[int, int, int]) -> float:
    return colorsys.rgb_to_hsv(*(c / 255 for c in rgb))[0] * 360


def _decoder_rows(image: object) -> list[tuple[int, int, tuple[int, int, int]]]:
    """The annotation rows: bands 12–40 px high below the logic traces (1–2 px lines)."""
    bands = annotation_rows(image)
    traces = [b for b in bands if b[1] - b[0] <= 3]
    assert traces, "no logic trace drawn"
    below = traces[-1][1]
    return [b for b in bands if b[0] > below and 12 <= b[1] - b[0] <= 40]


def _shot(tmp: Path, decoder_dir: Path, sr: Path, extra: list[str]) -> object:
    pvs = tmp / f"session{len(extra)}.pvs"
    cmd = [sys.executable, "-m", "wavecheck", "check", str(sr), "--drive", "gecko-g202",
           "--map", "step=step,dir=dir", "--pulseview", str(pvs), *extra]  # fmt: skip
    run = subprocess.run(cmd, capture_output=True, text=True)
    assert run.returncode in (0, 1), run.stderr
    assert f"pulseview -s {pvs}" in run.stderr
    image, log = screenshot(sr, pvs, decoder_dir)
    assert "wavecheck decoder" not in log  # no message that it cannot run
    image.save(tmp / f"{pvs.stem}.png")  # type: ignore[attr-defined]
    return image


def test_pulseview_draws_the_violation_row(tmp_path: Path, decoder_dir: Path) -> None:
    need("pulseview")
    need("Xvfb")
    capture = open_capture(str(GOLDEN))
    tick = capture.timebase.tick_ns
    window = (int(WINDOW_NS[0] / tick), int(WINDOW_NS[1] / tick))
    sr = sampled_sr(capture, tmp_path / "g202-reversal.sr", 1_000_000, window)
    failing = _decoder_rows(_shot(tmp_path, decoder_dir, sr, []))
    passing = _decoder_rows(_shot(tmp_path, decoder_dir, sr, ["--limit", "dir_hold=5us"]))
    red = [r for r in failing if min(_hue(r[2]), 360 - _hue(r[2])) <= 15]
    assert len(failing) == len(passing) + 1, (failing, passing)
    assert len(red) == 1 and not any(min(_hue(r[2]), 360 - _hue(r[2])) <= 15 for r in passing)
    assert failing.index(red[0]) == 2  # widths, DIR timing, then violations (pd.py's rows)
