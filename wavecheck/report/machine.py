"""The outputs of a run of several axes on one capture (:class:`~wavecheck.engine.outcome.MachineReport`).

The JSON of such a run keeps ``capture`` and ``verdict`` at the top level and lists the axes::

    {"capture": {...}, "axes": [{"name", "drive", "map", "steps", "rules", "violations",
     "violations_total", "violations_listed", "violations_truncated", "max_step_rate_hz",
     "verdict", "verdict_line", "unchecked"}, ...],
     "cross_axis": {...}, "verdict", "verdict_line", "unchecked", "required", "exit_code"}

A single-axis run keeps the plain report's keys exactly (:func:`wavecheck.report.json.report_dict`).
Cross-axis facts: the step counts side by side and whether the axes' step edges lie on one common
periodic lattice (one base thread or timer: :func:`wavecheck.engine.run.common_timer`, read with
:mod:`wavecheck.lattice`).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from wavecheck.engine import MachineReport
from wavecheck.report.claims import outcome_line, requirement_line

__all__ = ["machine_dict", "render_machine_text"]


def machine_dict(
    m: MachineReport, violation_cap: int, require: Sequence[str] = ()
) -> dict[str, Any]:
    """The JSON-ready data of a several-axes run (keys in the module docstring)."""
    from wavecheck.report.json import claims_dict, report_dict

    axes = []
    capture: dict[str, Any] = {}
    for r in m.axes:
        d = report_dict(r, violation_cap, require)
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
                "violations_listed": d["violations_listed"],
                "violations_truncated": d["violations_truncated"],
                "max_step_rate_hz": d["max_step_rate_hz"],
                "verdict": d["verdict"],
                "verdict_line": d["verdict_line"],
                "unchecked": d["unchecked"],
                **({"firmware": d["firmware"]} if "firmware" in d else {}),  # check --firmware
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
        **claims_dict(m, require),
    }


def render_machine_text(m: MachineReport, max_violations: int, require: Sequence[str] = ()) -> str:
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
        f"verdict: {outcome_line(m, require)}",
        *[line for line in [requirement_line(m, require)] if line],
        f"capture: {cap.path}",
        "",
        *("  ".join(x.ljust(w) for x, w in zip(row, widths, strict=True)).rstrip() for row in rows),
    ]
    out += [f"note: {n}" for n in m.notes]
    for r in m.axes:
        out += ["", f"== axis {r.axis} ==", render_text(r, max_violations, require).rstrip("\n")]
    return "\n".join(out) + "\n"
