"""A run of several axes on one capture: one :class:`Report` per axis, read once, one verdict.

The JSON of such a run keeps ``capture`` and ``verdict`` at the top level and lists the axes::

    {"capture": {...}, "axes": [{"name", "drive", "map", "steps", "rules", "violations",
     "violations_total", "max_step_rate_hz", "verdict"}, ...], "cross_axis": {...}, "verdict"}

A single-axis run keeps the plain report's keys exactly (:func:`wavecheck.report.json.report_dict`).
Cross-axis facts: the step counts side by side and whether the axes' step edges lie on one common
periodic lattice (one base thread or timer: :mod:`wavecheck.lattice`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from wavecheck.capture.model import Capture
from wavecheck.report.model import Report
from wavecheck.verdict import Verdict, exit_code, overall_verdict

__all__ = ["MachineReport", "common_timer", "machine_dict", "render_machine_text"]


@dataclass
class MachineReport:
    """Every axis of one capture, checked from the same edge arrays."""

    capture: Capture
    axes: list[Report]
    notes: list[str] = field(default_factory=list)

    @property
    def verdict(self) -> Verdict:
        """The worst verdict of the axes."""
        return overall_verdict(r.verdict for r in self.axes)

    @property
    def exit_code(self) -> int:
        """0 pass, 1 an axis failed, 3 only indeterminate or unchecked."""
        return exit_code(self.verdict)

    @property
    def total_violations(self) -> int:
        """Violations over every axis."""
        return sum(r.total_violations for r in self.axes)

    def axis(self, name: str) -> Report:
        """The report of axis ``name`` (KeyError when there is none)."""
        for r in self.axes:
            if r.axis == name:
                return r
        raise KeyError(name)


#: Step times the common-timer note reads: the first of the axes' steps merged (a bound on its
#: cost; a thread or timer that makes them all shows in any stretch of them).
TIMER_TICKS = 1 << 14
#: Fewest step times from which the note tells anything.
TIMER_MIN = 64


def common_timer(reports: list[Report]) -> str:
    """One line: do the axes' steps lie on one common periodic lattice (one thread or timer)?

    Read from the axes' step ticks (the first :data:`TIMER_TICKS` step times of them all) by
    :func:`wavecheck.lattice.common_period`."""
    from wavecheck.lattice import common_period
    from wavecheck.linuxcnc.worstcase import union

    cap = reports[0].capture
    ticks = [r.events().ticks for r in reports if r.steps.count]
    if len(ticks) < 2:
        return "fewer than two axes step: no common timer to look for"
    times = union(*ticks)
    if len(times) < TIMER_MIN:
        return (
            f"too few steps ({len(times)} step times) to tell whether one common periodic "
            "lattice (one thread or timer) makes them"
        )
    sample = times[:TIMER_TICKS]
    period, why = common_period(sample, cap.timebase.tick_ns, reports[0].resolution_ns)
    bound = f" (from the first {len(sample)} step times)" if len(sample) < len(times) else ""
    if period is not None:
        return (
            f"the steps of every axis lie on one common periodic lattice{bound}: one base "
            f"thread or timer makes them (its period {float(period) / 1000:.6g} us or a whole "
            "fraction of it)"
        )
    return f"the axes' steps are not on one common periodic lattice ({why}){bound}"


def machine_dict(m: MachineReport, violation_cap: int) -> dict[str, Any]:
    """The JSON-ready data of a several-axes run (keys in the module docstring)."""
    from wavecheck.report.json import report_dict

    axes = []
    capture: dict[str, Any] = {}
    for r in m.axes:
        d = report_dict(r, violation_cap)
        capture = capture or {
            k: v for k, v in d["capture"].items() if k not in ("mapping", "inverted")
        }
        axes.append(
            {
                "name": r.axis,
                "drive": d["drive"],
                "map": r.mapping,
                "inverted": list(r.inverted),
                "steps": d["steps"],
                "rules": d["rules"],
                "violations": d["violations"],
                "violations_total": d["violations_total"],
                "max_step_rate_hz": d["max_step_rate_hz"],
                "verdict": d["verdict"],
            }
        )
    for c in capture.get("channels", []):
        c["role"] = next(
            (
                f"{r.axis}.{role}"
                for r in m.axes
                for role, ch in r.mapping.items()
                if ch == c["name"]
            ),
            None,
        )
    return {
        "capture": capture,
        "axes": axes,
        "cross_axis": {
            "steps": {str(r.axis): r.steps.count for r in m.axes},
            "final_position": {str(r.axis): r.steps.final_position for r in m.axes},
            "notes": list(m.notes),
        },
        "verdict": m.verdict,
    }


def render_machine_text(m: MachineReport, max_violations: int) -> str:
    """A summary of every axis side by side, then each axis's own text report."""
    from wavecheck.report.text import render_text

    cap = m.capture
    rows = [["axis", "drive", "steps", "final position", "violations", "verdict"]]
    for r in m.axes:
        pos = r.steps.final_position
        rows.append(
            [
                str(r.axis),
                r.drive.id,
                str(r.steps.count),
                "unknown" if pos is None else f"{pos:+d}",
                str(r.total_violations),
                r.verdict.upper() if r.verdict == "fail" else r.verdict,
            ]
        )
    widths = [max(len(row[i]) for row in rows) for i in range(len(rows[0]))]
    out = [
        f"verdict: {m.verdict.upper()} ({len(m.axes)} axes)",
        f"capture: {cap.path}",
        "",
        *("  ".join(x.ljust(w) for x, w in zip(row, widths, strict=True)).rstrip() for row in rows),
    ]
    out += [f"note: {n}" for n in m.notes]
    for r in m.axes:
        out += ["", f"== axis {r.axis} ==", render_text(r, max_violations).rstrip("\n")]
    return "\n".join(out) + "\n"
