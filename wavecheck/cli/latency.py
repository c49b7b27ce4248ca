"""``wavecheck latency CAPTURE [--map ROLE=CH] [--base-period P | --ini F --hal F]``: base-thread
latency measured on the step pins (see :mod:`wavecheck.lattice`).

The channels are mapped as ``check`` maps them (``--map [AXIS.]ROLE=CH``, channels named after a
role, else the roles inferred from the waveforms); every mapped channel of every axis is read,
since one base thread drives them all. Exit codes: 0 the edges lie on a periodic lattice
and the worst lateness is established (reported), 3 it is not (not a base thread's timing, too
few edges, lateness of a period or more, or readings the capture cannot tell apart), 2 unusable
input.
"""

from __future__ import annotations

import argparse
import base64
import html
import io
import json
import sys
from fractions import Fraction
from typing import TYPE_CHECKING, Any

from wavecheck.capture.edges import Capture
from wavecheck.cli._axis_args import add_axis_arguments, check_options
from wavecheck.cli._capture_args import add_capture_arguments, capture_from_args
from wavecheck.cli._formats import Formats
from wavecheck.errors import UnitError, UsageError
from wavecheck.output import atomic_write, figure_file, figure_format, output_file
from wavecheck.progress import activate, current
from wavecheck.units import format_ns, json_number, time_ns
from wavecheck.verdict import EXIT_INDETERMINATE, EXIT_PASS

if TYPE_CHECKING:  # imported where used: only `wavecheck latency` needs it
    from wavecheck.lattice import LatencyReport

__all__ = ["capture_latency", "register", "render_json", "render_text", "run"]


def register(sub: Any) -> None:
    """Add the ``latency`` subcommand."""
    p = sub.add_parser(
        "latency",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("capture", metavar="CAPTURE", help="the capture (.sr, .vcd, ...)")
    add_axis_arguments(p, drive=False)
    p.add_argument(
        "--also",
        action="append",
        default=[],
        metavar="CH",
        help="another channel the same thread drives (an output that is no axis' role; repeatable)",
    )
    p.add_argument("--base-period", metavar="P", help="use this base period (e.g. 25us)")
    p.add_argument("--ini", metavar="FILE", help="LinuxCNC INI: [EMCMOT]BASE_PERIOD")
    p.add_argument("--hal", action="append", default=[], metavar="FILE", help="LinuxCNC HAL file")
    add_capture_arguments(p)
    FORMATS.add_argument(p)
    p.add_argument("-o", "--output", type=output_file, metavar="FILE", help="write the report here")
    p.add_argument(
        "--plot",
        type=figure_file,
        metavar="FILE.png",
        help="histogram + lateness over time (PNG; .jpg, .svg or .pdf by the file's name)",
    )
    p.add_argument("--html", type=output_file, metavar="FILE.html", help="a self-contained page")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=run)


def channel_roles(capture: Capture, args: argparse.Namespace) -> tuple[list[str], dict[str, str]]:
    """:func:`wavecheck.step_latency.step_channels` of the axes of ``args``, and ``--also``.

    Raises:
        UsageError: no step channel found, or the axis options do not fit the capture.
    """
    from wavecheck.step_latency import step_channels

    names, first = step_channels(capture, check_options(args, with_drive=False))
    names += list(args.also)
    if not names:
        raise UsageError(
            f"{capture.path}: no step channel found (map them: --map step=CH,dir=CH; channels: "
            f"{', '.join(repr(c.name) for c in capture.channels)})"
        )
    return list(dict.fromkeys(names)), first


def _period_ns(args: argparse.Namespace) -> tuple[Fraction | None, str]:
    if args.base_period:
        try:
            return time_ns(args.base_period), f"--base-period {args.base_period}"
        except UnitError as err:
            raise UnitError(f"--base-period: {err}") from None
    if args.ini or args.hal:
        from wavecheck.linuxcnc.stepgen_config import read_config

        cfg = read_config(args.ini, list(args.hal))
        if cfg.base_period_ns is None:
            raise UsageError(
                "--ini/--hal give no base period ([EMCMOT]BASE_PERIOD or loadrt threads)"
            )
        return Fraction(cfg.base_period_ns), cfg.sources.get("BASE_PERIOD", "--ini/--hal")
    return None, "inferred from the edges"


def capture_latency(args: argparse.Namespace, path: str) -> LatencyReport:
    """Open ``path`` and analyse it with the options in ``args``."""
    from wavecheck.lattice import analyse

    with activate(f"reading {path}", quiet=getattr(args, "quiet", False), unit="bytes"):
        capture = capture_from_args(args, path)
    period, _ = _period_ns(args)
    names, roles = channel_roles(capture, args)
    with activate("finding the lattice", quiet=getattr(args, "quiet", False), unit="edges"):
        return analyse(capture, names, period, roles, progress=current())


def _ns(v: Fraction | None) -> str:
    return format_ns(v)


def render_text(r: LatencyReport, source: str = "") -> str:
    """The text report."""
    res = r.resolution_ns
    lines = [f"{r.path}: {r.n_edges} edge times on {', '.join(r.channels)}"]
    lines.append(
        "  edges per channel: " + ", ".join(f"{c} {n}" for c, n in r.edges_per_channel.items())
    )
    lines.append(f"  {r.reason}")
    if r.lattice and not r.established:
        lines.append(
            f"  the worst lateness is not established ({r.unestablished}): plan from no figure here"
        )
    if r.fit is None or not len(r.lateness_num):
        lines.append("  no lateness figures: base-thread latency cannot be read from this capture")
        return "\n".join(lines) + "\n"
    fit = r.fit
    unc = f"± {float(fit.half_width * r.tick_ns):.3g} ns" if fit.half_width else "exact"
    lines.append(
        f"  base period P = {_ns(r.period_ns)} ({float(r.period_ns or 0):.9g} ns, "
        f"{fit.period} ticks; {source or ('given' if fit.given else 'inferred')}; {unc})"
    )
    lines.append(
        f"  lattice phase {_ns(r.phase_ns)} (the earliest edge is on time), "
        f"{fit.span_periods} periods spanned; chance of a fit this good without a thread "
        f"10^{fit.log10_chance:.0f}"
    )
    lines.append(
        f"  resolution: every figure below is exact to ± {_ns(res) if res else '0 (exact VCD)'}"
    )
    lines.append("  lateness (edge time − (phase + k·P)):")
    for q in (50, 90, 99, 99.9):
        lines.append(f"    p{q:<5g} {_ns(r.percentile_ns(q))}")
    bound = r.max_lateness_bound_ns
    lines.append(
        f"    max    {_ns(r.max_lateness_ns)}"
        + (f" (at most {_ns(bound)}: plus one sample)" if res else "")
        + ("" if r.catch_up is None else " — at least: see the catch-up note")
    )
    for c in r.candidates:
        lines.append(
            f"    or     {_ns(c.max_lateness_ns)} with P = {_ns(c.period_ns)} ({c.how}): the "
            "capture cannot tell"
        )
    worst = r.worst()
    if worst:
        lines.append(f"  worst lateness at {float(worst[0]) * 1e-9:.9g} s on {', '.join(worst[1])}")
    jit, pairs, rng = r.jitter()
    lines.append(
        "  latency-test Max Jitter (timedelta: max(max − P, P − min) of successive invocations): "
        + (
            f">= {_ns(jit)} from {pairs} pairs of edges in adjacent periods; "
            if jit is not None
            else "no edges in adjacent periods; "
        )
        + f"<= {_ns(rng)} (the lateness range) for the invocations that made edges"
    )
    spikes = r.spikes()
    if spikes:
        lines.append(f"  spikes ({len(spikes)}):")
        for s in spikes[:20]:
            lines.append(
                f"    {float(s.time_ns) * 1e-9:.9g} s  {_ns(s.lateness_ns)}  {', '.join(s.channels)}"
            )
        if len(spikes) >= 2:
            gaps = [
                float(b.time_ns - a.time_ns) * 1e-9
                for a, b in zip(spikes, spikes[1:], strict=False)
            ]
            lines.append(f"    every {sorted(gaps)[len(gaps) // 2]:.6g} s (median spacing)")
    width, counts = r.histogram()
    lines.append(f"  histogram (bin {_ns(width)}):")
    top = max(int(counts.max()), 1)
    for i, c in enumerate(counts):
        if c:
            lines.append(
                f"    {_ns(width * i):>10} {int(c):>9} {'#' * max(1, round(40 * int(c) / top))}"
            )
    for note in r.notes:
        lines.append(f"  note: {note}")
    lines.append(
        "  limits: lateness up to just under P is read (a thread later than that still makes "
        "pulses only G long); a period or more late shows only where two write times fall into "
        "one period (then as a lower bound), else modulo P"
    )
    return "\n".join(lines) + "\n"


def render_json(r: LatencyReport, source: str = "") -> str:
    """The JSON report (ns as exact integers where whole)."""
    out: dict[str, Any] = {
        "capture": r.path,
        "channels": dict(r.edges_per_channel),
        "edge_times": r.n_edges,
        "lattice": r.lattice,
        "established": r.established,
        "not_established": r.unestablished or None,
        "reason": r.reason,
        "resolution_ns": json_number(r.resolution_ns),
        "notes": r.notes,
    }
    if r.fit is not None and len(r.lateness_num):
        jit, pairs, rng = r.jitter()
        worst = r.worst()
        width, counts = r.histogram()
        t, mx = r.over_time()
        out.update(
            {
                "base_period_ns": json_number(r.period_ns),
                "base_period_samples": str(r.fit.period),
                "base_period_given": r.fit.given,
                "base_period_source": source,
                "base_period_uncertainty_ns": json_number(r.fit.half_width * r.tick_ns),
                "phase_ns": json_number(r.phase_ns),
                "log10_chance": r.fit.log10_chance,
                "lateness_ns": {
                    "min": 0,
                    **{f"p{q:g}": json_number(r.percentile_ns(q)) for q in (50, 90, 99, 99.9)},
                    "max": json_number(r.max_lateness_ns),
                    "max_bound": json_number(r.max_lateness_bound_ns),
                },
                "candidates": [
                    {
                        "base_period_ns": json_number(c.period_ns),
                        "max_lateness_ns": json_number(c.max_lateness_ns),
                        "how": c.how,
                    }
                    for c in r.candidates
                ],
                "worst_case_rule": r.rule or None,
                "catch_up": None
                if r.catch_up is None
                else {
                    "edges": r.catch_up.edges,
                    "first_s": float(r.catch_up.first_ns) * 1e-9,
                    "at_least_ns": json_number(r.catch_up.at_least_ns),
                },
                "worst": {"time_s": float(worst[0]) * 1e-9, "channels": list(worst[1])}
                if worst
                else None,
                "max_jitter_ns": {
                    "at_least": json_number(jit),
                    "adjacent_pairs": pairs,
                    "at_most": json_number(rng),
                },
                "spikes": [
                    {
                        "time_s": float(s.time_ns) * 1e-9,
                        "lateness_ns": json_number(s.lateness_ns),
                        "channels": list(s.channels),
                    }
                    for s in r.spikes()
                ],
                "histogram": {"bin_ns": json_number(width), "counts": [int(c) for c in counts]},
                "over_time": {
                    "start_s": [float(x) for x in t],
                    "max_lateness_ns": [None if x != x else float(x) for x in mx],
                },
            }
        )
    return json.dumps(out, indent=2) + "\n"


def render_png(r: LatencyReport, fmt: str = "png") -> bytes:
    """Histogram and lateness over time (matplotlib, imported here), PNG or ``fmt``."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    from matplotlib.figure import Figure

    fig = Figure(figsize=(10, 6), dpi=100, layout="constrained")
    ax1, ax2 = fig.subplots(2, 1)
    if r.fit is not None and len(r.lateness_num):
        lat = r.lateness_ns / 1000
        t = r.times.astype(float) * float(r.tick_ns) * 1e-9
        ax1.hist(lat, bins=60, color="#1f3b73")
        ax1.set_yscale("log")
        ax1.set_xlabel("lateness (µs)")
        ax1.set_ylabel("edges")
        ax1.set_title(
            f"{r.path}: P = {float(r.period_ns or 0):.9g} ns, resolution {float(r.resolution_ns):g} ns"
        )
        ax2.plot(t, lat, ".", markersize=2, color="#1f3b73")
        ax2.set_xlabel("time (s)")
        ax2.set_ylabel("lateness (µs)")
    else:
        ax1.set_title(r.reason[:110])
    buf = io.BytesIO()
    fig.savefig(buf, format=fmt)
    return buf.getvalue()


def render_html(r: LatencyReport, text: str, png: bytes) -> str:
    """A self-contained page: the text report and the figure."""
    b64 = base64.b64encode(png).decode("ascii")
    return (
        '<!DOCTYPE html><html lang="en"><head><meta charset="utf-8">'
        f"<title>wavecheck latency {html.escape(r.path)}</title></head><body>"
        f"<h1>Base-thread latency: {html.escape(r.path)}</h1><pre>{html.escape(text)}</pre>"
        f'<img alt="lateness histogram and over time" src="data:image/png;base64,{b64}">'
        "</body></html>\n"
    )


#: ``--format``: text or JSON.
FORMATS = Formats({"text": render_text, "json": render_json})


def run(args: argparse.Namespace) -> int:
    """Run ``wavecheck latency``; returns the exit code."""
    _, source = _period_ns(args)
    report = capture_latency(args, args.capture)
    out = FORMATS.render(args.format, report, source)
    if args.output:
        atomic_write(args.output, out)
    else:
        sys.stdout.write(out)
    if args.plot or args.html:
        png = render_png(report)
        if args.plot:
            fmt = figure_format(args.plot)
            atomic_write(args.plot, png if fmt == "png" else render_png(report, fmt))
        if args.html:
            atomic_write(args.html, render_html(report, render_text(report, source), png))
    return EXIT_PASS if report.established else EXIT_INDETERMINATE
