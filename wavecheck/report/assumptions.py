"""What a check assumed, stated for the reader of the report (text, HTML and JSON).

A verdict is only as good as its reading of the wire: which STEP edge the drive counts, which
ENABLE level means enabled, which DIR level means forward, and how sure the drive's figures are.
Each is a default the user can override, so each report says which one it used.
"""

from __future__ import annotations

from wavecheck.drives.datasheet import STATUS_MARKS
from wavecheck.engine import Report

__all__ = ["assumptions"]

_MARKED = {"uncertain": "uncertain", "firmware-default": "firmware defaults"}


def assumptions(report: Report) -> list[str]:
    """One sentence per assumption the check of ``report`` made, in a fixed order."""
    drive = report.drive
    signals = report.interface.signals
    out: list[str] = []
    if report.active_edge != drive.active_edge:
        out.append(
            f"STEP: steps are counted on the {report.active_edge} edge (--active-edge); "
            f"{drive.id} says {drive.active_edge}."
        )
    elif drive.edge_mark:
        src = f" [{drive.edge_source}]" if drive.edge_source else ""
        note = f" ({drive.edge_note})" if drive.edge_note else ""
        out.append(
            f"STEP: the {drive.active_edge} active edge is {drive.edge_status}{src}{note}; "
            "use --active-edge if your drive counts the other one."
        )
    inverted = [role for role, sig in signals.items() if sig.inverted]
    if inverted:
        out.append(
            f"Levels are judged at the drive input: {', '.join(inverted)} inverted from the "
            "capture (--invert)."
        )
    else:
        out.append(
            "Levels are judged as captured (no --invert); a capture taken before an inverting "
            "buffer or a common-anode opto input needs --invert ROLE."
        )
    if "enable" in signals:
        if signals["enable"].inverted:
            out.append("ENABLE: active low at the capture (--invert enable).")
        else:
            out.append(
                "ENABLE: active high (the drive is enabled while the line is high); add "
                "--invert enable for an active-low enable input."
            )
    if report.step_type.kind == "step-dir" and "dir" in signals:
        level, other = ("low", "high") if report.forward_level == 0 else ("high", "low")
        out.append(
            f"DIR: {level} = forward (--dir-forward {other} for the other way); it changes the "
            "step counts and final position, not the timing verdicts."
        )
    for status, word in _MARKED.items():
        rules = [r.rule for r in report.rules if r.figure is not None and r.figure.status == status]
        if rules:
            out.append(
                f"Limits marked {STATUS_MARKS[status]} are {word} ({', '.join(rules)}): a pass "
                "against them is not a datasheet guarantee; `wavecheck drives "
                f"{drive.id}` shows their sources."
            )
    return out
