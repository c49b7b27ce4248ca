"""PNG figure of ``wavecheck measure``: motion per axis, then a histogram of every interval kind.

Per axis, position (steps) and instantaneous step rate (1 / the time since the previous step)
against time, with every reversal marked by a dashed line — the picture to hold against the
G-code. Then, per axis, one histogram per interval kind measured (no limit: ``measure`` has no
drive), the shortest and the median marked. matplotlib is imported lazily with the Agg backend;
long captures are thinned for drawing only (every figure in the text and JSON is from all steps;
:func:`draw_motion` is also the motion panel of ``check --plot``).
"""

from __future__ import annotations

import math
import os
from typing import TYPE_CHECKING, Any

import numpy as np

from wavecheck.units import format_ns

if TYPE_CHECKING:  # names for annotations: check --plot loads no measurement module
    import numpy.typing as npt
    from matplotlib.axes import Axes

    from wavecheck.engine.parts import StepCounts, StepTrace
    from wavecheck.measurement import AxisMeasurement, IntervalStats, Measurement
    from wavecheck.steps.interface import StepInterface
    from wavecheck.steptypes import StepType
    from wavecheck.timebase import Timebase

__all__ = ["draw_motion", "position_unknown", "render_measure_png"]


#: Reversals marked at most per panel.
MAX_MARKS = 200
_LINE = "#1f3b73"
_MARK = "#c0392b"


def _style(ax: Axes) -> None:
    for side in ("top", "right"):
        ax.spines[side].set_visible(False)
    ax.tick_params(labelsize=8)


def position_unknown(step_type: StepType, interface: StepInterface, steps: StepCounts) -> str:
    """Why no step's direction is known ("no DIR": a step/dir axis without a DIR channel), or ""
    when some are known (the position is then drawn, steps of unknown direction counting 0)."""
    if step_type.kind == "step-dir" and interface.get("dir") is None:
        return "no DIR"
    return "direction unknown" if steps.count and steps.unknown == steps.count else ""


def draw_motion(
    ax_pos: Axes,
    ax_rate: Axes,
    trace: StepTrace,
    timebase: Timebase,
    title: str,
    unknown: str = "",
) -> None:
    """Position and step rate of an axis's steps against time (s) on two axes, reversals marked,
    from its step trace (:mod:`wavecheck.engine.trace`): every step when it holds them all, else
    the position through each bucket's first and last step over the range it reached and each
    bucket's fastest and slowest step (the titles then say "thinned"). ``unknown``: why no
    step's direction is known (:func:`position_unknown`); the position panel then says so
    instead of drawing a flat line at 0."""
    from matplotlib.collections import PolyCollection

    def sec(ticks: npt.NDArray[np.int64]) -> Any:
        return timebase.ns_array(ticks) / 1e9

    start, low, high = trace.envelope()
    bucket = format_ns(trace.width * timebase.tick_ns)
    if trace.thinned and not unknown:
        x0, width = sec(start), float(trace.width * timebase.tick_ns) / 1e9
        boxes = [
            [(a, lo), (a + width, lo), (a + width, hi), (a, hi)]
            for a, lo, hi in zip(x0.tolist(), low.tolist(), high.tolist(), strict=True)
        ]
        ax_pos.add_collection(PolyCollection(boxes, facecolors=_LINE, alpha=0.2, lw=0))
    t, p = trace.position_points()
    if unknown:
        ax_pos.text(0.5, 0.5, f"{unknown}: position unknown", transform=ax_pos.transAxes,
                    ha="center", va="center", fontsize=11, color=_MARK)  # fmt: skip
        ax_pos.set_yticks([])
        if len(t) > 1:  # the steps' time span, as the rate panel beside it
            ax_pos.set_xlim(float(sec(t)[0]), float(sec(t)[-1]))
    else:
        ax_pos.plot(sec(t), p, drawstyle="steps-post", color=_LINE, lw=1)
    t, gap = trace.rate_points()
    rate = float(timebase.samplerate_hz) / gap
    ms = 2 if len(rate) > 1000 else 5
    ax_rate.plot(sec(t), rate, ".", ms=ms, color=_LINE)
    if len(rate) and rate.max() / max(rate.min(), 1e-12) > 100:
        ax_rate.set_yscale("log")
    for ax in (ax_pos, ax_rate):
        for x in sec(trace.reversal_ticks[:MAX_MARKS]).tolist():
            ax.axvline(x, color=_MARK, lw=0.8, ls="--", alpha=0.7)
        _style(ax)
    extra = f" (first {MAX_MARKS} marked)" if trace.reversals > MAX_MARKS else ""
    thin = " — thinned" if trace.thinned else ""
    ax_pos.set_title(
        f"{title}: position unknown ({unknown})"
        if unknown
        else f"{title}: position, {trace.reversals} reversal(s){extra}{thin}",
        fontsize=9,
        loc="left",
    )
    ax_pos.set_xlabel(
        f"time (s); {trace.count:,} steps, none of known direction"
        if unknown
        else f"time (s); {len(p):,} points of {trace.count:,} steps, range per {bucket} shaded"
        if trace.thinned
        else f"time (s); every one of {trace.count:,} steps",
        fontsize=8.5,
    )
    ax_pos.set_ylabel("position (steps)", fontsize=8.5)
    ax_rate.set_title(f"{title}: step rate{thin}", fontsize=9, loc="left")
    ax_rate.set_xlabel(
        f"time (s); fastest and slowest step per {bucket}" if trace.thinned else "time (s)",
        fontsize=8.5,
    )
    ax_rate.set_ylabel("step rate (Hz)", fontsize=8.5)


def _time_label(v: float, _pos: object = None) -> str:
    """Tick label for a time in ns: ``500 ns``, ``20 us``, ``5 ms``."""
    from wavecheck.units import format_time

    return "0" if v == 0 else format_time(v / 1e9, 3)


def _draw_histogram(ax: Axes, s: IntervalStats, distribution: tuple[Any, Any], title: str) -> None:
    lengths, counts_of = distribution
    ns = lengths * float(s.timebase.tick_ns)
    lo, hi = float(ns.min()), float(ns.max())
    if lo > 0 and hi / lo > 50:
        bins: Any = np.logspace(math.log10(lo * 0.8), math.log10(hi * 1.25), 60)
        ax.set_xscale("log")
    else:
        pad = (hi - lo) * 0.08 or max(abs(lo), 1.0) * 0.1
        bins = np.linspace(lo - pad, hi + pad, 60)
    ax.hist(ns, bins=bins, weights=counts_of, color="#5b7db1")
    counts, _ = np.histogram(ns, bins=bins, weights=counts_of)
    if counts.max(initial=0) > 50:
        ax.set_yscale("log")
        ax.set_ylim(bottom=0.7)
    assert s.min_ns is not None
    ax.axvline(float(s.min_ns), color=_MARK, lw=1.2, ls="--", label="shortest")
    med = s.percentile_ns(50)
    if med is not None:
        ax.axvline(float(med), color="#27ae60", lw=1.0, ls=":", label="median")
    ax.legend(fontsize=7.5, frameon=False, loc="upper right")
    from wavecheck.units import format_ns

    ax.set_title(
        f"{title}{s.rule}: {s.count:,}, min {format_ns(s.min_ns)}, median {format_ns(med)}",
        fontsize=9,
        loc="left",
    )
    from matplotlib.ticker import FuncFormatter, NullLocator

    ax.xaxis.set_major_formatter(FuncFormatter(_time_label))
    ax.xaxis.set_minor_locator(NullLocator())
    ax.set_xlabel("measured", fontsize=8.5)
    ax.set_ylabel("count", fontsize=8.5)
    _style(ax)


def render_measure_png(m: Measurement, dpi: int = 110, fmt: str = "png") -> bytes:
    """The measurement's figure as PNG bytes (``fmt``: ``jpg``, ``svg``, ``pdf`` instead), laid
    out in fixed room (:mod:`wavecheck.report.layout`) on a bare Agg figure."""
    from matplotlib.figure import Figure

    from wavecheck.report.layout import (
        WIDTH_IN,
        Row,
        figure_bytes,
        figure_height,
        fixed_titles,
        place_rows,
        suptitle,
    )

    with fixed_titles():
        hists: list[tuple[AxisMeasurement, IntervalStats]] = [
            (a, s) for a in m.axes for s in a.stats if s.count
        ]
        full, last = divmod(len(hists), 2)
        rows = [Row(1.7, 2)] * (len(m.axes) + full) + [Row(1.7)] * last
        fig = Figure(figsize=(WIDTH_IN, figure_height(rows, 1)), dpi=dpi)
        suptitle(fig, f"wavecheck measure — {os.path.basename(m.capture.path)}", fontsize=12)
        panels = place_rows(fig, rows, 1)
        tb = m.capture.timebase
        for (ax_pos, ax_rate), a in zip(panels, m.axes, strict=False):
            name = "axis" if a.name is None else f"axis {a.name}"
            unknown = position_unknown(a.step_type, a.interface, a.steps)
            draw_motion(ax_pos, ax_rate, a.trace, tb, name, unknown)
        several = len(m.axes) > 1
        hist_axes = [ax for row in panels[len(m.axes) :] for ax in row]
        for ax, (a, s) in zip(hist_axes, hists, strict=True):
            _draw_histogram(ax, s, a.distributions[s.rule], f"{a.name} " if several else "")
    return figure_bytes(fig, fmt)
