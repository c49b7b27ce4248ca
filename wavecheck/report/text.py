"""The text report: verdict, what was checked, a rule table, worst violations, max step rates.

A limit whose figure is uncertain or a firmware default carries its mark (``100 ns?``, see
:data:`~wavecheck.drives.datasheet.STATUS_MARKS`); identical violations are grouped on one line
(:mod:`wavecheck.report.groups`); the assumptions the check made close the report as notes.
"""

from __future__ import annotations

from collections.abc import Sequence
from fractions import Fraction
from typing import TYPE_CHECKING, cast

from wavecheck.drives.datasheet import MARK_LEGEND
from wavecheck.engine import Report, RuleResult
from wavecheck.report.assumptions import assumptions
from wavecheck.report.claims import outcome_line, requirement_line
from wavecheck.report.groups import ViolationGroup, group_violations
from wavecheck.rules import rule
from wavecheck.units import format_frequency, format_ns, format_rate, format_time

if TYPE_CHECKING:
    from wavecheck.firmware.capture import FirmwareCheck

__all__ = ["DEFAULT_TEXT_VIOLATIONS", "note_line", "rate_lines", "render_text"]

DEFAULT_TEXT_VIOLATIONS = 20


def note_line(note: str) -> str:
    """A capture's note as a report line: ``note: …``, or as it is when it is a warning (a
    reader's ``warning: …``, such as a sample rate no capture has)."""
    return note if note.startswith("warning: ") else f"note: {note}"


def _ns(v: Fraction | None, signed: bool = False) -> str:
    return format_ns(v, signed=signed)


def _hz(v: Fraction | None) -> str:
    return format_rate(v)


def rate_lines(report: Report) -> list[str]:
    """The max step rates: drive, observed and headroom, then (with a stepgen configuration)
    config and latency_safe with the settings they assume and their notes."""
    rates = report.rates
    by = f" ({rates.drive_limited_by})" if rates.drive_limited_by else ""
    if rates.headroom is not None:
        headroom = f"{_hz(rates.headroom)} ({rates.headroom_limited_by})"
    else:
        headroom = f"- ({rates.headroom_note})" if rates.headroom_note else "-"
    out = [
        f"max step rate: drive {_hz(rates.drive)}{by}, observed {_hz(rates.observed)}, "
        f"headroom {headroom}"
    ]
    cfg = rates.configured
    if cfg is not None:
        j = "" if cfg.latency_ns is None else f" (J = {format_time(cfg.latency_ns / 10**9)})"
        out.append(
            f"max step rate (stepgen channel {cfg.channel}, BASE_PERIOD "
            f"{format_time(Fraction(cfg.base_period_ns, 10**9))}): config {_hz(cfg.config)}, "
            f"latency_safe{j} {_hz(cfg.latency_safe)}"
        )
        out += [f"note: {n}" for n in cfg.notes]
    return out


def _at(r: RuleResult) -> str:
    t = r.min_margin_at_s
    return "-" if t is None else f"{float(t):.9f} s"


def _mark(r: RuleResult) -> str:
    return r.figure.mark if r.figure is not None else ""


def _violation_lines(report: Report, max_violations: int) -> list[str]:
    """The worst ``max_violations`` violations, identical ones grouped on one line; a group
    counts every identical violation of the capture, and spans from the first to the last."""
    total = report.total_violations
    shown = report.violations(max_violations)
    groups = group_violations(shown, report.rules)
    marks = {r.rule: _mark(r) for r in report.rules}
    head = f"violations: {total} (worst first"
    if len(groups) < len(shown):
        head += (
            f"; the {len(shown)} worst shown as {len(groups)} "
            f"group{'' if len(groups) == 1 else 's'} of identical violations, each counted over "
            "the whole capture"
        )
    out = ["", head + ")"]
    out += [_group_line(g, marks.get(g.rule, "")) for g in groups]
    told = sum(g.count for g in groups)
    if total > told:
        out.append(f"  … and {total - told} more, not identical to these")
    return out


def _group_line(g: ViolationGroup, mark: str) -> str:
    v = g.first
    if g.count == 1:
        at = f"at {float(v.time_s):.9f} s"
        what = f"{v.rule:<14} {at}"
    else:
        what = f"{g.count} × {v.rule}"
    if v.margin_ns is None:
        line = f"  {what}  {v.detail}"
    else:
        line = (
            f"  {what}  measured {_ns(v.measured_ns)}  limit {_ns(v.limit_ns)}{mark}"
            f"  margin {_ns(v.margin_ns, signed=True)}"
        )
    if g.count > 1:
        line += f"  first at {float(g.first_s):.9f} s, last at {float(g.last_s):.9f} s"
    return line


def _table(rows: list[list[str]]) -> list[str]:
    widths = [max(len(row[i]) for row in rows) for i in range(len(rows[0]))]
    return [
        "  ".join(c.ljust(w) for c, w in zip(row, widths, strict=True)).rstrip() for row in rows
    ]


def render_text(
    report: Report, max_violations: int = DEFAULT_TEXT_VIOLATIONS, require: Sequence[str] = ()
) -> str:
    """The human report; ``max_violations`` worst violations are listed, the rest counted. The
    verdict line names the rules not checked and why; with ``require`` (``--require``) the next
    line says which required rules were not decided."""
    cap = report.capture
    drive = report.drive
    out: list[str] = [f"verdict: {outcome_line(report, require)}"]
    out += [line for line in [requirement_line(report, require)] if line]
    res = "exact" if report.resolution_ns == 0 else f"T = {_ns(report.resolution_ns)}"
    rate = f"{format_frequency(cap.samplerate_hz)}, " if cap.samplerate_hz else ""
    out.append(
        f"capture: {cap.path} ({cap.format}, {rate}{res}, {format_time(cap.duration_s)}, "
        f"{len(cap.channels)} channels)"
    )
    out.append(
        f"drive:   {drive.id} — {drive.name} (steps on the {report.active_edge}"
        f"{drive.edge_mark if report.active_edge == drive.active_edge else ''} edge; {drive.path})"
    )
    mapping = ", ".join(f"{role}={ch!r}" for role, ch in report.mapping.items())
    inv = f"; inverted: {', '.join(report.inverted)}" if report.inverted else ""
    out.append(
        f"map:     {mapping}{inv}; step type {report.step_type.number} ({report.step_type.name})"
    )
    s = report.steps
    line = f"steps:   {s.count}"
    if report.step_type.kind == "step-dir" and report.interface.get("dir") is None:
        line += " (direction unknown: no DIR mapped)"
    else:
        pos = "unknown" if s.final_position is None else f"{s.final_position:+d}"
        if s.lost_from is not None:
            pos = (
                f"unknown from {format_time(report.capture.timebase.seconds(s.lost_from))} (steps "
                "inside an unknown stretch of a step line are not seen)"
            )
        line += f" (forward {s.forward}, reverse {s.reverse}"
        if s.unknown:
            line += f", unknown {s.unknown}"
        line += f"; final position {pos}"
        if report.step_type.kind == "step-dir":
            line += f"; DIR {'low' if report.forward_level == 0 else 'high'} = forward"
        line += ")"
    out.append(line)
    out.append("")
    rows = [
        ["rule", "limit", "checked", "fail", "indet", "shortest", "min margin", "at", "verdict"]
    ]
    for r in report.rules:
        rows.append(
            [
                r.rule,
                _ns(r.limit_ns) + _mark(r),
                str(r.checked),
                str(r.violations),
                str(r.indeterminate),
                _ns(r.min_measured_ns),
                _ns(r.min_margin_ns, signed=True),
                _at(r),
                r.verdict.upper() if r.verdict == "fail" else r.verdict,
            ]
        )
    out += _table(rows)
    out += [
        f"{r.rule}: limit {_ns(r.limit_ns)} applied ({r.figure.applied}); datasheet "
        f"{_ns(rule(r.rule).limit_ns(r.figure.datasheet))}"
        for r in report.rules
        if r.figure is not None and r.figure.applied and r.figure.datasheet is not None
    ]
    if any(_mark(r) for r in report.rules):
        out.append(f"{MARK_LEGEND}; `wavecheck drives {drive.id}` shows every figure's source")
    if report.not_stated:
        out.append(f"not stated by the drive (not checked): {', '.join(report.not_stated)}")
    if report.not_applicable:
        out.append(
            f"stated by the drive but not used by step type {report.step_type.number}: "
            f"{', '.join(report.not_applicable)}"
        )
    for r in report.rules:
        if r.indeterminate:
            hz = r.decide_samplerate_hz
            how = (
                f"sampling faster than {format_frequency(hz)} would decide the closest one"
                if hz is not None
                else "the closest one measured exactly the limit, so this capture cannot say how "
                "much faster a sample rate would decide it"
            )
            out.append(
                f"{r.rule}: {r.indeterminate} interval(s) indeterminate at this resolution; {how}"
            )
    out += [  # intervals touching an x/z stretch of a signal they use (checks/compile.py)
        f"{r.rule}: {r.unknown} interval(s) not judged: they touch an unknown (x/z) stretch, "
        f"the first at {format_time(r.timebase.seconds(int(r.unknown_ticks[0])))}"
        for r in report.rules
        if r.unknown
    ]
    if report.total_violations:
        out += _violation_lines(report, max_violations)
    rates, *configured = rate_lines(report)
    out += ["", rates]
    out += [note_line(n) for n in report.notes]
    out += [f"note: {a}" for a in assumptions(report)]
    out += configured
    if report.firmware is not None:  # check --firmware
        from wavecheck.report.firmware import firmware_check_lines

        out += ["", *firmware_check_lines(cast("FirmwareCheck", report.firmware))]
    return "\n".join(out) + "\n"
