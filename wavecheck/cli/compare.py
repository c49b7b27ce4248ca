"""``wavecheck compare CAPTURE GOLDEN``: a capture against a golden trace (e.g. made by stepgen).

What is compared and how the verdict is reached: :mod:`wavecheck.compare`. Exit codes as for
``check``: 0 pass, 1 fail, 3 indeterminate, 2 unusable input.

Several axes: ``--map x.step=5,x.dir=6 --map y.step=3,y.dir=4`` for the capture and
``--golden-map x.step=…`` for the golden (default: the capture's axes, channel for channel);
each capture axis is compared with the golden axis of the same name, ``--drive x=ID`` gives one
axis its own drive and ``--invert x.step`` inverts one axis's role, as in ``check``. The text has
a section per axis; the JSON is ``{"capture", "golden", "axes": [{"name", …one comparison…}],
"failures", "said", "verdict"}`` (``said``: the verdict line's words, what was compared and
found: the failures, or "matches the golden trace …" and the rules both fail). One unnamed axis keeps the output above exactly.

Time differences are computed in float64 ns (±0.001 ns at 10⁶ s); the largest is recomputed
exactly.
"""

from __future__ import annotations

import argparse
import sys
from fractions import Fraction
from typing import Any

from wavecheck.capture.open import open_capture
from wavecheck.cli._capture_args import add_capture_arguments, capture_from_args
from wavecheck.cli._formats import Formats, json_text
from wavecheck.compare import Comparison, MachineComparison, compare_axes
from wavecheck.drives.datasheet import Drive
from wavecheck.drives.library import load_drive
from wavecheck.errors import UsageError
from wavecheck.output import atomic_write, output_file
from wavecheck.steps.mapping import AxisMap, parse_axes, per_axis, split_invert
from wavecheck.units import format_ns, format_time, json_number, option_ns
from wavecheck.verdict import exit_code

__all__ = [
    "FORMATS",
    "compare_doc",
    "register",
    "render_compare_json",
    "render_compare_text",
    "run",
]


def _pos(v: int | None) -> str:
    return "unknown" if v is None else f"{v:+d}"


def render_compare_text(c: Comparison | MachineComparison) -> str:
    """The human comparison (a section per axis when there are named axes)."""
    if isinstance(c, MachineComparison):
        if not c.several:
            return render_compare_text(c.axes[0])
        first = c.axes[0]
        out = [
            f"verdict: {c.verdict.upper()} ({len(c.axes)} axes; {'; '.join(c.said())})",
            f"capture: {first.capture.capture.path}",
            f"golden:  {first.golden.capture.path}",
        ]
        for a in c.axes:
            out += ["", f"== axis {a.capture.axis} ==", render_compare_text(a).rstrip("\n")]
        return "\n".join(out) + "\n"
    cs, gs = c.capture.steps, c.golden.steps
    out = [
        f"verdict: {c.verdict.upper()} ({'; '.join(c.said())})",
        f"capture: {c.capture.capture.path} ({cs.count} steps, final position {_pos(cs.final_position)})",
        f"golden:  {c.golden.capture.path} ({gs.count} steps, final position {_pos(gs.final_position)})",
        f"drive:   {c.capture.drive.id}",
        "",
        f"step count:     {cs.count} vs {gs.count} ({'same' if c.same_count else 'DIFFERENT'})",
        f"final position: {_pos(cs.final_position)} vs {_pos(gs.final_position)} "
        f"({ {'same': 'same', 'different': 'DIFFERENT', 'unknown': 'no DIR on either: not compared'}[c.position] })",
        f"directions:     {c.direction_mismatches} mismatch(es) in {c.compared} step(s)",
    ]
    align = "the first step" if c.align == "first-step" else "time 0 of each file"
    if c.max_abs_diff_ns is not None and c.max_at_step is not None:
        t = c.golden.capture.timebase.seconds(int(c.golden_steps.ticks[c.max_at_step]))
        out.append(
            f"step times:     aligned on {align}; max |Δt| {format_ns(c.max_abs_diff_ns)} at step "
            f"{c.max_at_step} (golden t = {float(t):.9f} s); mean Δt "
            f"{format_time(Fraction(c.mean_diff_ns or 0.0) / 10**9)}; {c.beyond_tolerance} step(s) "
            f"beyond ±{format_ns(c.tolerance_ns)}"
        )
    else:
        out.append("step times:     no step to compare")
    out.append("")
    rows = [["rule", "golden", "capture", "golden margin", "capture margin", "Δ margin", "change"]]
    for d in c.rules:
        rows.append(
            [
                d.rule,
                f"{d.golden_verdict or '-'} ({d.golden_violations if d.golden_violations is not None else '-'})",
                f"{d.capture_verdict or '-'} ({d.capture_violations if d.capture_violations is not None else '-'})",
                format_ns(d.golden_margin_ns, signed=True),
                format_ns(d.capture_margin_ns, signed=True),
                format_ns(d.delta_margin_ns, signed=True),
                d.change.upper() if d.change == "worse" else d.change,
            ]
        )
    widths = [max(len(r[i]) for r in rows) for i in range(len(rows[0]))]
    out += ["  ".join(x.ljust(w) for x, w in zip(r, widths, strict=True)).rstrip() for r in rows]
    out.append("(verdict (violations) per rule; margin = shortest measured − limit)")
    return "\n".join(out) + "\n"


def compare_doc(c: Comparison | MachineComparison) -> dict[str, Any]:
    """The comparison as JSON (keys: capture, golden, drive, steps, timing, rules, failures,
    verdict; named axes: capture, golden, axes, failures, verdict)."""
    if isinstance(c, MachineComparison) and c.several:
        first = c.axes[0]
        data: dict[str, Any] = {
            "capture": first.capture.capture.path,
            "golden": first.golden.capture.path,
            "axes": [{"name": a.capture.axis, **_compare_dict(a)} for a in c.axes],
            "failures": c.failures(),
            "said": c.said(),
            "verdict": c.verdict,
        }
    else:
        data = _compare_dict(c.axes[0] if isinstance(c, MachineComparison) else c)
    return data


render_compare_json = json_text(compare_doc)
#: ``--format``: text or JSON.
FORMATS = Formats({"text": render_compare_text, "json": render_compare_json})


def _compare_dict(c: Comparison) -> dict[str, Any]:
    """One comparison's JSON data."""
    return {
        "capture": c.capture.capture.path,
        "golden": c.golden.capture.path,
        "drive": c.capture.drive.id,
        "steps": {
            "count": {"capture": c.capture.steps.count, "golden": c.golden.steps.count},
            "final_position": {
                "capture": c.capture.steps.final_position,
                "golden": c.golden.steps.final_position,
            },
            "same_count": c.same_count,
            "same_position": c.same_position,
            "direction_mismatches": c.direction_mismatches,
        },
        "timing": {
            "align": c.align,
            "tolerance_ns": json_number(c.tolerance_ns),
            "compared": c.compared,
            "max_abs_diff_ns": json_number(c.max_abs_diff_ns),
            "max_at_step": c.max_at_step,
            "mean_diff_ns": c.mean_diff_ns,
            "beyond_tolerance": c.beyond_tolerance,
        },
        "rules": [
            {
                "id": d.rule,
                "golden": {
                    "verdict": d.golden_verdict,
                    "violations": d.golden_violations,
                    "min_margin_ns": json_number(d.golden_margin_ns),
                },
                "capture": {
                    "verdict": d.capture_verdict,
                    "violations": d.capture_violations,
                    "min_margin_ns": json_number(d.capture_margin_ns),
                },
                "delta_margin_ns": json_number(d.delta_margin_ns),
                "change": d.change,
            }
            for d in c.rules
        ],
        "failures": c.failures(),
        "said": c.said(),
        "verdict": c.verdict,
    }


def register(sub: Any) -> None:
    """Add the ``compare`` subcommand."""
    p = sub.add_parser(
        "compare",
        description="Compare CAPTURE with GOLDEN (e.g. a VCD made by stepgen simulate): step "
        "count, final position, per-step time difference, and the two rule tables. Exit 0 pass, "
        "1 different or worse, 3 indeterminate, 2 unusable input.",
    )
    p.add_argument("capture", metavar="CAPTURE")
    p.add_argument("golden", metavar="GOLDEN")
    p.add_argument(
        "--drive",
        action="append",
        required=True,
        metavar="ID|FILE|AXIS=ID",
        help="drive id or rule file; AXIS=ID gives one axis its own drive (repeatable)",
    )
    p.add_argument(
        "--map",
        action="append",
        default=[],
        metavar="[AXIS.]ROLE=CH",
        help="capture mapping; several axes: --map x.step=5,x.dir=6 --map y.step=3,y.dir=4",
    )
    p.add_argument(
        "--golden-map",
        action="append",
        default=[],
        metavar="[AXIS.]ROLE=CH",
        help="golden mapping (default: by name, e.g. stepgen's step/dir; with several axes the "
        "capture's --map)",
    )
    p.add_argument(
        "--invert",
        action="append",
        default=[],
        metavar="[AXIS.]ROLE",
        help="capture role to invert (x.step: one axis)",
    )
    p.add_argument(
        "--golden-invert",
        action="append",
        default=[],
        metavar="[AXIS.]ROLE",
        help="golden role to invert (x.step: one axis)",
    )
    p.add_argument("--type", type=int, default=None, metavar="N", help="LinuxCNC step type")
    p.add_argument(
        "--dir-forward", choices=("low", "high"), default="low", help="DIR level meaning forward"
    )
    p.add_argument(
        "--tolerance", default="2us", metavar="TIME", help="allowed per-step time difference (2us)"
    )
    p.add_argument(
        "--align",
        choices=("first-step", "none"),
        default="first-step",
        help="align times on each file's first step (default) or on each file's time 0",
    )
    add_capture_arguments(p)
    FORMATS.add_argument(p)
    p.add_argument(  # output_file: checked before any work (wavecheck.output)
        "-o", "--output", type=output_file, metavar="FILE", help="write the comparison to FILE"
    )
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Run ``wavecheck compare``; returns the exit code."""
    tol = option_ns(args.tolerance, "--tolerance")
    if tol < 0:
        raise UsageError(f"--tolerance must not be negative, got {args.tolerance}")
    axes = parse_axes(args.map)
    names = [a.name for a in axes]
    if args.golden_map:
        golden_axes = parse_axes(args.golden_map, "--golden-map")
    elif names == [None]:
        golden_axes = [AxisMap(None, {})]  # by name, as stepgen writes step/dir
    else:
        golden_axes = [AxisMap(a.name, dict(a.roles)) for a in axes]
    drives = per_axis(args.drive, "--drive", names)
    loaded: dict[str, Drive] = {}
    for name in names:
        if name not in drives:
            raise UsageError(f"--drive: axis {name} has no drive (add --drive {name}=ID)")
        if drives[name] not in loaded:
            loaded[drives[name]] = load_drive(drives[name])
    golden_names = [a.name for a in golden_axes]
    result = compare_axes(
        capture_from_args(args, args.capture),
        open_capture(args.golden),
        axes,
        golden_axes,
        {name: loaded[drives[name]] for name in names},
        tol,
        args.align,
        capture_invert=split_invert(args.invert, names),
        golden_invert=split_invert(args.golden_invert, golden_names),
        step_type=args.type,
        forward_level=1 if args.dir_forward == "high" else 0,
    )
    text = FORMATS.render(args.format, result)
    if args.output:
        atomic_write(args.output, text)
        print(f"{result.verdict}: compared with {args.golden}; written to {args.output}")
    else:
        sys.stdout.write(text)
    return exit_code(result.verdict)
