"""PNG figure of ``wavecheck measure``: motion per axis, then a histogram of every interval kind.

Per axis, position (steps) and instantaneous step rate (1 / the time since the previous step)
against time, with every reversal marked by a dashed line — the picture to hold against the
G-code. Then, per axis, one histogram per interval kind measured (no limit: ``measure`` has no
drive), the shortest and the median marked. matplotlib is imported lazily with the Agg backend;
long captures are thinned for drawing only (every figure in the text and JSON is from all steps).
"""

from __future__ import annotations

import io
import math
import os
from typing import TYPE_CHECKING, Any

import numpy as np

from wavecheck.engine.decode import StepEvents
from wavecheck.measure import AxisMeasurement, IntervalStats, Measurement
from wavecheck.timebase import Timebase

if TYPE_CHECKING:
    from matplotlib.axes import Axes

__all__ = ["draw_motion", "render_measure_png"]

#: Points drawn per curve at most (every k-th step beyond it).
MAX_POINTS = 20_000
#: Reversals marked at most per panel.
MAX_MARKS = 200
_LINE = "#1f3b73"
_MARK = "#c0392b"


def _style(ax: Axes) -> None:
    for side in ("top", "right"):
        ax.spines[side].set_visible(False)
    ax.tick_params(labelsize=8)


def draw_motion(
    ax_pos: Axes, ax_rate: Axes, steps: StepEvents, timebase: Timebase, title: str
) -> None:
    """Position and step rate of ``steps`` against time (s) on two axes, reversals marked."""
    t = timebase.ns_array(steps.ticks) / 1e9
    stride = max(1, math.ceil(len(t) / MAX_POINTS))
    ax_pos.plot(t[::stride], steps.position[::stride], drawstyle="steps-post", color=_LINE, lw=1)
    gaps = np.diff(steps.ticks)
    ok = gaps > 0
    rate = float(timebase.samplerate_hz) / gaps[ok]
    ax_rate.plot(
        t[1:][ok][::stride], rate[::stride], ".", ms=2 if len(rate) > 1000 else 5, color=_LINE
    )
    if len(rate) and rate.max() / max(rate.min(), 1e-12) > 100:
        ax_rate.set_yscale("log")
    known = steps.direction != 0
    d, tk = steps.direction[known], t[known]
    rev = tk[1:][d[1:] != d[:-1]]
    for ax in (ax_pos, ax_rate):
        for x in rev[:MAX_MARKS]:
            ax.axvline(x, color=_MARK, lw=0.8, ls="--", alpha=0.7)
        ax.set_xlabel("time (s)", fontsize=8.5)
        _style(ax)
    extra = f" (first {MAX_MARKS} marked)" if len(rev) > MAX_MARKS else ""
    ax_pos.set_title(f"{title}: position, {len(rev)} reversal(s){extra}", fontsize=9, loc="left")
    ax_pos.set_ylabel("position (steps)", fontsize=8.5)
    ax_rate.set_title(f"{title}: instantaneous step rate", fontsize=9, loc="left")
    ax_rate.set_ylabel("step rate (Hz)", fontsize=8.5)


def _time_label(v: float, _pos: object = None) -> str:
    """Tick label for a time in ns: ``500 ns``, ``20 us``, ``5 ms``."""
    from wavecheck.units import format_time

    return "0" if v == 0 else format_time(v / 1e9, 3)


def _draw_histogram(ax: Axes, s: IntervalStats, values: Any, title: str) -> None:
    ns = values * float(s.timebase.tick_ns)
    lo, hi = float(ns.min()), float(ns.max())
    if lo > 0 and hi / lo > 50:
        bins: Any = np.logspace(math.log10(lo * 0.8), math.log10(hi * 1.25), 60)
        ax.set_xscale("log")
    else:
        pad = (hi - lo) * 0.08 or max(abs(lo), 1.0) * 0.1
        bins = np.linspace(lo - pad, hi + pad, 60)
    ax.hist(ns, bins=bins, color="#5b7db1")
    counts, _ = np.histogram(ns, bins=bins)
    if counts.max(initial=0) > 50:
        ax.set_yscale("log")
        ax.set_ylim(bottom=0.7)
    assert s.min_ns is not None
    ax.axvline(float(s.min_ns), color=_MARK, lw=1.2, ls="--")
    med = s.percentile_ns(50)
    if med is not None:
        ax.axvline(float(med), color="#27ae60", lw=1.0, ls=":")
    from wavecheck.units import format_ns

    ax.set_title(
        f"{title}{s.rule}: {s.count:,}, min {format_ns(s.min_ns)}, median {format_ns(med)}",
        fontsize=9,
        loc="left",
    )
    from matplotlib.ticker import FuncFormatter, NullFormatter

    ax.xaxis.set_major_formatter(FuncFormatter(_time_label))
    ax.xaxis.set_minor_formatter(NullFormatter())
    ax.set_xlabel("measured", fontsize=8.5)
    ax.set_ylabel("count", fontsize=8.5)
    _style(ax)


def render_measure_png(m: Measurement, dpi: int = 110) -> bytes:
    """The measurement's figure as PNG bytes."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    from matplotlib.figure import Figure

    hists: list[tuple[AxisMeasurement, IntervalStats]] = [
        (a, s) for a in m.axes for s in a.stats if s.count
    ]
    hist_rows = math.ceil(len(hists) / 2)
    heights = [2.6] * (len(m.axes) + hist_rows)
    fig = Figure(figsize=(11, sum(heights) + 0.8), dpi=dpi, layout="constrained")
    fig.suptitle(f"wavecheck measure — {os.path.basename(m.capture.path)}", fontsize=12)
    grid = fig.add_gridspec(len(heights), 2, height_ratios=heights)
    tb = m.capture.timebase
    for k, a in enumerate(m.axes):
        name = "axis" if a.name is None else f"axis {a.name}"
        draw_motion(fig.add_subplot(grid[k, 0]), fig.add_subplot(grid[k, 1]), a.steps, tb, name)
    several = len(m.axes) > 1
    for k, (a, s) in enumerate(hists):
        row, col = divmod(k, 2)
        span = slice(None) if k == len(hists) - 1 and col == 0 else col
        ax = fig.add_subplot(grid[len(m.axes) + row, span])
        _draw_histogram(ax, s, a.intervals[s.rule].measured, f"{a.name} " if several else "")
    buf = io.BytesIO()
    fig.savefig(buf, format="png")
    return buf.getvalue()
