"""Real PulseView 0.4.2 under Xvfb shows a capture's violations at full zoom-out, and its Summary
row ends with ``check``'s verdict (issues 28 and 36).

``wavecheck check --pulseview`` writes the session; PulseView opens the capture with it
(``tools/pulseview_shot.py`` starts Xvfb and PulseView, moves the pointer over the view once
the window has settled — PulseView draws what the decoder put after its last repaint, the
summary and the regions at the end of the input, when it repaints — types ``f`` (zoom to fit)
and grabs the window). Two captures: the README's G202 trace (stepgen, 500 ms, one 9 us DIR hold
violation) and sigrok-dumps' 97 M-sample grbl capture against a DM542 with tightened limits
(9,831 violations of two rules, 9,517 indeterminate intervals: the mixed row PulseView draws
grey). The pixels are held against sigrok-cli's output of the same decoder and against ``check
--format json``:

- the Violation regions row is the decoder's first row and is red exactly over the regions
  sigrok-cli lists, and each region holds ``check``'s violations (every one in one region, the
  counts adding up to ``check``'s total);
- red appears nowhere else in the decode trace but in one more row (the Violations row) and
  only over ``check``'s violations;
- the Summary row reaches the capture's end, and the summary PulseView's decoder logged is
  sigrok-cli's, whose lines are ``check``'s verdict and counts per rule.

The screenshots are kept under ``$WAVECHECK_ARTEFACTS`` (default
``/tmp/wavecheck-artefacts``)/pulseview, printed by the test.
"""

from __future__ import annotations

import colorsys
import json
import os
import re
import subprocess
import sys
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest

from tests.conftest import shared_capture
from tests.wavecheck.sigrok.conftest import RunDecoder, need
from tests.wavecheck.sigrok.test_sigrok_cli import _REGION, _decoder_options
from tools.pulseview_shot import readme_trace, screenshot

pytestmark = [pytest.mark.sigrok, pytest.mark.slow]

ARTEFACTS = Path(os.environ.get("WAVECHECK_ARTEFACTS", "/tmp/wavecheck-artefacts")) / "pulseview"
GRBL = "sigrok-dumps/stepper_motor/grbl_cnc/grbl_cnc_1.sr"
GRBL_ARGV = ["--drive", "leadshine-dm542", "--map", "step=STEP (Y axis)",
             "--limit", "step_high=10.25us", "--limit", "max_rate=4kHz"]  # fmt: skip
G202_ARGV = ["--drive", "gecko-g202", "--map", "step=step,dir=dir", "--resolution", "0"]
_SUMMARY_LOG = re.compile(r"^wavecheck decoder: summary to sample (\d+): (.*)$", re.M)
_RULE_LINE = re.compile(r"^(\w+): (\w+), (\d+) checked, (\d+) violation\(s\)")
#: Hues (degrees) of the decoder's classes on screen (pd.py's ANNOTATIONS: 120° + 20° per row
#: + 55° per class): a violation 10°, a region 5°; the summary 235°.
RED, SUMMARY = 15, 235


def _hues(image: object) -> tuple[np.ndarray, np.ndarray]:
    """Each pixel's hue (degrees) and whether it is coloured (saturation and value > 0.3)."""
    rgb = np.asarray(image.convert("RGB"), dtype=np.float64) / 255  # type: ignore[attr-defined]
    hi, lo = rgb.max(axis=2), rgb.min(axis=2)
    sat = np.where(hi > 0, (hi - lo) / np.maximum(hi, 1e-9), 0)
    hue = np.vectorize(lambda r, g, b: colorsys.rgb_to_hsv(r, g, b)[0] * 360, otypes=[float])
    flat = rgb.reshape(-1, 3)
    coloured = (sat > 0.3) & (hi > 0.3)
    hues = np.zeros(hi.shape)
    idx = np.flatnonzero(coloured.reshape(-1))
    hues.reshape(-1)[idx] = hue(flat[idx, 0], flat[idx, 1], flat[idx, 2])
    return hues, coloured


def _near(hues: np.ndarray, coloured: np.ndarray, target: float, tol: float) -> np.ndarray:
    d = np.abs((hues - target + 180) % 360 - 180)
    return coloured & (d <= tol)


def _spans(columns: np.ndarray) -> list[tuple[int, int]]:
    """Runs of consecutive column numbers (first, last)."""
    if not len(columns):
        return []
    cuts = np.flatnonzero(np.diff(columns) > 1)
    return list(zip(columns[np.r_[0, cuts + 1]].tolist(), columns[np.r_[cuts, -1]].tolist(),
                    strict=True))  # fmt: skip


def _check(capture: Path, argv: list[str], pvs: Path, code: int = 1) -> dict:  # type: ignore[type-arg]
    cmd = [sys.executable, "-m", "wavecheck", "check", str(capture), *argv, "--format", "json",
           "--max-violations", "100000", "--pulseview", str(pvs)]  # fmt: skip
    run = subprocess.run(cmd, capture_output=True, text=True)
    assert run.returncode == code, run.stderr
    return json.loads(run.stdout)  # type: ignore[no-any-return]


@pytest.mark.parametrize("case", ["g202", "grbl"])
def test_pulseview_shows_violations_and_summary(
    tmp_path: Path, decoder_dir: Path, run_decoder: RunDecoder, case: str
) -> None:
    need("pulseview")
    need("Xvfb")
    capture, argv = (
        (readme_trace(tmp_path), G202_ARGV) if case == "g202" else (shared_capture(GRBL), GRBL_ARGV)
    )
    pvs = tmp_path / f"{case}.pvs"
    doc = _check(capture, argv, pvs)
    rate = int(doc["capture"]["samplerate_hz"])
    fails = [
        (round(Fraction(v["time_s"]) * rate),
         round((Fraction(v["time_s"]) + Fraction(v["measured_ns"] or 0) / 10**9) * rate))
        for v in doc["violations"]
    ]  # fmt: skip
    assert len(fails) == doc["violations_total"] > 0

    # sigrok-cli: the regions hold check's violations; the summary is check's
    channels, options = _decoder_options(argv)
    cli = run_decoder(capture, channels, options, rows="regions:summary")
    regions = [a for a in cli.annotations if _REGION.match(a.text)]
    summary = [a for a in cli.annotations if a not in regions]
    assert sum(int(_REGION.match(r.text).group(1)) for r in regions) == len(fails)  # type: ignore[union-attr]
    for start, end in fails:
        assert sum(r.start <= start and end <= r.end for r in regions) == 1, (start, end)
    assert all(any(r.start <= s <= r.end for s, _ in fails) for r in regions)
    head = summary[-1].text
    assert head.startswith(
        f"{doc['verdict'].upper()} against {options['drive']}: {doc['violations_total']} "
        f"violation(s), {doc['steps']['count']} steps"
    ), head
    rules = {r["id"]: r for r in doc["rules"]}
    lines = [_RULE_LINE.match(a.text) for a in summary[1:-1]]
    assert [m.groups() for m in lines if m] == [  # type: ignore[union-attr]
        (k, r["verdict"], str(r["checked"]), str(r["violations"])) for k, r in rules.items()
    ]
    seen = summary[-1].end
    samples = int(Fraction(doc["capture"]["duration_s"]) * rate)
    assert 0 <= samples - seen <= max(1024, samples // 1024)  # the tick (pd.py)

    # PulseView: its decoder logged the same summary, at the same sample
    image, log = screenshot(capture, pvs, decoder_dir, pointer=(700, 600), keys="f")
    ARTEFACTS.mkdir(parents=True, exist_ok=True)
    shot = ARTEFACTS / f"{case}-full-zoom.png"
    image.save(shot)  # type: ignore[attr-defined]
    print(f"screenshot: {shot}")
    logged = _SUMMARY_LOG.findall(log)  # (a loaded machine may stall the input for 1.5 s)
    assert logged and all(int(n) == seen for n, _ in logged[-len(summary) :]), log[-2000:]
    assert [t for _, t in logged][-len(summary) :] == [a.text for a in summary]

    # pixels: x of a sample, from the Summary row (sample 0 to `seen`)
    hues, coloured = _hues(image)
    blue = _near(hues, coloured, SUMMARY, 10)
    ys, xs = np.nonzero(blue)
    assert len(xs), "no Summary row drawn"
    x0, x1 = int(xs.min()), int(xs.max())
    width = image.width  # type: ignore[attr-defined]
    assert x1 >= width - 25, "the Summary row does not reach the capture's end"

    def x_of(sample: int) -> float:
        return x0 + (x1 - x0) * sample / seen

    # the decode trace: its green name badge, left of the traces (the lowest, below the
    # channels'); its first row is level with it
    badge = _near(hues, coloured, 120, 10)[:, : x0 - 2]
    top, bottom = _spans(np.flatnonzero(badge.any(axis=1)))[-1]
    red = _near(hues, coloured, 0, RED)
    red[:, : x0 - 2] = False  # the channel badges
    red[: top - 3] = False  # the toolbar, the logic traces
    bands = _spans(np.flatnonzero(red.any(axis=1)))
    assert bands, "nothing red in the decode trace"
    band = bands[0]  # the first decoder row: Violation regions
    assert band[0] <= bottom and top <= band[1], ("the regions row is not the first", band)
    assert band[1] < ys.min(), "the regions row is not above the Summary row"
    in_band = red[band[0] : band[1] + 1].any(axis=0)
    got = _spans(np.flatnonzero(in_band))
    want = [(x_of(r.start), x_of(r.end)) for r in regions]
    for a, b in want:  # each region red across its span (its pointed ends aside: 3 px)
        inner = np.arange(int(np.ceil(a)) + 3, int(b) - 2)
        assert in_band[inner].all(), (a, b, got)
    for a, b in got:  # and red nowhere else in that row
        assert any(lo - 3 <= a and b <= hi + 3 for lo, hi in want), ((a, b), want)
    # below it, red only over check's violations, in one row (the Violations row)
    below = red.copy()
    below[: band[1] + 1] = False
    other = np.flatnonzero(below.any(axis=1))
    if len(other):
        assert other.max() - other.min() <= 25, "red in more than one other row"
        marks = [(x_of(s) - 2, x_of(e) + 2) for s, e in fails]
        for a, b in _spans(np.flatnonzero(below.any(axis=0))):
            assert any(lo <= a and b <= hi for lo, hi in marks) or _covered(a, b, marks), (a, b)


def _covered(a: int, b: int, marks: list[tuple[float, float]]) -> bool:
    """Every column a..b lies within one of ``marks``."""
    return all(any(lo <= x <= hi for lo, hi in marks) for x in range(a, b + 1))


def test_no_violation_no_red(tmp_path: Path, decoder_dir: Path) -> None:
    """The same trace with the DIR hold limit at 5 us passes: no region, nothing red in the
    decode trace, and the logged summary is a PASS."""
    need("pulseview")
    need("Xvfb")
    capture, pvs = readme_trace(tmp_path), tmp_path / "pass.pvs"
    doc = _check(capture, [*G202_ARGV, "--limit", "dir_hold=5us"], pvs, code=0)
    assert doc["violations_total"] == 0
    image, log = screenshot(capture, pvs, decoder_dir, pointer=(700, 600), keys="f")
    ARTEFACTS.mkdir(parents=True, exist_ok=True)
    image.save(ARTEFACTS / "g202-pass-full-zoom.png")  # type: ignore[attr-defined]
    assert _SUMMARY_LOG.findall(log)[-1][1].startswith("PASS against gecko-g202: 0 violation(s)")
    hues, coloured = _hues(image)
    xs = np.nonzero(_near(hues, coloured, SUMMARY, 10))[1]
    badge = _near(hues, coloured, 120, 10)[:, : xs.min() - 2]
    top = _spans(np.flatnonzero(badge.any(axis=1)))[-1][0]
    red = _near(hues, coloured, 0, RED)[top - 3 :, xs.min() - 2 :]
    assert not red.any()
