"""A streamed report draws the position / step-rate panel from a thinned trace of the steps.

The oracle is the whole-capture report's every step (:class:`wavecheck.engine.decode.StepEvents`). On the
corpus and under hypothesis, at block sizes from one event up: every position point of the
thinned trace lies on the whole path's position curve, each bucket's range is the whole path's
range there, every rate point is one of the whole path's (tick, gap) points and each bucket's
fastest and slowest step are the whole path's over the same bucket, the reversals are counted
exactly. A capture 16 times longer keeps no more points. The streamed PNG has the whole path's
panels, the motion titles saying "thinned".
"""

from __future__ import annotations

import subprocess
import sys
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tests.conftest import shared_capture
from tests.wavecheck.engine.corpus import GOLDEN, GOLDEN_CASES, ROOT
from wavecheck.axes import AxisMap
from wavecheck.capture.blocks import MemorySource
from wavecheck.capture.edges import Capture, Channel
from wavecheck.capture.open import open_capture
from wavecheck.drives.library import load_drive
from wavecheck.engine.axis import check_stream
from wavecheck.engine.decode import StepEvents
from wavecheck.engine.plan import check_machine
from wavecheck.engine.trace import MAX_BUCKETS, REVERSALS_KEPT, StepTrace
from wavecheck.report.measure_plot import MAX_MARKS
from wavecheck.report.model import Report
from wavecheck.report.plot import figure
from wavecheck.timebase import Timebase

SMOOTHIE = "sigrok-dumps/stepper_motor/smoothieware/smoothieware_snippet.sr"
GRBL = "sigrok-dumps/stepper_motor/grbl_cnc/grbl_cnc_1.sr"


def _reversals(s: StepEvents) -> np.ndarray:
    """Ticks of the whole path's reversals (as draw_motion marks them)."""
    known = s.direction != 0
    d, t = s.direction[known], s.ticks[known]
    return t[1:][d[1:] != d[:-1]]


def _on_the_curve(trace: StepTrace, s: StepEvents) -> None:
    """``trace`` is a thinning of ``s`` (module docstring)."""
    assert trace.count == s.count
    if not s.count:
        assert trace.buckets == 0
        return
    assert trace.origin == int(s.ticks[0])
    assert trace.buckets <= trace.size
    # position: each kept point is a step, with the whole path's position after it
    t, p = trace.position_points()
    assert len(t) <= 2 * trace.size and np.all(np.diff(t) >= 0)
    curve = set(zip(s.ticks.tolist(), s.position.tolist(), strict=True))
    assert set(zip(t.tolist(), p.tolist(), strict=True)) <= curve
    assert int(t[-1]) == int(s.ticks[-1]) and int(p[-1]) == int(s.position[-1])
    # each bucket: the range of positions the whole path reaches in it
    bucket = (s.ticks - trace.origin) // trace.width
    start, low, high = trace.envelope()
    used = np.unique(bucket)
    assert np.array_equal(start, trace.origin + used * trace.width)
    first = np.unique(bucket, return_index=True)[1]
    last = len(bucket) - 1 - np.unique(bucket[::-1], return_index=True)[1]
    ends = np.sort(np.unique(np.concatenate([first, last])))  # each bucket's first and last step
    assert np.array_equal(t, s.ticks[ends]) and np.array_equal(p, s.position[ends])
    for k, b in enumerate(used.tolist()):
        pos = s.position[bucket == b]
        assert (int(low[k]), int(high[k])) == (int(pos.min()), int(pos.max()))
    # step rate: every point is the whole path's; the fastest and slowest of each bucket are
    gaps = np.diff(s.ticks)
    ok = gaps > 0
    rt, rg = s.ticks[1:][ok], gaps[ok]
    whole = set(zip(rt.tolist(), rg.tolist(), strict=True))
    t, g = trace.rate_points()
    assert len(t) <= 2 * trace.size and set(zip(t.tolist(), g.tolist(), strict=True)) <= whole
    rb = (rt - trace.origin) // trace.width
    mine = (t - trace.origin) // trace.width
    points = set(zip(t.tolist(), g.tolist(), strict=True))
    for b in np.unique(rb).tolist():
        for pick in (np.argmin, np.argmax):  # the earliest fastest and slowest step are drawn
            k = int(pick(rg[rb == b]))
            assert (int(rt[rb == b][k]), int(rg[rb == b][k])) in points
        here = g[mine == b]
        assert (int(here.min()), int(here.max())) == (
            int(rg[rb == b].min()),
            int(rg[rb == b].max()),
        )
    assert set(np.unique(mine).tolist()) == set(np.unique(rb).tolist())
    if len(rg):  # the highest rate drawn is the whole path's
        assert int(g.min()) == int(rg.min())
    rev = _reversals(s)
    assert trace.reversals == len(rev)
    assert np.array_equal(trace.reversal_ticks, rev[:REVERSALS_KEPT])


def _both(cap: Capture, axes: list[AxisMap], drives: dict, block: int, **kw: object) -> list[tuple[Report, Report]]:  # fmt: skip
    whole = check_machine(cap, axes, drives, **kw)  # type: ignore[arg-type]
    streamed = check_stream(MemorySource(cap, block), axes, drives, block_edges=block, **kw)  # type: ignore[arg-type]
    return list(zip(whole.axes, streamed.axes, strict=True))


def _titles(report: Report) -> list[str]:
    return [ax.get_title(loc="left") for ax in figure(report).axes]


def _same_panels(whole: Report, streamed: Report) -> None:
    """The streamed figure has the whole figure's panels; the motion titles say "thinned"."""
    a, b = _titles(whole), _titles(streamed)
    assert len(a) == len(b)
    motion = [k for k, t in enumerate(a) if t.startswith("steps: ")]
    assert len(motion) == (2 if whole.events().count > 1 else 0)
    for k, (x, y) in enumerate(zip(a, b, strict=True)):
        if k not in motion:
            assert x == y
        else:
            assert "thinned" in y and "thinned" not in x
    if motion:
        assert b[motion[0]] == a[motion[0]] + " — thinned"  # position, reversals
        assert a[motion[1]] == "steps: instantaneous step rate"
        assert b[motion[1]] == "steps: step rate — thinned"


@pytest.mark.parametrize("block", [1, 7, 10**9])
@pytest.mark.parametrize(("name", "drive", "typ"), GOLDEN_CASES)
def test_golden_traces(name: str, drive: str, typ: int | None, block: int) -> None:
    cap = open_capture(GOLDEN / name)
    types = {None: typ} if typ is not None else None
    for whole, streamed in _both(cap, [AxisMap(None, {})], {None: load_drive(drive)}, block,
                                 step_types=types):  # fmt: skip
        assert streamed.trace is not None and whole.trace is None
        _on_the_curve(streamed.trace, whole.events())
        _same_panels(whole, streamed)


@pytest.mark.parametrize("block", [1, 4096])
def test_real_captures(block: int) -> None:
    for name, axes in [
        (SMOOTHIE, [AxisMap(None, {"step": "5", "dir": "6"})]),
        (GRBL, [AxisMap(None, {"step": "STEP (Y axis)"})]),  # no DIR: every direction unknown
    ]:
        cap = open_capture(shared_capture(name))
        (whole, streamed), = _both(cap, axes, {None: load_drive("gecko-g202")}, block)  # fmt: skip
        assert streamed.trace is not None and whole.events().count > 700
        _on_the_curve(streamed.trace, whole.events())
        _same_panels(whole, streamed)


def test_the_corpus_reverses() -> None:
    """The golden traces above have a reversal to count and mark."""
    cap = open_capture(GOLDEN / "g202-p16-dirhold2-worst.vcd")
    (whole, streamed), = _both(cap, [AxisMap(None, {})], {None: load_drive("gecko-g202")}, 3)  # fmt: skip
    assert streamed.trace is not None and streamed.trace.reversals > 0
    assert len(streamed.trace.reversal_ticks) == streamed.trace.reversals


# -- thinning: bounded, exact ---------------------------------------------------------------------
def _motion(steps: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """``steps`` steps at random gaps (1–40 ticks, some bursts of 1), random reversals."""
    rng = np.random.default_rng(seed)
    ticks = np.cumsum(rng.integers(1, 40, steps)).astype(np.int64)
    runs = rng.integers(1, 300, steps // 20 + 2)
    d = np.repeat(np.where(np.arange(len(runs)) % 2, -1, 1), runs)[:steps].astype(np.int8)
    d[rng.random(steps) < 0.01] = 0  # unknown direction
    return ticks, d


def _whole(ticks: np.ndarray, d: np.ndarray) -> StepEvents:
    return StepEvents(ticks, d, np.cumsum(d, dtype=np.int64))


@pytest.mark.parametrize("size", [4, 64, MAX_BUCKETS])
def test_thinning_is_exact_and_bounded(size: int) -> None:
    ticks, d = _motion(200_000, 1)
    trace = StepTrace(size)
    for a, b in zip(range(0, len(ticks), 9_973), range(9_973, len(ticks) + 9_973, 9_973), strict=True):  # fmt: skip
        trace.add(ticks[a:b], d[a:b])
    assert trace.buckets > size // 2  # the width is as small as the buckets allow
    _on_the_curve(trace, _whole(ticks, d))
    assert trace.reversals > REVERSALS_KEPT


def test_memory_does_not_grow_with_the_capture() -> None:
    sizes = []
    for steps in (50_000, 800_000):
        ticks, d = _motion(steps, 2)
        trace = StepTrace()
        for a in range(0, steps, 65_536):
            trace.add(ticks[a : a + 65_536], d[a : a + 65_536])
        t, _ = trace.position_points()
        r, _ = trace.rate_points()
        assert len(t) <= 2 * MAX_BUCKETS and len(r) <= 2 * MAX_BUCKETS
        held = sum(v.nbytes for v in vars(trace._b).values()) + trace.reversal_ticks.nbytes
        sizes.append(held)
    assert sizes[0] == sizes[1]  # 16 times the steps, the same memory


@settings(max_examples=150, deadline=None)
@given(
    gaps=st.lists(st.integers(0, 1 << 20), min_size=0, max_size=300),
    dirs=st.lists(st.sampled_from([-1, 0, 1]), min_size=300, max_size=300),
    cuts=st.lists(st.integers(0, 300), max_size=12),
    size=st.sampled_from([1, 2, 8, 32]),
)
def test_thinning_under_hypothesis(gaps: list[int], dirs: list[int], cuts: list[int], size: int) -> None:  # fmt: skip
    ticks = np.cumsum(np.array([5, *gaps], np.int64))[1:] if gaps else np.zeros(0, np.int64)
    d = np.array(dirs[: len(ticks)], np.int8)
    trace = StepTrace(size)
    bounds = sorted({0, len(ticks), *(c for c in cuts if c <= len(ticks))})
    for a, b in zip(bounds, bounds[1:], strict=False):
        trace.add(ticks[a:b], d[a:b])
    _on_the_curve(trace, _whole(ticks, d))


def test_reversal_marks_match_the_plot() -> None:
    assert REVERSALS_KEPT >= MAX_MARKS


# -- the command line -----------------------------------------------------------------------------
def _plot(tmp_path: Path, *args: str) -> bytes:
    png = tmp_path / "p.png"
    p = subprocess.run(
        [sys.executable, "-m", "wavecheck", "check", *args, f"--plot={png}", "-q"],
        capture_output=True, text=True, cwd=ROOT,
    )  # fmt: skip
    assert p.returncode == 1 and not p.stderr, p.stderr
    return png.read_bytes()


def test_cli_streamed_png_has_the_panel(tmp_path: Path) -> None:
    """The streamed PNG is as tall as the whole one: the same rows, the panel among them."""
    from PIL import Image

    args = [str(shared_capture(SMOOTHIE)), "--drive", "gecko-g202", "--map", "step=5,dir=6"]
    whole = tmp_path / "w"
    streamed = tmp_path / "s"
    whole.mkdir(), streamed.mkdir()
    a = _plot(whole, *args, "--no-stream")
    b = _plot(streamed, *args, "--block-edges", "1000")
    import io

    assert Image.open(io.BytesIO(a)).size == Image.open(io.BytesIO(b)).size


def test_a_long_capture_keeps_few_points() -> None:
    """A streamed check of 16 times the steps keeps a trace of no more buckets."""
    tb = Timebase(Fraction(1, 10**7))

    def cap(steps: int) -> Capture:
        rise = np.arange(steps, dtype=np.int64) * 10 + 5
        step = np.stack([rise, rise + 1], axis=1).ravel()
        dirs = np.arange(1, steps // 500, dtype=np.int64) * 5000 + 2
        chans = [Channel("step", 0, 0, step), Channel("dir", 1, 0, dirs)]
        return Capture("p", "vcd", tb, 0, None, 0, steps * 10 + 20, chans)

    drive = load_drive("gecko-g202")
    got = []
    for steps in (20_000, 320_000):
        c = cap(steps)
        (whole, streamed), = _both(c, [AxisMap(None, {})], {None: drive}, 1 << 14)  # fmt: skip
        assert streamed.trace is not None
        _on_the_curve(streamed.trace, whole.events())
        got.append(streamed.trace.buckets)
    assert got[1] <= MAX_BUCKETS and got[0] <= MAX_BUCKETS
