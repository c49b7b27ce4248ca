"""PNG plots of a report: timing diagrams at the worst places and histograms of every rule.

The figure has three parts:

- up to :data:`MAX_PLACES` timing diagrams, one per place: the mapped signals (STEP/DIR, UP/DOWN
  or the phases, at the drive's input, i.e. after any inversion) around a violation — the worst
  violation of each failing rule first, then the next worst — or, when nothing fails, around the
  smallest margin of each rule. The measured interval is drawn as an arrow and labelled, the
  rule's limit as a shaded span from the same start, so "too short" is visible at a glance;
- position and step rate against time, reversals marked;
- one histogram per rule of every measured interval (each rule's fixed bins, four per octave),
  with the limit as a vertical line, so the whole capture's distance from the datasheet shows.

A report keeps no capture: its timing diagrams are drawn from the small windows of the signals
kept around the worst places (:mod:`wavecheck.engine.windows`), its motion panel from the step
trace (:mod:`wavecheck.engine.trace`): per time bucket, the first and last step's position and the
range reached, the fastest and slowest step, every reversal counted (the first ones marked);
when a bucket holds more than two steps the titles say "thinned". The check must have kept
pictures (:attr:`wavecheck.engine.options.CheckOptions.pictures`).

matplotlib is imported lazily with the Agg backend (no display needed). Times are drawn in µs
(or ns/ms when that reads better) relative to the start of the drawn interval; each panel's
title gives the absolute time in the capture.
"""

from __future__ import annotations

import math
import os
import textwrap
from dataclasses import dataclass
from fractions import Fraction
from typing import TYPE_CHECKING, Any

import numpy as np

from wavecheck.engine import Report, RuleResult
from wavecheck.output import atomic_write, figure_format
from wavecheck.report.claims import not_checked
from wavecheck.units import SI_TIME, format_time

if TYPE_CHECKING:
    import numpy.typing as npt
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure


__all__ = [
    "MAX_PLACES",
    "Place",
    "binned",
    "choose_places",
    "figure",
    "hist_title",
    "place_title",
    "place_traces",
    "render_png",
    "write_plot",
]

#: Timing diagrams drawn at most.
MAX_PLACES = 4
_FAIL_COLOR = "#c0392b"
_PASS_COLOR = "#27ae60"
_INDET_COLOR = "#e67e22"
_TRACE_COLOR = "#1f3b73"
_ROLE_ORDER = (
    "step",
    "up",
    "down",
    "phase-A",
    "phase-B",
    "phase-C",
    "phase-D",
    "phase-E",
    "dir",
    "enable",
)


@dataclass(frozen=True)
class Place:
    """One interval to draw.

    Attributes:
        rule: the rule id.
        start_tick: start of the interval (its reference event).
        end_tick: its end.
        measured_ns: its length, exact ns (None for ``state_sequence``).
        limit_ns: the rule's limit, exact ns (None for ``state_sequence``).
        failed: True for a violation, False for a smallest-margin place of a passing rule.
        detail: extra text (``state_sequence``).
    """

    rule: str
    start_tick: int
    end_tick: int
    measured_ns: Fraction | None
    limit_ns: Fraction | None
    failed: bool
    detail: str = ""

    @property
    def margin_ns(self) -> Fraction | None:
        """measured − limit, exact ns."""
        if self.measured_ns is None or self.limit_ns is None:
            return None
        return self.measured_ns - self.limit_ns


def _span(p: Place) -> int:
    return max(p.end_tick - p.start_tick, 1)


def _overlaps(a: Place, b: Place) -> bool:
    pad = 2 * max(_span(a), _span(b))
    return a.start_tick - pad <= b.end_tick and b.start_tick - pad <= a.end_tick


def choose_places(report: Report, n: int = MAX_PLACES) -> list[Place]:
    """The places to draw: worst violations (one per failing rule first), else smallest margins.

    Places that would show the same stretch of the capture are drawn once.
    """
    places: list[Place] = []

    def add(p: Place) -> None:
        if len(places) < n and not any(_overlaps(p, q) for q in places):
            places.append(p)

    violations = report.violations(max(4 * n, 16))
    if violations:
        firsts: dict[str, Place] = {}
        rest: list[Place] = []
        for v in violations:
            p = Place(v.rule, v.start_tick, v.end_tick, v.measured_ns, v.limit_ns, True, v.detail)
            if v.rule in firsts:
                rest.append(p)
            else:
                firsts[v.rule] = p
        for p in [*firsts.values(), *rest]:
            add(p)
        return places
    margins: list[tuple[Fraction, Place]] = []
    for r in report.rules:
        start, measured = r.min_margin_at_tick, r.min_measured_ns
        if start is None or measured is None or r.limit_ns is None:
            continue
        end = start + int(measured / r.timebase.tick_ns)
        rel = (measured - r.limit_ns) / r.limit_ns if r.limit_ns else measured
        margins.append((rel, Place(r.rule, start, end, measured, r.limit_ns, False)))
    for _, p in sorted(margins, key=lambda m: m[0]):
        add(p)
    return places


# -- units ----------------------------------------------------------------------------------------
_UNITS: tuple[tuple[str, float], ...] = tuple(  # ns up to s, µ for the axis labels
    (name.replace("us", "µs"), 10.0 ** (exp + 9)) for name, exp in reversed(SI_TIME[:4])
)


def _unit_for(ns: float) -> tuple[str, float]:
    """A display unit for lengths around ``ns`` nanoseconds: (name, ns per unit)."""
    chosen = _UNITS[0]
    for name, scale in _UNITS:
        if abs(ns) >= scale:
            chosen = (name, scale)
    return chosen


def _fmt_ns(v: Fraction | float | None) -> str:
    if v is None:
        return "-"
    return format_time(Fraction(v) / 10**9)


def _signed_ns(v: Fraction | None) -> str:
    if v is None:
        return "-"
    return ("+" if v > 0 else "") + _fmt_ns(v)


# -- drawing --------------------------------------------------------------------------------------
def _roles(report: Report) -> list[str]:
    roles = list(report.interface.signals)
    return sorted(roles, key=lambda r: _ROLE_ORDER.index(r) if r in _ROLE_ORDER else 99)


def _extent(place: Place, tick_ns: float) -> tuple[float, float, float]:
    """The ticks ``(lo, hi)`` a timing diagram of ``place`` shows (1.6 times the interval's width,
    or the limit's, each side: within :func:`wavecheck.engine.windows.place_range`), and the
    limit in ticks."""
    span_ticks = max(place.end_tick - place.start_tick, 1)
    limit_ticks = float(place.limit_ns) / tick_ns if place.limit_ns else 0.0
    pad = 1.6 * max(span_ticks, limit_ticks, 1.0)
    return (
        place.start_tick - pad,
        max(place.end_tick, place.start_tick + limit_ticks) + pad,
        limit_ticks,
    )


def place_traces(
    report: Report, place: Place
) -> dict[str, tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]]:
    """Role → (times, levels) of the steps a timing diagram of ``place`` draws: times in ticks
    from the diagram's left end to its right end, ``levels[k]`` the level from ``times[k]`` on
    (the last repeated), at the drive's input."""
    lo, hi, _ = _extent(place, float(report.capture.timebase.tick_ns))
    out = {}
    for role in _roles(report):
        sig = report.traces[role]
        a = int(np.searchsorted(sig.edges, int(math.floor(lo)), side="right"))
        b = int(np.searchsorted(sig.edges, int(math.ceil(hi)), side="right"))
        ts = sig.edges[a:b].astype(np.float64)
        level0 = sig.initial ^ (a & 1)
        levels = np.array([level0] + [level0 ^ ((k + 1) & 1) for k in range(len(ts))], dtype=float)
        out[role] = (np.concatenate([[lo], ts, [hi]]), np.append(levels, levels[-1]))
    return out


def _draw_place(ax: Axes, report: Report, place: Place, index: int) -> None:
    tb = report.capture.timebase
    tick_ns = float(tb.tick_ns)
    lo, hi, limit_ticks = _extent(place, tick_ns)
    unit, scale = _unit_for((hi - lo) * tick_ns / 4)
    t0 = place.start_tick

    def x(ticks: npt.NDArray[np.float64] | float) -> Any:
        return (np.asarray(ticks, dtype=np.float64) - t0) * tick_ns / scale

    roles = _roles(report)
    n = len(roles)
    ypos = {role: (n - 1 - k) * 1.6 for k, role in enumerate(roles)}
    for role, (xs, levels) in place_traces(report, place).items():
        y = ypos[role]
        ax.step(x(xs), levels + y, where="post", color=_TRACE_COLOR, lw=1.6)
        label = role.upper() if not role.startswith("phase") else role
        inv = " (inv)" if report.traces[role].inverted else ""
        ax.text(x(lo), y + 0.5, f"{label}{inv} ", ha="right", va="center", fontsize=9, color="#333")
    color = _FAIL_COLOR if place.failed else _PASS_COLOR
    lane = (n - 1) * 1.6 + 1.55  # the annotation lane above every trace
    limit_end = place.start_tick + limit_ticks
    # the limit: a shaded span of the required minimum from the interval's start
    if place.limit_ns is not None and place.limit_ns > 0:
        ax.axvspan(x(place.start_tick), x(limit_end), color=color, alpha=0.10, lw=0)
        ax.axvline(x(limit_end), color=color, lw=1, ls="--", alpha=0.8)
        ax.text(
            x(limit_end),
            lane + 0.75,
            f" limit ≥ {_fmt_ns(place.limit_ns)} ",
            ha="left" if limit_end >= place.end_tick else "right",
            va="center",
            fontsize=8.5,
            color=color,
        )
    # the measured interval
    ax.annotate(
        "",
        xy=(x(place.end_tick), lane),
        xytext=(x(place.start_tick), lane),
        arrowprops={"arrowstyle": "<|-|>", "color": color, "lw": 1.4, "shrinkA": 0, "shrinkB": 0},
    )
    ax.axvline(x(place.start_tick), color=color, lw=0.8, ls=":")
    ax.axvline(x(place.end_tick), color=color, lw=0.8, ls=":")
    measured = (
        f"{place.rule} {_fmt_ns(place.measured_ns)}"
        if place.measured_ns is not None
        else (place.detail or "state sequence error")
    )
    ax.text(
        x(place.end_tick) if place.end_tick > place.start_tick else x(place.start_tick),
        lane,
        f"  {measured}",
        ha="left",
        va="center",
        fontsize=9,
        color=color,
        fontweight="bold",
        bbox={"facecolor": "white", "edgecolor": "none", "alpha": 0.8, "pad": 1},
    )
    ax.set_title(
        place_title(report, place, index),
        fontsize=10,
        loc="left",
        color=color if place.failed else "#222",
    )
    ax.set_xlim(x(lo), x(hi))
    ax.set_ylim(-0.4, lane + 1.2)
    ax.set_yticks([])
    ax.set_xlabel(f"time from the interval's start ({unit})", fontsize=9)
    for side in ("top", "right", "left"):
        ax.spines[side].set_visible(False)
    ax.tick_params(labelsize=8)


def place_title(report: Report, place: Place, index: int) -> str:
    """The title of the ``index``-th timing diagram."""
    t_s = report.capture.timebase.seconds(place.start_tick)
    verdict = "FAIL" if place.failed else "smallest margin"
    margin = "" if place.margin_ns is None else f", margin {_signed_ns(place.margin_ns)}"
    return f"{index}. {place.rule} — {verdict} at t = {float(t_s):.6f} s{margin}"


def hist_title(r: RuleResult) -> str:
    """The title of a rule's histogram."""
    return (
        f"{r.rule}: {r.checked:,} interval(s), {r.violations:,} fail, min margin "
        f"{_signed_ns(r.min_margin_ns)}"
    )


def _human_ns(v: float, _pos: object = None) -> str:
    """Tick label for a time in ns: ``500 ns``, ``20 µs``, ``5 ms``."""
    if v <= 0:
        return "0"
    name, scale = _unit_for(v)
    return f"{v / scale:g} {name}"


def _count_label(v: float, _pos: object = None) -> str:
    return f"{v:,.0f}" if v >= 1 else ""


def _log_x(ax: Axes, lo: float, hi: float, limit: float) -> bool:
    """Set a log time axis (ns, human tick labels) when the lengths span decades (the space
    between pulses of a slow move); True when set."""
    from matplotlib.ticker import FuncFormatter, NullLocator

    if not (lo > 0 and limit > 0 and max(hi, limit) / min(lo, limit) > 50):
        return False
    ax.set_xscale("log")
    ax.xaxis.set_major_formatter(FuncFormatter(_human_ns))
    ax.xaxis.set_minor_locator(NullLocator())  # no unlabelled minor ticks: a third of the drawing
    return True


def binned(r: RuleResult) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64], list[int]]:
    """A rule's fixed bins (:meth:`RuleResult.histogram`, four per octave of ticks) as
    (left edges in ns, right edges in ns, counts); the bin of lengths ≤ 0 spans [0, 1 tick)."""
    from wavecheck.engine.parts import Histogram

    hist = r.histogram()
    pairs = hist.counts if hist is not None else ()
    tick = r.timebase.tick_ns
    left = [0 if b == 0 else Histogram.lower_edge(b) * tick for b, _ in pairs]
    right = [Histogram.lower_edge(b + 1) * tick for b, _ in pairs]
    return np.array(left, float), np.array(right, float), [c for _, c in pairs]


def _bars_binned(ax: Axes, r: RuleResult) -> tuple[str, float, bool, int]:
    """A rule's fixed bins as bars: (unit, ns per unit, log x, highest count); a bin wholly
    below the limit is drawn as failing, one the limit splits as indeterminate."""
    assert r.limit_ns is not None and r.min_measured_ns is not None
    assert r.max_measured_ns is not None
    limit = float(r.limit_ns)
    left, right, counts = binned(r)
    lo, hi = float(r.min_measured_ns), float(r.max_measured_ns)
    log_x = _log_x(ax, lo, hi, limit)
    if log_x:
        unit, scale = "", 1.0
        left = np.maximum(left, min(lo, limit) * 0.8)
    else:
        unit, scale = _unit_for(max(limit, hi) / 2 or 1.0)
    colors = [
        _FAIL_COLOR if b <= limit else "#5b7db1" if a >= limit else _INDET_COLOR
        for a, b in zip(left.tolist(), right.tolist(), strict=True)
    ]
    ax.bar(left / scale, counts, width=(right - left) / scale, align="edge", color=colors)
    return unit, scale, log_x, max(counts, default=0)


def _draw_histogram(ax: Axes, r: RuleResult) -> None:
    from matplotlib.ticker import FuncFormatter, MaxNLocator, NullLocator

    assert r.limit_ns is not None
    unit, scale, log_x, top = _bars_binned(ax, r)
    lim = float(r.limit_ns) / scale
    if top > 50:
        ax.set_yscale("log")
        ax.set_ylim(bottom=0.7)
        ax.yaxis.set_major_formatter(FuncFormatter(_count_label))
        ax.yaxis.set_minor_locator(NullLocator())
    else:
        ax.yaxis.set_major_locator(MaxNLocator(integer=True))
    ax.axvline(lim, color=_FAIL_COLOR, lw=1.6, ls="--")
    ax.text(
        lim,
        1.0,
        f" limit {_fmt_ns(r.limit_ns)}",
        transform=ax.get_xaxis_transform(),
        ha="left",
        va="top",
        fontsize=8,
        color=_FAIL_COLOR,
    )
    status = {"fail": _FAIL_COLOR, "pass": _PASS_COLOR, "indeterminate": _INDET_COLOR}
    ax.set_title(
        hist_title(r),
        fontsize=9,
        loc="left",
        color=status.get(r.verdict, "#222"),
    )
    bins = ", 4 bins per octave"
    ax.set_xlabel(
        f"measured (log scale{bins})" if log_x else f"measured ({unit}{bins})", fontsize=8.5
    )
    ax.set_ylabel("count", fontsize=8.5)
    ax.tick_params(labelsize=8)
    for side in ("top", "right"):
        ax.spines[side].set_visible(False)


def figure(report: Report, max_places: int = MAX_PLACES, dpi: int = 110) -> Figure:
    """The report's figure: timing diagrams, the motion panel (position and step rate, when
    there are steps, from the step trace), then histograms; laid out in fixed room
    (:mod:`wavecheck.report.layout`), drawn on a bare Agg figure (no pyplot state)."""
    from wavecheck.report.layout import fixed_titles

    with fixed_titles():
        return _figure(report, max_places, dpi)


def _figure(report: Report, max_places: int, dpi: int) -> Figure:
    from matplotlib.figure import Figure

    from wavecheck.report.layout import WIDTH_IN, Row, figure_height, place_rows, suptitle

    places = choose_places(report, max_places)
    hist_rules = [
        r
        for r in report.rules
        if r.limit_ns is not None and (h := r.histogram()) is not None and h.counts
    ]
    n_roles = max(len(report.interface.signals), 1)
    hist_cols = 2 if len(hist_rules) > 1 else 1
    motion = report.trace is not None and report.trace.count > 1
    rows = [Row(0.3 + 0.55 * n_roles)] * len(places) + [Row(1.5, 2)] * motion
    full, last = divmod(len(hist_rules), hist_cols)
    rows += [Row(1.7, hist_cols)] * full + [Row(1.7)] * last  # an odd last histogram: whole width
    nothing = not places and not hist_rules
    rows += [Row(0.5)] * nothing
    verdict = report.verdict.upper()
    vcolor = {"FAIL": _FAIL_COLOR, "PASS": _PASS_COLOR}.get(verdict, _INDET_COLOR)
    said = not_checked(report)  # "dir_setup, dir_hold not checked: no DIR channel; …"
    title = [
        f"{verdict} — {os.path.basename(report.capture.path)} vs {report.drive.id} "
        f"({report.total_violations:,} violation(s), {report.steps.count:,} steps)",
        *textwrap.wrap(f"({said})" if said else "", 110),
    ]
    fig = Figure(figsize=(WIDTH_IN, figure_height(rows, len(title))), dpi=dpi)
    suptitle(fig, "\n".join(title), fontsize=12, color=vcolor, fontweight="bold")
    panels = iter(place_rows(fig, rows, len(title)))
    for k, place in enumerate(places):
        _draw_place(next(panels)[0], report, place, k + 1)
    if motion:
        from wavecheck.report.measured_plot import draw_motion, position_unknown

        ax_pos, ax_rate = next(panels)
        assert report.trace is not None
        unknown = position_unknown(report.step_type, report.interface, report.steps)
        draw_motion(ax_pos, ax_rate, report.trace, report.capture.timebase, "steps", unknown)
    hist_axes = [ax for row in panels for ax in row]
    for ax, r in zip(hist_axes, hist_rules, strict=False):
        _draw_histogram(ax, r)
    if nothing:
        ax = hist_axes[0]
        ax.axis("off")
        ax.text(0.5, 0.5, "nothing measured", ha="center", va="center")
    return fig


def render_png(
    report: Report, max_places: int = MAX_PLACES, dpi: int = 110, fmt: str = "png"
) -> bytes:
    """The report's figure (:func:`figure`) as PNG bytes (``fmt``: another format matplotlib
    writes, ``jpg``, ``svg``, ``pdf``: :data:`wavecheck.output.FIGURE_FORMATS`)."""
    from wavecheck.report.layout import figure_bytes

    return figure_bytes(figure(report, max_places, dpi), fmt)


def write_plot(report: Report, path: str | os.PathLike[str], max_places: int = MAX_PLACES) -> None:
    """Render the report's figure in the format ``path``'s extension says and write it there
    atomically."""
    atomic_write(path, render_png(report, max_places, fmt=figure_format(path)))
