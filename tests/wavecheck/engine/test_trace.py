"""A report draws the position / step-rate panel from a thinned trace of the steps.

The oracle is every step, as a step sink collects them (:class:`wavecheck.compare.StepCollector`,
:class:`wavecheck.steps.decode.StepEvents`). On the corpus and under hypothesis, at block sizes
from one event up: every position point of the thinned trace lies on the whole position curve,
each bucket's range is the whole curve's range there, every rate point is one of the whole
(tick, gap) points and each bucket's fastest and slowest step are the whole's over the same
bucket, the reversals are counted exactly. A capture 16 times longer keeps no more points. The
PNG of a capture cut into blocks has the one-block PNG's panels, word for word.
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
from wavecheck.capture.blocks import WHOLE, MemorySource
from wavecheck.capture.edges import Capture, Channel
from wavecheck.capture.open import open_capture
from wavecheck.compare import StepCollector
from wavecheck.drives.library import load_drive
from wavecheck.engine.options import CheckOptions
from wavecheck.engine.outcome import Report
from wavecheck.engine.run import check_source
from wavecheck.engine.trace import MAX_BUCKETS, REVERSALS_KEPT, StepTrace
from wavecheck.report.measured_plot import MAX_MARKS
from wavecheck.report.plot import figure
from wavecheck.steps.decode import StepEvents
from wavecheck.steps.mapping import AxisMap
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


def _run(
    cap: Capture, axes: list[AxisMap], drives: dict, block: int, **kw: object
) -> list[tuple[Report, StepEvents]]:
    """Each axis's report (pictures kept) and every step a sink was given, ``cap`` cut into
    blocks of about ``block`` edges."""
    collectors: list[StepCollector] = []

    def sinks(plan: object) -> list[StepCollector]:
        collectors.append(StepCollector())
        return [collectors[-1]]

    types = kw.get("step_types") or {}
    options = CheckOptions(drive=drives, axes=tuple(axes), step_type=types, block_edges=block,  # type: ignore[arg-type]
                           pictures=True)  # fmt: skip
    machine = check_source(MemorySource(cap, block), options, step_sinks=sinks)
    return [(r, c.events()) for r, c in zip(machine.axes, collectors, strict=True)]


def _both(cap: Capture, axes: list[AxisMap], drives: dict, block: int, **kw: object) -> list[tuple[Report, Report, StepEvents]]:  # fmt: skip
    """(one block, ``block``-edge blocks, every step) per axis."""
    whole = _run(cap, axes, drives, WHOLE, **kw)
    cut = _run(cap, axes, drives, block, **kw)
    for (_, a), (_, b) in zip(whole, cut, strict=True):
        assert np.array_equal(a.ticks, b.ticks) and np.array_equal(a.direction, b.direction)
    return [(w, c, steps) for (w, steps), (c, _) in zip(whole, cut, strict=True)]


def _titles(report: Report) -> list[str]:
    return [ax.get_title(loc="left") for ax in figure(report).axes]


def _same_panels(whole: Report, streamed: Report, steps: StepEvents) -> None:
    """The figure of the blocks is the one-block figure, panel for panel; the motion titles say
    "thinned" only when a bucket left steps out (a position of no known direction is not drawn,
    and says so: issue 26)."""
    a, b = _titles(whole), _titles(streamed)
    assert a == b
    motion = [k for k, t in enumerate(a) if t.startswith("steps: ")]
    assert len(motion) == (2 if steps.count > 1 else 0)
    if motion:
        assert streamed.trace is not None
        thinned = streamed.trace.thinned
        unknown = b[motion[0]] == "steps: position unknown (no DIR)"
        assert unknown or ("thinned" in b[motion[0]]) == thinned
        assert b[motion[1]] == "steps: step rate" + (" — thinned" if thinned else "")


@pytest.mark.parametrize("block", [1, 7, 10**9])
@pytest.mark.parametrize(("name", "drive", "typ"), GOLDEN_CASES)
def test_golden_traces(name: str, drive: str, typ: int | None, block: int) -> None:
    cap = open_capture(GOLDEN / name)
    types = {None: typ} if typ is not None else None
    for whole, streamed, steps in _both(cap, [AxisMap(None, {})], {None: load_drive(drive)},
                                        block, step_types=types):  # fmt: skip
        assert streamed.trace is not None and whole.trace is not None
        _on_the_curve(streamed.trace, steps)
        _same_panels(whole, streamed, steps)


@pytest.mark.parametrize("block", [1, 4096])
def test_real_captures(block: int) -> None:
    for name, axes in [
        (SMOOTHIE, [AxisMap(None, {"step": "5", "dir": "6"})]),
        (GRBL, [AxisMap(None, {"step": "STEP (Y axis)"})]),  # no DIR: every direction unknown
    ]:
        cap = open_capture(shared_capture(name))
        (whole, streamed, steps), = _both(cap, axes, {None: load_drive("gecko-g202")}, block)  # fmt: skip
        assert streamed.trace is not None and steps.count > 700
        _on_the_curve(streamed.trace, steps)
        _same_panels(whole, streamed, steps)


def test_the_corpus_reverses() -> None:
    """The golden traces above have a reversal to count and mark."""
    cap = open_capture(GOLDEN / "g202-p16-dirhold2-worst.vcd")
    (whole, streamed, _), = _both(cap, [AxisMap(None, {})], {None: load_drive("gecko-g202")}, 3)  # fmt: skip
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
    """The PNG of a capture checked in many windows is as tall as the one-window PNG: the same
    rows, the panel among them."""
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

    def _run3(c: Capture, drive: object) -> list[tuple[Report, Report, StepEvents]]:
        return _both(c, [AxisMap(None, {})], {None: drive}, 1 << 14)

    for steps in (20_000, 320_000):
        c = cap(steps)
        (_, streamed, steps), = _run3(c, drive)  # fmt: skip
        assert streamed.trace is not None
        _on_the_curve(streamed.trace, steps)
        got.append(streamed.trace.buckets)
    assert got[1] <= MAX_BUCKETS and got[0] <= MAX_BUCKETS
