"""``wavecheck follow CAPTURE --command FILE [--map ROLE=CH]``: commanded motion against the
position decoded from the capture — the following error over time (max, RMS, where), steps
lost or extra at the end, and a plot (see :mod:`wavecheck.follow`).

The feedback is the capture's STEP/DIR (``--map step=…,dir=…``; up/down with ``--type 1``) or a
quadrature encoder (``--map phase-A=…,phase-B=…``, decoded as step type 2; ``--index CH`` its
index pulse). The command is ``--command FILE`` (a CSV with a header ``time_s,position`` /
``time_s,steps``, or halsampler output with ``--sample-period``), or, with an encoder mapped,
the capture's own STEP/DIR (a servo drive's step input).

Exit codes: 0 followed; 1 steps lost or extra at the end (the command at rest), an encoder
state skipped, or ``--max-error`` exceeded; 2 unusable input.
"""

from __future__ import annotations

import argparse
import io
import json
import sys
from fractions import Fraction
from typing import Any

import numpy as np

from wavecheck.capture.edges import Capture
from wavecheck.cli._capture_args import add_capture_arguments, capture_from_args
from wavecheck.cli._formats import Formats
from wavecheck.engine.planning import auto_map
from wavecheck.errors import UnitError, UsageError
from wavecheck.follow import (
    Command,
    FollowReport,
    command_from_steps,
    follow,
    positions_at,
    read_command,
)
from wavecheck.output import atomic_write, figure_file, figure_format, output_file
from wavecheck.steps.decode import StepEvents
from wavecheck.steps.decode import decode as decode_steps
from wavecheck.steps.interface import build_interface, find_channel, parse_map
from wavecheck.steptypes import step_type
from wavecheck.units import number_option, parse_option
from wavecheck.verdict import EXIT_FAIL, EXIT_PASS

__all__ = ["register", "render_json", "render_text", "run"]


def register(sub: Any) -> None:
    """Add the ``follow`` subcommand."""
    p = sub.add_parser(
        "follow",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("capture", metavar="CAPTURE", help="the capture (.sr, .vcd, ...)")
    c = p.add_argument_group("command")
    c.add_argument(
        "--command",
        metavar="FILE",
        help="commanded motion: CSV with a header (time_s|time_ms|time_us|time_ns, then the "
        "position: in counts when named steps/counts/*_steps/*_counts, else in units), or "
        "halsampler output (with --sample-period); stepgen simulate --command-out writes one",
    )
    c.add_argument(
        "--column",
        metavar="NAME|N",
        help="the position column (default: the first "
        "after time; halsampler: N, 1-based among the values, default 1)",
    )
    c.add_argument("--command-unit", choices=("counts", "units"), help="override the column's unit")
    c.add_argument(
        "--sample-period",
        metavar="TIME",
        help="halsampler: the sampler thread's "
        "period with its unit (e.g. 1ms); sample n is at n·TIME",
    )
    c.add_argument(
        "--tagged", action="store_true", help="halsampler -t: the first value is the sample number"
    )
    c.add_argument(
        "--delay",
        default="0",
        metavar="TIME",
        help="shift the command later by "
        "TIME (e.g. 1.5ms: LinuxCNC stepgen's position follower aims 1.5 servo periods "
        "behind its command)",
    )
    f = p.add_argument_group("feedback")
    f.add_argument(
        "--map",
        action="append",
        default=[],
        metavar="ROLE=CH",
        help="step=CH,dir=CH (a stepper) or phase-A=CH,phase-B=CH (an encoder); "
        "channels named after a role are taken by default",
    )
    f.add_argument(
        "--type",
        type=int,
        help="step type of the feedback (default: 2 with phase-A/B mapped, 1 with up/down, else 0)",
    )
    f.add_argument("--invert", action="append", default=[], metavar="ROLE", help="invert a role")
    f.add_argument(
        "--active-edge",
        choices=("rising", "falling", "both"),
        default="rising",
        help="STEP edge that counts a step (default rising)",
    )
    f.add_argument(
        "--forward-level",
        type=int,
        choices=(0, 1),
        default=0,
        help="DIR level meaning forward (default 0, LinuxCNC's)",
    )
    f.add_argument(
        "--index",
        metavar="CH",
        help="the encoder's index channel: counts at each "
        "rising edge (equal steps between them: no count lost)",
    )
    f.add_argument(
        "--scale",
        type=number_option,
        help="feedback counts per position unit (LinuxCNC "
        "position-scale / encoder scale); needed for a command in units",
    )
    f.add_argument(
        "--command-scale",
        type=number_option,
        help="counts per unit of a command in counts "
        "when it differs from the feedback's (a step input and an encoder)",
    )
    f.add_argument(
        "--start-position",
        type=number_option,
        metavar="COUNTS",
        help="the feedback's position at the capture's start (default: the command there, rounded)",
    )
    add_capture_arguments(p)
    o = p.add_argument_group("report")
    o.add_argument(
        "--max-error",
        type=number_option,
        metavar="COUNTS",
        help="exit 1 when |following error| exceeds this (counts)",
    )
    FORMATS.add_argument(o)
    o.add_argument("-o", "--output", type=output_file, metavar="FILE", help="write the report here")
    o.add_argument(
        "--plot",
        type=figure_file,
        metavar="FILE.png",
        help="command and feedback over time, and the error (PNG; .jpg, .svg or .pdf by the "
        "file's name)",
    )
    p.set_defaults(func=run)


def _time_s(text: str, option: str) -> Fraction:
    try:
        return parse_option(text, option, "time")
    except UnitError as err:
        raise UnitError(str(err)) from None


def _mapping(capture: Capture, args: argparse.Namespace) -> dict[str, str]:
    mapping = parse_map(args.map)
    if not mapping:
        mapping = auto_map(capture, step_type(0))
        if "step" not in mapping:
            mapping = auto_map(capture, step_type(2))
    mapping.pop("enable", None)
    return mapping


def _decode(
    capture: Capture,
    mapping: dict[str, str],
    roles: tuple[str, ...],
    number: int,
    args: argparse.Namespace,
) -> StepEvents:
    sub = {r: mapping[r] for r in roles if r in mapping}
    invert = [r for r in args.invert if r in sub or r.lower().replace("_", "-") in sub]
    iface = build_interface(capture, sub, invert)
    return decode_steps(
        iface, number, active_edge=args.active_edge, forward_level=args.forward_level
    )


def _describe(mapping: dict[str, str], roles: tuple[str, ...]) -> str:
    return ", ".join(f"{r}={mapping[r]}" for r in roles if r in mapping)


def analyse(args: argparse.Namespace) -> tuple[FollowReport, StepEvents, Command]:
    """Open the capture and the command, decode, and compute the following error."""
    delay_ns = _time_s(args.delay, "--delay") * 10**9  # option errors before any reading
    for option, value in (("--scale", args.scale), ("--command-scale", args.command_scale)):
        if value == 0:
            raise UsageError(f"{option} 0: counts per unit must not be 0")
    if args.max_error is not None and args.max_error < 0:
        raise UsageError(f"--max-error {args.max_error:g}: must be 0 or more (counts)")
    capture = capture_from_args(args, args.capture)
    tick_ns = capture.timebase.tick_ns
    mapping = _mapping(capture, args)
    encoder = "phase-A" in mapping and "phase-B" in mapping
    number = args.type if args.type is not None else 2 if encoder else 1 if "up" in mapping else 0
    st = step_type(number)
    fb_roles = st.outputs
    missing = [r for r in fb_roles if r not in mapping]
    if missing:
        raise UsageError(
            f"{capture.path}: the feedback (step type {number}) needs {', '.join(missing)} mapped "
            f"(e.g. --map {'phase-A=A,phase-B=B' if st.kind == 'phases' else 'step=STEP,dir=DIR'}; "
            f"channels: {', '.join(repr(c.name) for c in capture.channels)})"
        )
    fb = _decode(capture, mapping, fb_roles, number, args)
    kind = "encoder" if st.kind == "phases" else "STEP/DIR" if st.kind == "step-dir" else "UP/DOWN"
    fb_source = f"{kind} ({_describe(mapping, fb_roles)}; {fb.count} counts)"
    cmd_scale = args.command_scale
    if args.command:
        period = _time_s(args.sample_period, "--sample-period") if args.sample_period else None
        if period is not None and period <= 0:
            raise UsageError(f"--sample-period {args.sample_period}: must be > 0")
        command = read_command(
            args.command,
            column=args.column,
            unit=args.command_unit,
            sample_period_s=period,
            tagged=args.tagged,
        )
    elif st.kind == "phases" and ("step" in mapping or "up" in mapping):
        cmd_roles = ("step", "dir") if "step" in mapping else ("up", "down")
        events = _decode(capture, mapping, cmd_roles, 0 if "step" in mapping else 1, args)
        command = command_from_steps(
            events,
            tick_ns,
            f"{capture.path} {_describe(mapping, cmd_roles)} ({events.count} steps)",
            capture.start,
            capture.end,
        )
    else:
        raise UsageError(
            "give the command: --command FILE (CSV time_s,position or halsampler output), or map "
            "an encoder (phase-A/phase-B) as the feedback and the capture's step/dir as the command"
        )
    if command.unit == "units":
        if args.scale is None:
            raise UsageError(
                f"the command ({command.source}) is in position units: give --scale COUNTS_PER_UNIT "
                "(or --command-unit counts)"
            )
        factor = args.scale
    else:
        factor = args.scale / cmd_scale if args.scale is not None and cmd_scale else 1.0
    report = follow(
        command,
        fb.ticks,
        fb.position,
        tick_ns=tick_ns,
        capture_start=capture.start,
        capture_end=capture.end,
        factor=factor,
        delay_ns=delay_ns,
        start_position=args.start_position,
        scale=args.scale,
        feedback_source=fb_source,
    )
    report.stepper = st.kind != "phases"
    if fb.unknown:
        report.notes.append(f"{fb.unknown} feedback steps of unknown direction (counted 0)")
    if len(fb.sequence_errors):
        t = float(fb.sequence_errors[0] * tick_ns) * 1e-9
        report.notes.append(
            f"{len(fb.sequence_errors)} encoder state changes skip a state (counts lost), the "
            f"first at {t:.9g} s"
        )
    if args.index:
        ch = find_channel(capture, args.index)
        first_rising = 0 if ch.initial == 0 else 1
        at = positions_at(report, ch.edges[first_rising::2], fb.ticks, fb.position)
        report.index_counts = [float(x) for x in at]
    return report, fb, command


def _counts(r: FollowReport, x: float) -> str:
    text = f"{x:.4g} counts"
    if r.scale:
        text += f" ({x / r.scale:.6g} units)"
    return text


def failures(r: FollowReport, max_error: float | None, sequence_errors: int) -> list[str]:
    """Why the run fails (empty: it passes)."""
    out = []
    if r.stepper and not r.end_moving and r.lost_steps:
        what = "lost" if r.lost_steps > 0 else "extra"
        out.append(f"{abs(r.lost_steps)} step(s) {what} at the end")
    if max_error is not None and abs(r.max_error) > max_error:
        out.append(f"|following error| {abs(r.max_error):.4g} > --max-error {max_error:g}")
    if sequence_errors:
        out.append(f"{sequence_errors} encoder state(s) skipped")
    return out


def render_text(r: FollowReport, fails: list[str]) -> str:
    """The text report."""
    lines = [
        f"feedback: {r.feedback_source}",
        f"command:  {r.command_source}"
        + (f", delayed {r.delay_s * 1e3:.6g} ms" if r.delay_s else ""),
        f"  window {r.start_s:.9g} s … {r.end_s:.9g} s; feedback starts at {r.start_position:g}",
        f"  following error (command − feedback): max |e| {_counts(r, abs(r.max_error))} at "
        f"{r.max_at_s:.9g} s ({'command ahead' if r.max_error > 0 else 'feedback ahead'})",
        f"  RMS {_counts(r, r.rms)}, mean {_counts(r, r.mean)}",
    ]
    if r.sampled is not None:
        e, at, rms, n = r.sampled
        lines.append(
            f"  at the command's {n} samples only (a servo thread's view): max |e| "
            f"{_counts(r, abs(e))} at {at:.9g} s, RMS {_counts(r, rms)}"
        )
    if r.lag_s is not None:
        lines.append(
            f"  as a lag: error ≈ command velocity × {r.lag_s * 1e3:.4g} ms (least squares)"
        )
    end = f"  at the end ({r.end_s:.9g} s): command {r.end_command:.6g}, feedback {r.end_feedback:.6g}"
    if r.end_moving:
        end += " (the command is still moving: no lost-step count)"
    elif not r.stepper:
        end += f": residual error {_counts(r, r.end_difference)} (a servo's, not lost steps)"
    elif r.lost_steps > 0:
        end += f": {r.lost_steps} step(s) LOST"
    elif r.lost_steps < 0:
        end += f": {-r.lost_steps} EXTRA step(s)"
    else:
        end += ": no step lost or extra"
    lines.append(end)
    if r.index_counts:
        gaps = np.diff(np.asarray(r.index_counts))
        lines.append(
            f"  index: {len(r.index_counts)} pulses at counts "
            + ", ".join(f"{x:g}" for x in r.index_counts[:8])
            + (" …" if len(r.index_counts) > 8 else "")
            + (f"; counts between them {sorted({float(g) for g in gaps})[:6]}" if len(gaps) else "")
        )
    for note in r.notes:
        lines.append(f"  note: {note}")
    lines.append(f"  verdict: {'FAIL (' + '; '.join(fails) + ')' if fails else 'pass'}")
    return "\n".join(lines) + "\n"


def render_json(r: FollowReport, fails: list[str]) -> str:
    """The JSON report (positions in counts, times in seconds)."""
    doc = {
        "command": r.command_source,
        "feedback": r.feedback_source,
        "scale_counts_per_unit": r.scale,
        "delay_s": r.delay_s,
        "window_s": [r.start_s, r.end_s],
        "start_position": r.start_position,
        "following_error": {
            "max_abs": abs(r.max_error),
            "max_signed": r.max_error,
            "at_s": r.max_at_s,
            "rms": r.rms,
            "mean": r.mean,
            "lag_s": r.lag_s,
            "at_command_samples": None
            if r.sampled is None
            else {
                "max_abs": abs(r.sampled[0]),
                "max_signed": r.sampled[0],
                "at_s": r.sampled[1],
                "rms": r.sampled[2],
                "samples": r.sampled[3],
            },
        },
        "end": {
            "command": r.end_command,
            "feedback": r.end_feedback,
            "difference": r.end_difference,
            "command_moving": r.end_moving,
            "lost_steps": None if r.end_moving or not r.stepper else r.lost_steps,
        },
        "feedback_steps": r.feedback_steps,
        "index_counts": r.index_counts,
        "notes": r.notes,
        "verdict": "fail" if fails else "pass",
        "failures": fails,
    }
    return json.dumps(doc, indent=2) + "\n"


def _decimate(t: np.ndarray, *ys: np.ndarray, n: int = 4000) -> list[np.ndarray]:
    """At most about 2n points: every series' min and max per time bin (keeps spikes)."""
    if len(t) <= 2 * n:
        return [t, *ys]
    edges = np.linspace(t[0], t[-1], n + 1)
    b = np.minimum(np.searchsorted(edges, t, side="right") - 1, n - 1)
    first = np.flatnonzero(np.diff(np.concatenate([[-1], b])) != 0)
    keep = set(first.tolist())
    for y in ys:
        for red in (np.minimum, np.maximum):
            v = red.reduceat(y, first)
            for j, s in enumerate(first):
                e = first[j + 1] if j + 1 < len(first) else len(y)
                keep.add(int(s + np.flatnonzero(y[s:e] == v[j])[0]))
    idx = np.array(sorted(keep))
    return [t[idx], *(y[idx] for y in ys)]


def render_png(r: FollowReport, fmt: str = "png") -> bytes:
    """Command and feedback over time, and the following error (matplotlib, imported here),
    PNG or ``fmt``."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    from matplotlib.figure import Figure

    fig = Figure(figsize=(10, 6), dpi=100, layout="constrained")
    ax1, ax2 = fig.subplots(2, 1, sharex=True)
    t, c, fbk, e = _decimate(r.t_s, r.command, r.feedback, r.error)
    ax1.plot(t, c, lw=1, label="command", color="#1f3b73")
    ax1.step(t, fbk, where="post", lw=1, label="feedback", color="#c0392b")
    ax1.set_ylabel("position (counts)")
    ax1.legend(fontsize=8)
    ax1.set_title(
        f"following error: max {abs(r.max_error):.4g} counts at {r.max_at_s:.6g} s, RMS {r.rms:.3g}"
    )
    ax2.plot(t, e, lw=1, color="#1f3b73")
    ax2.axhline(0, color="#888", lw=0.5)
    ax2.set_ylabel("command − feedback (counts)")
    ax2.set_xlabel("time (s)")
    buf = io.BytesIO()
    fig.savefig(buf, format=fmt)
    return buf.getvalue()


#: ``--format``: text or JSON.
FORMATS = Formats({"text": render_text, "json": render_json})


def run(args: argparse.Namespace) -> int:
    """Run ``wavecheck follow``; returns the exit code."""
    report, fb, _ = analyse(args)
    fails = failures(report, args.max_error, len(fb.sequence_errors))
    out = FORMATS.render(args.format, report, fails)
    if args.output:
        atomic_write(args.output, out)
    else:
        sys.stdout.write(out)
    if args.plot:
        atomic_write(args.plot, render_png(report, figure_format(args.plot)))
    return EXIT_FAIL if fails else EXIT_PASS
