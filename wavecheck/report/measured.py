"""``wavecheck measure``'s outputs: text, JSON-ready data and one self-contained HTML page.

JSON (``--format json``)::

    {"capture": {"path", "format", "tick_s", "samplerate_hz", "duration_s", "channels"},
     "resolution_ns": T, "resolution": "...",
     "axes": [{"name", "map", "inverted", "step_type", "active_edge", "dir_forward",
               "steps": {"count", "forward", "reverse", "unknown", "final_position",
                         "reversals", "reversals_at_s", "sequence_errors"},
               "step_rate_hz": {"min", "median", "max", "max_at_s"},
               "intervals": {RULE: {"what", "count", "min_ns", "min_at_s", "max_ns",
                                    "max_at_s", "mean_ns", "p1_ns", "p5_ns", "p50_ns",
                                    "p95_ns", "p99_ns"}}}],
     "notes": [...]}

Times in exact ns are JSON integers when whole, else floats; ``*_at_s`` are seconds (floats) of
the interval's start. The run has no verdict: ``measure`` judges nothing.
"""

from __future__ import annotations

import base64
import html
import os
from fractions import Fraction
from typing import Any

from wavecheck.measurement import PERCENTILES, AxisMeasurement, IntervalStats, Measurement
from wavecheck.output import atomic_write
from wavecheck.units import format_ns, format_rate, format_time, json_number

__all__ = [
    "measurement_dict",
    "render_measure_html",
    "render_measure_text",
    "resolution_line",
    "write_measure_html",
]

#: Reversal times listed in JSON at most (the count is always given).
MAX_REVERSALS = 1000


def resolution_line(m: Measurement) -> str:
    """What bounds every figure: the resolution T (one sample period, unless overridden)."""
    t = m.resolution_ns
    if t == 0:
        return "T = 0 (a simulator's exact times): every figure is exact"
    cap = m.capture
    if t != cap.resolution_ns:
        what = "--resolution"
    elif cap.samplerate_hz is not None:
        what = f"one sample period at {format_rate(cap.samplerate_hz)}"
    else:
        what = "the capture's resolution"
    return f"T = {format_ns(t)} ({what}): every interval is within ± T of its figure"


def _at(tb_seconds: Fraction | None) -> str:
    return "-" if tb_seconds is None else f"{float(tb_seconds):.9f} s"


def _seconds(s: IntervalStats, tick: int | None) -> Fraction | None:
    return None if tick is None else s.timebase.seconds(tick)


def _axis_head(a: AxisMeasurement) -> list[str]:
    label = "axis" if a.name is None else f"axis {a.name}"
    mapping = ", ".join(f"{role}={ch!r}" for role, ch in a.mapping.items())
    inv = f"; inverted {', '.join(a.inverted)}" if a.inverted else ""
    st = a.step_type
    steps = a.steps
    pos = steps.final_position
    tb = a.interface.capture.timebase
    rev = a.reversals
    first = f" (first at {_at(tb.seconds(int(a.reversal_ticks[0])))})" if rev else ""
    lines = [
        f"{label}: {mapping}{inv}; step type {st.number} ({st.kind}); active edge "
        f"{a.active_edge}"
        + (
            f"; DIR {'high' if a.forward_level else 'low'} = forward"
            if st.kind == "step-dir"
            else ""
        ),
        f"  steps:     {steps.count} (forward {steps.forward}, reverse {steps.reverse}, unknown "
        f"{steps.unknown}); final position {'unknown' if pos is None else f'{pos:+d}'}; "
        f"{rev} reversal(s){first}",
    ]
    if a.sequence_errors:
        lines.append(f"  sequence:  {a.sequence_errors} move(s) to a state that is not a neighbour")
    if a.rate_max_hz is not None:
        at = _seconds(a.period, a.period.min_at)
        lines.append(
            f"  step rate: {format_rate(a.rate_min_hz)} … {format_rate(a.rate_max_hz)} "
            f"(median {format_rate(a.rate_median_hz)}; highest at {_at(at)})"
        )
    return lines


def _table(rows: list[list[str]]) -> list[str]:
    widths = [max(len(r[i]) for r in rows) for i in range(len(rows[0]))]
    return [
        "  " + "  ".join(c.ljust(w) for c, w in zip(r, widths, strict=True)).rstrip() for r in rows
    ]


def _interval_rows(a: AxisMeasurement) -> list[list[str]]:
    rows = [["interval", "count", "min", "at", "p1", "median", "p99", "mean", "max", "at"]]
    for s in a.stats:
        rows.append(
            [
                s.rule,
                str(s.count),
                format_ns(s.min_ns),
                _at(_seconds(s, s.min_at)),
                format_ns(s.percentile_ns(1)),
                format_ns(s.percentile_ns(50)),
                format_ns(s.percentile_ns(99)),
                format_ns(s.mean_ns),
                format_ns(s.max_ns),
                _at(_seconds(s, s.max_at)),
            ]
        )
    return rows


def render_measure_text(m: Measurement) -> str:
    """The text report: the capture, what bounds the figures, then a section per axis."""
    cap = m.capture
    out = [
        f"capture:    {cap.path} ({cap.timebase.describe()} tick, "
        f"{format_time(cap.duration_s)}, {len(cap.channels)} channels)",
        f"resolution: {resolution_line(m)}",
    ]
    if len(m.axes) > 1:
        out.append(
            "steps:      "
            + ", ".join(
                f"{a.name} {a.steps.count}"
                + ("" if a.steps.final_position is None else f" ({a.steps.final_position:+d})")
                for a in m.axes
            )
        )
    for a in m.axes:
        out += ["", *_axis_head(a), "", *_table(_interval_rows(a))]
        empty = [s.rule for s in a.stats if s.count == 0]
        if empty:
            out.append(
                f"  not measured (no complete interval, or its signal not mapped): {', '.join(empty)}"
            )
    if m.notes:
        out.append("")
        out += [f"note: {n}" for n in m.notes]
    return "\n".join(out) + "\n"


def _stats_dict(s: IntervalStats) -> dict[str, Any]:
    d: dict[str, Any] = {
        "what": s.what,
        "count": s.count,
        "min_ns": json_number(s.min_ns),
        "min_at_s": json_number(_seconds(s, s.min_at)),
        "max_ns": json_number(s.max_ns),
        "max_at_s": json_number(_seconds(s, s.max_at)),
        "mean_ns": json_number(s.mean_ns),
    }
    for p in PERCENTILES:
        d[f"p{p}_ns"] = json_number(s.percentile_ns(p))
    return d


def _axis_dict(a: AxisMeasurement) -> dict[str, Any]:
    tb = a.interface.capture.timebase
    steps = a.steps
    return {
        "name": a.name,
        "map": a.mapping,
        "inverted": list(a.inverted),
        "step_type": a.step_type.number,
        "active_edge": a.active_edge,
        "dir_forward": "high" if a.forward_level else "low",
        "steps": {
            "count": steps.count,
            "forward": steps.forward,
            "reverse": steps.reverse,
            "unknown": steps.unknown,
            "final_position": steps.final_position,
            "reversals": a.reversals,
            "reversals_at_s": [
                json_number(tb.seconds(int(t))) for t in a.reversal_ticks[:MAX_REVERSALS].tolist()
            ],
            "sequence_errors": a.sequence_errors,
        },
        "step_rate_hz": {
            "min": json_number(a.rate_min_hz),
            "median": json_number(a.rate_median_hz),
            "max": json_number(a.rate_max_hz),
            "max_at_s": json_number(_seconds(a.period, a.period.min_at)),
        },
        "intervals": {s.rule: _stats_dict(s) for s in a.stats},
    }


def measurement_dict(m: Measurement) -> dict[str, Any]:
    """The JSON-ready data of a measurement (keys in the module docstring)."""
    cap = m.capture
    tb = cap.timebase
    return {
        "capture": {
            "path": cap.path,
            "format": cap.format,
            "tick_s": str(tb.tick_s),
            "samplerate_hz": json_number(cap.samplerate_hz),
            "duration_s": json_number(cap.duration_s),
            "channels": [c.name for c in cap.channels],
        },
        "resolution_ns": json_number(m.resolution_ns),
        "resolution": resolution_line(m),
        "axes": [_axis_dict(a) for a in m.axes],
        "notes": list(m.notes),
    }


_CSS = """
body{font-family:system-ui,-apple-system,"Segoe UI",Roboto,sans-serif;margin:2rem auto;
max-width:1200px;padding:0 1rem;color:#222;line-height:1.4}
h1{font-size:1.5rem}h2{font-size:1.2rem;margin-top:2rem;border-bottom:1px solid #ddd}
table{border-collapse:collapse;margin:.4rem 0;font-size:.9rem}
th,td{border:1px solid #ddd;padding:.25rem .55rem;text-align:left}
th{background:#f4f4f4}td.num{text-align:right;font-variant-numeric:tabular-nums}
.note{color:#555;font-size:.9rem}img{max-width:100%;border:1px solid #eee}
"""


def _e(text: object) -> str:
    return html.escape(str(text), quote=True)


def render_measure_html(m: Measurement, png: bytes | None = None) -> str:
    """One self-contained page (inline CSS, the figure as a ``data:`` PNG): the capture, the
    resolution, a table of every interval kind per axis (class ``intervals``), the notes."""
    cap = m.capture
    body = [
        "<!DOCTYPE html>",
        '<html lang="en"><head><meta charset="utf-8">',
        f"<title>wavecheck measure: {_e(os.path.basename(cap.path))}</title>",
        f"<style>{_CSS}</style></head><body>",
        f"<h1>wavecheck measure: {_e(cap.path)}</h1>",
        f"<p>{_e(cap.timebase.describe())} tick, {_e(format_time(cap.duration_s))}, "
        f"{len(cap.channels)} channels. Resolution: {_e(resolution_line(m))}.</p>",
    ]
    for k, a in enumerate(m.axes, 1):
        head = _axis_head(a)
        body.append(f'<section class="axis" id="axis-{k}"><h2>{_e(head[0])}</h2>')
        body += [f"<p>{_e(line.strip())}</p>" for line in head[1:]]
        rows = _interval_rows(a)
        body.append(
            '<table class="intervals"><tr>'
            + "".join(f"<th>{_e(c)}</th>" for c in rows[0])
            + "</tr>"
        )
        for r in rows[1:]:
            cells = [f"<td>{_e(r[0])}</td>"] + [f'<td class="num">{_e(c)}</td>' for c in r[1:]]
            body.append("<tr>" + "".join(cells) + "</tr>")
        body.append("</table></section>")
    if m.notes:
        body.append(
            '<ul class="notes">'
            + "".join(f'<li class="note">{_e(n)}</li>' for n in m.notes)
            + "</ul>"
        )
    if png is not None:
        data = base64.b64encode(png).decode("ascii")
        body.append(
            f'<h2>Figures</h2><img alt="position, step rate and histograms" src="data:image/png;base64,{data}">'
        )
    body.append(
        '<p class="note">Made by wavecheck measure: no drive, no limits, no verdicts.</p></body></html>'
    )
    return "\n".join(body) + "\n"


def write_measure_html(
    m: Measurement, path: str | os.PathLike[str], png: bytes | None = None
) -> None:
    """Write :func:`render_measure_html` to ``path`` atomically."""
    atomic_write(path, render_measure_html(m, png))
