"""One self-contained HTML page for one or more reports.

Everything is inline: CSS in a ``<style>`` element, the plots as base64 ``data:`` PNG images; the
page makes no request of its own (no scripts, fonts, or links to anything outside). Per capture
it shows the verdict, what was checked, the rule table, the worst violations, the maximum step
rates, the notes and the plots (:mod:`wavecheck.report.plot`).

Element ids for tools and tests: ``verdict`` (the overall verdict), per capture a ``section``
with class ``capture`` and ``data-verdict`` whose ``p.verdict-line`` names the rules not checked
and why (and ``p.required`` the rules ``--require`` asks for that were not decided), a
``summary`` table (several captures or axes; an ``axis`` column when there are axes), tables
with class ``rules``, ``violations``, ``rates``,
and a ``dl`` with class ``sources`` (``id="sources-N"``; each key's ``dt`` has ``id="src-N-KEY"``)
listing the full references the rule table's "source" column cites. A limit whose figure is
uncertain or a firmware default carries its mark (``100 ns?``); identical violations are one row
with their count (:mod:`wavecheck.report.groups`); the check's assumptions are among the notes.
"""

from __future__ import annotations

import base64
import html
import os
from collections.abc import Iterable, Iterator, Sequence
from dataclasses import dataclass
from fractions import Fraction

from wavecheck.drives.datasheet import MARK_LEGEND
from wavecheck.engine import Report
from wavecheck.output import atomic_write
from wavecheck.report import claims
from wavecheck.report.assumptions import assumptions
from wavecheck.report.groups import group_violations
from wavecheck.units import format_ns, format_rate, format_time
from wavecheck.verdict import overall_verdict

__all__ = ["PageRow", "html_page", "html_section", "render_html", "write_html"]

_CSS = """
body{font-family:system-ui,-apple-system,"Segoe UI",Roboto,sans-serif;margin:2rem auto;
max-width:1200px;padding:0 1rem;color:#222;line-height:1.4}
h1{font-size:1.5rem;margin-bottom:.2rem}h2{font-size:1.2rem;margin-top:2rem;
border-bottom:1px solid #ddd;padding-bottom:.2rem}h3{font-size:1rem;margin:1.2rem 0 .4rem}
.verdict{display:inline-block;padding:.15rem .6rem;border-radius:4px;color:#fff;font-weight:700}
.v-pass{background:#27ae60}.v-fail{background:#c0392b}.v-indeterminate,.v-unchecked{background:#e67e22}
table{border-collapse:collapse;margin:.4rem 0;font-size:.9rem}
th,td{border:1px solid #ddd;padding:.25rem .55rem;text-align:left}
th{background:#f4f4f4}td.num{text-align:right;font-variant-numeric:tabular-nums}
tr.r-fail td{background:#fdecea}tr.r-indeterminate td{background:#fef5e7}
dl{display:grid;grid-template-columns:max-content auto;gap:.1rem 1rem;margin:.4rem 0}
dt{font-weight:600}dd{margin:0}.note{color:#555;font-size:.9rem}
img{max-width:100%;border:1px solid #eee}
.summary td:first-child{font-family:ui-monospace,monospace}
.verdict-line{font-weight:600}.required{color:#c0392b;font-weight:600}
"""


def _e(text: object) -> str:
    return html.escape(str(text), quote=True)


def _ns(v: Fraction | None, signed: bool = False) -> str:
    return format_ns(v, signed=signed, missing="–")


def _hz(v: Fraction | None) -> str:
    return format_rate(v, missing="–")


def _badge(verdict: str) -> str:
    return f'<span class="verdict v-{_e(verdict)}">{_e(verdict.upper())}</span>'


def _src_id(index: int, key: str) -> str:
    return f"src-{index}-{key}"


def _source_cell(report: Report, index: int, key: str, status: str) -> str:
    if not key:
        return ""
    text = _e(key)
    if key in report.drive.sources:
        text = f'<a href="#{_e(_src_id(index, key))}">{text}</a>'
    return text if status == "datasheet" else f"{text} ({_e(status)})"


def _rules_table(report: Report, index: int) -> str:
    head = (
        "<tr><th>rule</th><th>limit</th><th>checked</th><th>fail</th><th>indet.</th>"
        "<th>shortest</th><th>min margin</th><th>at (s)</th><th>verdict</th><th>source</th></tr>"
    )
    rows = []
    for r in report.rules:
        at = r.min_margin_at_s
        fig = r.figure
        src = _source_cell(report, index, fig.source, fig.status) if fig else ""
        mark = fig.mark if fig else ""
        rows.append(
            f'<tr class="r-{_e(r.verdict)}"><td>{_e(r.rule)}</td>'
            f'<td class="num">{_ns(r.limit_ns)}{_e(mark)}</td><td class="num">{r.checked:,}</td>'
            f'<td class="num">{r.violations:,}</td><td class="num">{r.indeterminate:,}</td>'
            f'<td class="num">{_ns(r.min_measured_ns)}</td>'
            f'<td class="num">{_ns(r.min_margin_ns, signed=True)}</td>'
            f'<td class="num">{"–" if at is None else f"{float(at):.9f}"}</td>'
            f'<td>{_badge(r.verdict)}</td><td class="note">{src}</td></tr>'
        )
    legend = ""
    if any(r.figure is not None and r.figure.mark for r in report.rules):
        legend = f'<p class="note">{_e(MARK_LEGEND)}.</p>'
    return f'<table class="rules">{head}{"".join(rows)}</table>{legend}'


def _violations_table(report: Report, limit: int) -> str:
    total = report.total_violations
    if not total:
        return "<p>No violations.</p>"
    head = (
        "<tr><th>#</th><th>rule</th><th>count</th><th>at (s)</th><th>last at (s)</th>"
        "<th>measured</th><th>limit</th><th>margin</th></tr>"
    )
    shown = report.violations(limit)
    groups = group_violations(shown, report.rules)
    marks = {r.rule: r.figure.mark for r in report.rules if r.figure is not None}
    rows = []
    for k, g in enumerate(groups, 1):
        v = g.first
        if v.margin_ns is None:
            cells = f'<td colspan="3">{_e(v.detail)}</td>'
        else:
            cells = (
                f'<td class="num">{_ns(v.measured_ns)}</td>'
                f'<td class="num">{_ns(v.limit_ns)}{_e(marks.get(v.rule, ""))}</td>'
                f'<td class="num">{_ns(v.margin_ns, signed=True)}</td>'
            )
        last = "–" if g.count == 1 else f"{float(g.last_s):.9f}"
        rows.append(
            f'<tr><td class="num">{k}</td><td>{_e(v.rule)}</td><td class="num">{g.count:,}</td>'
            f'<td class="num">{float(g.first_s):.9f}</td><td class="num">{last}</td>{cells}</tr>'
        )
    told = sum(g.count for g in groups)
    more = f'<p class="note">… and {total - told:,} more.</p>' if total > told else ""
    grouped = (
        f" The {len(shown):,} worst are shown as {len(groups):,} "
        f"group{'' if len(groups) == 1 else 's'} of identical violations (count, first and last "
        "time)."
        if len(groups) < len(shown)
        else ""
    )
    return (
        f"<p>{total:,} violation(s), worst first.{grouped}</p>"
        f'<table class="violations">{head}{"".join(rows)}</table>{more}'
    )


def _sources(report: Report, index: int) -> str:
    """The drive's full references, keyed as the rule table's "source" column cites them."""
    items = "".join(
        f'<dt id="{_e(_src_id(index, key))}">{_e(key)}</dt><dd>{_e(text)}</dd>'
        for key, text in report.drive.sources.items()
    )
    return (
        f'<dl class="sources" id="sources-{index}">{items}</dl>'
        f'<p class="note">Rule file: {_e(report.drive.path)}</p>'
    )


def _rates_table(report: Report) -> str:
    rates = report.rates
    rows = [
        (
            "drive",
            rates.drive,
            f"datasheet ({rates.drive_limited_by})" if rates.drive_limited_by else "datasheet",
        ),
        ("observed", rates.observed, "highest instantaneous rate in the capture"),
        (
            "headroom",
            rates.headroom,
            "highest rate at which this generator's pulses (typical length "
            f"{_ns(rates.typical_pulse_ns)}) still leave the gaps their minimum"
            + (f"; limited by {rates.headroom_limited_by}" if rates.headroom_limited_by else "")
            + (f"; none: {rates.headroom_note}" if rates.headroom_note else ""),
        ),
    ]
    cfg = rates.configured
    if cfg is not None:
        assumed = f"stepgen channel {cfg.channel}, BASE_PERIOD {_ns(Fraction(cfg.base_period_ns))}"
        if cfg.latency_ns is not None:
            assumed += f", J = {_ns(cfg.latency_ns)}"
        rows.append(("config", cfg.config, f"stepgen's own clamp ({assumed})"))
        why = "" if cfg.latency_safe is not None else "; ".join(cfg.notes)
        rows.append(
            (
                "latency_safe",
                cfg.latency_safe,
                f"meets the drive under worst latency ({assumed})"
                + (f"; none: {why}" if why else ""),
            )
        )
    body = "".join(
        f'<tr><td>{_e(k)}</td><td class="num">{_hz(v)}</td><td class="note">{_e(what)}</td></tr>'
        for k, v, what in rows
    )
    return f'<table class="rates"><tr><th>max step rate</th><th>rate</th><th>meaning</th></tr>{body}</table>'


def _verdict_lines(report: Report, require: Sequence[str]) -> list[str]:
    """The verdict line (rules not checked and why) and the required rules not decided."""
    out = [f'<p class="verdict-line">Verdict: {_e(claims.outcome_line(report, require))}</p>']
    line = claims.requirement_line(report, require)
    return out + ([f'<p class="required">{_e(line)}</p>'] if line else [])


def html_section(
    report: Report,
    index: int,
    png: bytes | None,
    max_violations: int,
    require: Sequence[str] = (),
) -> str:
    """The page's section of ``report``, the ``index``-th (from 1), with its figure ``png``."""
    cap = report.capture
    res = "exact" if report.resolution_ns == 0 else _ns(report.resolution_ns)
    mapping = ", ".join(f"{role} = {ch!r}" for role, ch in report.mapping.items())
    if report.inverted:
        mapping += f"; inverted: {', '.join(report.inverted)}"
    s = report.steps
    pos = "unknown" if s.final_position is None else f"{s.final_position:+d}"
    edge_mark = report.drive.edge_mark if report.active_edge == report.drive.active_edge else ""
    parts = [
        f'<section class="capture" id="capture-{index}" data-verdict="{_e(report.verdict)}">',
        f"<h2>{_badge(report.verdict)} {_e(cap.path)}"
        + (f" — axis {_e(report.axis)}" if report.axis is not None else "")
        + "</h2>",
        *_verdict_lines(report, require),
        "<dl>",
        f"<dt>drive</dt><dd>{_e(report.drive.id)} — {_e(report.drive.name)} "
        f"(steps on the {_e(report.active_edge)}{_e(edge_mark)} edge)</dd>",
        f"<dt>capture</dt><dd>{_e(cap.format)}, {_e(format_time(cap.duration_s))}, "
        f"resolution {_e(res)}, {len(cap.channels)} channels</dd>",
        f"<dt>mapping</dt><dd>{_e(mapping)}; step type {report.step_type.number} "
        f"({_e(report.step_type.name)})</dd>",
        f"<dt>steps</dt><dd>{s.count:,} (forward {s.forward:,}, reverse {s.reverse:,}; "
        f"final position {_e(pos)})</dd>",
        "</dl>",
        "<h3>Rules</h3>",
        _rules_table(report, index),
    ]
    if report.not_stated:
        parts.append(
            f'<p class="note">Not stated by the drive (not checked): {_e(", ".join(report.not_stated))}</p>'
        )
    parts += ["<h3>Worst violations</h3>", _violations_table(report, max_violations)]
    parts += ["<h3>Maximum step rates</h3>", _rates_table(report)]
    notes = [*report.notes, *assumptions(report)]
    if notes:
        parts.append("<h3>Notes</h3><ul>")
        parts += [f"<li>{_e(n)}</li>" for n in notes]
        parts.append("</ul>")
    if report.drive.sources:
        parts += ["<h3>Sources</h3>", _sources(report, index)]
    if png is not None:
        data = base64.b64encode(png).decode("ascii")
        parts.append(
            "<h3>Plots</h3>"
            f'<img alt="timing diagrams and histograms of {_e(cap.path)}" '
            f'src="data:image/png;base64,{data}">'
        )
    parts.append("</section>")
    return "\n".join(parts)


def render_html(
    reports: Sequence[Report],
    *,
    plots: bool = True,
    max_violations: int = 20,
    errors: Sequence[str] = (),
    title: str = "wavecheck report",
    pngs: Sequence[bytes | None] | None = None,
    require: Sequence[str] = (),
) -> str:
    """The page for ``reports`` (one section each).

    Args:
        reports: the checked captures.
        plots: embed the PNG figure of each report (needs matplotlib).
        max_violations: violations listed per capture (the total is always given).
        errors: one-line errors of captures that could not be checked (shown, and they make the
            overall verdict ``error``).
        title: the page title.
        pngs: figures already rendered (one per report; None entries are rendered here).
        require: the rules ``--require`` asks to be decided.
    """
    given = list(pngs) if pngs is not None else [None] * len(reports)
    figures: list[bytes | None] = []
    for r, png in zip(reports, given, strict=True):
        if plots and png is None:
            from wavecheck.report.plot import render_png

            png = render_png(r)
        figures.append(png if plots else None)
    sections = (
        html_section(r, k, png, max_violations, require)
        for k, (r, png) in enumerate(zip(reports, figures, strict=True), 1)
    )
    rows = [PageRow.of(r, require) for r in reports]
    return "".join(html_page(rows, sections, errors=errors, title=title))


@dataclass(frozen=True)
class PageRow:
    """A report's row in the page's summary table: all the page needs of a report besides its
    section (so a page of many captures can be written section by section)."""

    path: str
    axis: str | None
    drive: str
    verdict: str
    violations: int
    steps: int
    not_checked: str = ""  # the rules not checked and why (:func:`claims.not_checked`)
    required: str = ""  # the required rules not decided (:func:`claims.requirement_line`)

    @classmethod
    def of(cls, report: Report, require: Sequence[str] = ()) -> PageRow:
        """The row of ``report``; ``require``: the rules ``--require`` asks to be decided."""
        return cls(
            report.capture.path,
            report.axis,
            report.drive.id,
            report.verdict,
            report.total_violations,
            report.steps.count,
            claims.not_checked(report),
            claims.requirement_line(report, require),
        )


def _qualifier(row: PageRow) -> str:
    """The rules not checked and why, beside a summary row's badge."""
    return f' <span class="note">({_e(row.not_checked)})</span>' if row.not_checked else ""


def html_page(
    rows: Sequence[PageRow],
    sections: Iterable[str],
    *,
    errors: Sequence[str] = (),
    title: str = "wavecheck report",
) -> Iterator[str]:
    """The page in pieces: its head and summary of ``rows`` (and ``errors``), then each of
    ``sections`` (:func:`html_section`, one per row, in the same order), then its foot."""
    verdict: str = overall_verdict([r.verdict for r in rows]) if rows else "unchecked"
    if errors:
        verdict = "error"
    axes = any(r.axis is not None for r in rows)
    summary_rows = "".join(
        f'<tr><td><a href="#capture-{k}">{_e(r.path)}</a></td>'
        + (f"<td>{_e('' if r.axis is None else r.axis)}</td>" if axes else "")
        + f"<td>{_e(r.drive)}</td><td>{_badge(r.verdict)}{_qualifier(r)}</td>"
        f'<td class="num">{r.violations:,}</td><td class="num">{r.steps:,}</td></tr>'
        for k, r in enumerate(rows, 1)
    )
    error_rows = "".join(f"<li>{_e(e)}</li>" for e in errors)
    head = [
        "<!DOCTYPE html>",
        '<html lang="en"><head><meta charset="utf-8">',
        '<meta name="viewport" content="width=device-width, initial-scale=1">',
        f"<title>{_e(title)}: {_e(verdict.upper())}</title>",
        f"<style>{_CSS}</style></head><body>",
        f"<h1>{_e(title)}</h1>",
        f'<p>Overall verdict: <span id="verdict" class="verdict v-{_e(verdict)}">'
        f"{_e(verdict.upper())}</span></p>",
    ]
    for r in rows if len(rows) > 1 else ():  # one report: its section says it
        if r.required:
            where = r.path + (f" axis {r.axis}" if r.axis else "")
            head.append(f'<p class="required">{_e(where)}: {_e(r.required)}</p>')
    if len(rows) > 1 or errors:
        axis_head = "<th>axis</th>" if axes else ""
        head.append(
            f'<table class="summary"><tr><th>capture</th>{axis_head}<th>drive</th><th>verdict</th>'
            f"<th>violations</th><th>steps</th></tr>{summary_rows}</table>"
        )
    if errors:
        head.append(
            f'<h3>Captures that could not be checked</h3><ul class="errors">{error_rows}</ul>'
        )
    yield "".join(line + "\n" for line in head)
    for section in sections:
        yield section + "\n"
    yield (
        '<p class="note">Made by wavecheck. Times in s, intervals in ns/µs; a margin is measured − '
        "limit (negative = violation).</p></body></html>\n"
    )


def write_html(reports: Sequence[Report], path: str | os.PathLike[str], **kwargs: object) -> None:
    """Render :func:`render_html` and write it to ``path`` atomically."""
    atomic_write(path, render_html(reports, **kwargs))  # type: ignore[arg-type]
