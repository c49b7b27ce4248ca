"""``wavecheck compare CAPTURE GOLDEN``: a capture against a golden trace (e.g. made by stepgen).

Both files are checked against the same drive; then compared are

- the step count, the final position and every step's direction;
- every step's time: step *i* of the capture against step *i* of the golden, after aligning both
  on their first step (``--align first-step``, the default: a logic analyzer starts at an
  arbitrary moment) or on their own time 0 (``--align none``); a step further than
  ``--tolerance`` (default 2 µs) from its golden time is a difference;
- the two rule tables: each rule's verdict, violations and smallest margin, and the change.

Verdict: **fail** when the steps differ (count, final position, a direction, a time beyond the
tolerance) or a rule is worse than in the golden (fails where the golden does not); else
**indeterminate** when a rule is indeterminate where the golden passes; else **pass**. A golden
that itself fails a rule (a golden of a bad configuration) is matched by a capture failing it
too. Exit codes as for ``check``: 0 pass, 1 fail, 3 indeterminate, 2 unusable input.

Time differences are computed in float64 ns (±0.001 ns at 10⁶ s); the largest is recomputed
exactly.
"""

from __future__ import annotations

import argparse
import json
import sys
from dataclasses import dataclass
from fractions import Fraction
from typing import Any, Literal

import numpy as np

from wavecheck.capture.open import open_capture
from wavecheck.cli._capture_args import add_capture_arguments, capture_from_args
from wavecheck.drives.library import load_drive
from wavecheck.engine import run_check
from wavecheck.errors import UsageError
from wavecheck.interface import parse_map
from wavecheck.output import atomic_write, output_file
from wavecheck.report.model import Report
from wavecheck.units import format_time, parse_time

__all__ = ["Comparison", "compare_reports", "register", "render_compare_json", "render_compare_text", "run"]

Align = Literal["first-step", "none"]
_RANK = {"pass": 0, "unchecked": 0, "indeterminate": 1, "fail": 2}


@dataclass(frozen=True)
class RuleDiff:
    """One rule in both reports (None where a report did not evaluate it)."""

    rule: str
    golden_verdict: str | None
    capture_verdict: str | None
    golden_violations: int | None
    capture_violations: int | None
    golden_margin_ns: Fraction | None
    capture_margin_ns: Fraction | None

    @property
    def delta_margin_ns(self) -> Fraction | None:
        """capture − golden smallest margin, exact ns."""
        if self.golden_margin_ns is None or self.capture_margin_ns is None:
            return None
        return self.capture_margin_ns - self.golden_margin_ns

    @property
    def change(self) -> str:
        """``"same"``, ``"worse"`` or ``"better"`` (by verdict)."""
        g = _RANK.get(self.golden_verdict or "unchecked", 0)
        c = _RANK.get(self.capture_verdict or "unchecked", 0)
        return "same" if g == c else ("worse" if c > g else "better")


@dataclass(frozen=True)
class Comparison:
    """The result of comparing a capture with a golden trace.

    Attributes:
        capture / golden: the two reports.
        align: how times were aligned.
        tolerance_ns: the allowed per-step time difference, exact ns.
        compared: steps compared (the shorter count).
        max_abs_diff_ns: the largest |Δt| over compared steps, exact ns (None: nothing compared).
        max_at_step: index of that step.
        beyond_tolerance: steps whose |Δt| exceeds the tolerance.
        mean_diff_ns: mean Δt (capture − golden), ns (float).
        direction_mismatches: steps whose known directions differ.
        rules: per-rule differences.
    """

    capture: Report
    golden: Report
    align: Align
    tolerance_ns: Fraction
    compared: int
    max_abs_diff_ns: Fraction | None
    max_at_step: int | None
    beyond_tolerance: int
    mean_diff_ns: float | None
    direction_mismatches: int
    rules: list[RuleDiff]

    @property
    def same_count(self) -> bool:
        """Both have the same number of steps."""
        return self.capture.steps.count == self.golden.steps.count

    @property
    def same_position(self) -> bool:
        """Both end at the same position (unknown positions never match)."""
        c, g = self.capture.steps.final_position, self.golden.steps.final_position
        return c is not None and c == g

    @property
    def verdict(self) -> str:
        """pass / fail / indeterminate (see the module docstring)."""
        if (
            not self.same_count
            or not self.same_position
            or self.beyond_tolerance
            or self.direction_mismatches
            or any(d.change == "worse" and d.capture_verdict == "fail" for d in self.rules)
        ):
            return "fail"
        if any(d.change == "worse" for d in self.rules):
            return "indeterminate"
        return "pass"

    @property
    def exit_code(self) -> int:
        """0 pass, 1 fail, 3 indeterminate."""
        return {"pass": 0, "fail": 1, "indeterminate": 3}[self.verdict]


def _times_ns(report: Report, align: Align) -> np.ndarray:
    ticks = report.steps.ticks
    origin = int(ticks[0]) if align == "first-step" and len(ticks) else 0
    return (ticks - origin).astype(np.float64) * float(report.capture.timebase.tick_ns)


def _exact_ns(report: Report, i: int, align: Align) -> Fraction:
    ticks = report.steps.ticks
    origin = int(ticks[0]) if align == "first-step" and len(ticks) else 0
    return report.capture.timebase.ns(int(ticks[i]) - origin)


def compare_reports(
    capture: Report, golden: Report, tolerance_ns: Fraction, align: Align = "first-step"
) -> Comparison:
    """Compare two checked reports (see the module docstring)."""
    n = min(capture.steps.count, golden.steps.count)
    max_diff = max_at = mean = None
    beyond = 0
    if n:
        d = _times_ns(capture, align)[:n] - _times_ns(golden, align)[:n]
        i = int(np.argmax(np.abs(d)))
        max_at = i
        max_diff = abs(_exact_ns(capture, i, align) - _exact_ns(golden, i, align))
        beyond = int(np.count_nonzero(np.abs(d) > float(tolerance_ns) + 1e-3))
        mean = float(d.mean())
    dc, dg = capture.steps.direction[:n], golden.steps.direction[:n]
    mismatches = int(np.count_nonzero((dc != 0) & (dg != 0) & (dc != dg)))
    ids = [r.rule for r in golden.rules] + [
        r.rule for r in capture.rules if golden.rule(r.rule) is None
    ]
    diffs = []
    for rule in ids:
        g, c = golden.rule(rule), capture.rule(rule)
        diffs.append(
            RuleDiff(
                rule,
                g.verdict if g else None,
                c.verdict if c else None,
                g.violations if g else None,
                c.violations if c else None,
                g.min_margin_ns if g else None,
                c.min_margin_ns if c else None,
            )
        )
    return Comparison(
        capture, golden, align, tolerance_ns, n, max_diff, max_at, beyond, mean, mismatches, diffs
    )


def _ns(v: Fraction | None, signed: bool = False) -> str:
    if v is None:
        return "-"
    text = format_time(v / 10**9)
    return ("+" + text) if signed and v > 0 else text


def _pos(v: int | None) -> str:
    return "unknown" if v is None else f"{v:+d}"


def render_compare_text(c: Comparison) -> str:
    """The human comparison."""
    cs, gs = c.capture.steps, c.golden.steps
    out = [
        f"verdict: {c.verdict.upper()}",
        f"capture: {c.capture.capture.path} ({cs.count} steps, final position {_pos(cs.final_position)})",
        f"golden:  {c.golden.capture.path} ({gs.count} steps, final position {_pos(gs.final_position)})",
        f"drive:   {c.capture.drive.id}",
        "",
        f"step count:     {cs.count} vs {gs.count} ({'same' if c.same_count else 'DIFFERENT'})",
        f"final position: {_pos(cs.final_position)} vs {_pos(gs.final_position)} "
        f"({'same' if c.same_position else 'DIFFERENT'})",
        f"directions:     {c.direction_mismatches} mismatch(es) in {c.compared} step(s)",
    ]
    align = "the first step" if c.align == "first-step" else "time 0 of each file"
    if c.max_abs_diff_ns is not None and c.max_at_step is not None:
        t = c.golden.capture.timebase.seconds(int(c.golden.steps.ticks[c.max_at_step]))
        out.append(
            f"step times:     aligned on {align}; max |Δt| {_ns(c.max_abs_diff_ns)} at step "
            f"{c.max_at_step} (golden t = {float(t):.9f} s); mean Δt "
            f"{format_time(Fraction(c.mean_diff_ns or 0.0) / 10**9)}; {c.beyond_tolerance} step(s) "
            f"beyond ±{_ns(c.tolerance_ns)}"
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
                _ns(d.golden_margin_ns, True),
                _ns(d.capture_margin_ns, True),
                _ns(d.delta_margin_ns, True),
                d.change.upper() if d.change == "worse" else d.change,
            ]
        )
    widths = [max(len(r[i]) for r in rows) for i in range(len(rows[0]))]
    out += ["  ".join(x.ljust(w) for x, w in zip(r, widths, strict=True)).rstrip() for r in rows]
    out.append("(verdict (violations) per rule; margin = shortest measured − limit)")
    return "\n".join(out) + "\n"


def _num(v: Fraction | int | float | None) -> float | int | None:
    if v is None:
        return None
    if isinstance(v, Fraction):
        return int(v) if v.denominator == 1 else float(v)
    return v


def render_compare_json(c: Comparison) -> str:
    """The comparison as JSON (keys: capture, golden, drive, steps, timing, rules, verdict)."""
    data: dict[str, Any] = {
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
            "tolerance_ns": _num(c.tolerance_ns),
            "compared": c.compared,
            "max_abs_diff_ns": _num(c.max_abs_diff_ns),
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
                    "min_margin_ns": _num(d.golden_margin_ns),
                },
                "capture": {
                    "verdict": d.capture_verdict,
                    "violations": d.capture_violations,
                    "min_margin_ns": _num(d.capture_margin_ns),
                },
                "delta_margin_ns": _num(d.delta_margin_ns),
                "change": d.change,
            }
            for d in c.rules
        ],
        "verdict": c.verdict,
    }
    return json.dumps(data, indent=2, ensure_ascii=False) + "\n"


def register(sub: Any) -> None:
    """Add the ``compare`` subcommand."""
    p = sub.add_parser(
        "compare",
        help="compare a capture with a golden trace (steps, times, rule tables)",
        description="Compare CAPTURE with GOLDEN (e.g. a VCD made by stepgen simulate): step "
        "count, final position, per-step time difference, and the two rule tables. Exit 0 pass, "
        "1 different or worse, 3 indeterminate, 2 unusable input.",
    )
    p.add_argument("capture", metavar="CAPTURE")
    p.add_argument("golden", metavar="GOLDEN")
    p.add_argument("--drive", required=True, metavar="ID|FILE", help="drive id or rule file")
    p.add_argument("--map", action="append", default=[], metavar="ROLE=CH", help="capture mapping")
    p.add_argument(
        "--golden-map",
        action="append",
        default=[],
        metavar="ROLE=CH",
        help="golden mapping (default: by name, e.g. stepgen's step/dir)",
    )
    p.add_argument("--invert", action="append", default=[], metavar="ROLE", help="capture role to invert")
    p.add_argument(
        "--golden-invert", action="append", default=[], metavar="ROLE", help="golden role to invert"
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
    p.add_argument("--format", choices=("text", "json"), default="text")
    p.add_argument(  # output_file: checked before any work (wavecheck.output)
        "-o", "--output", type=output_file, metavar="FILE", help="write the comparison to FILE"
    )
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Run ``wavecheck compare``; returns the exit code."""
    tol = parse_time(args.tolerance, default_unit="ns") * 10**9
    if tol < 0:
        raise UsageError(f"--tolerance must not be negative, got {args.tolerance}")
    drive = load_drive(args.drive)
    fwd = 1 if args.dir_forward == "high" else 0
    cap = run_check(
        capture_from_args(args, args.capture),
        drive,
        parse_map(args.map),
        args.invert,
        args.type,
        forward_level=fwd,
    )
    gold = run_check(
        open_capture(args.golden),
        drive,
        parse_map(args.golden_map),
        args.golden_invert,
        args.type,
        forward_level=fwd,
    )
    result = compare_reports(cap, gold, tol, args.align)
    text = render_compare_json(result) if args.format == "json" else render_compare_text(result)
    if args.output:
        atomic_write(args.output, text)
        print(f"{result.verdict}: compared with {args.golden}; written to {args.output}")
    else:
        sys.stdout.write(text)
    return result.exit_code
