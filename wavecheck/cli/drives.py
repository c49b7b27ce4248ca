"""``wavecheck drives [ID]``: list the rule library, or show one drive with every figure and source."""

from __future__ import annotations

import argparse
import sys
from fractions import Fraction
from typing import Any

from wavecheck.cli._formats import Formats, json_text
from wavecheck.drives.datasheet import MARK_LEGEND, TIME_RULES, Drive, Figure
from wavecheck.drives.library import list_drives, load_drive
from wavecheck.rules import PLAN_RULES
from wavecheck.units import format_frequency, format_time

__all__ = ["drive_json", "register", "run"]

_COLUMNS = PLAN_RULES


def register(sub: Any) -> None:
    """Add the ``drives`` subcommand."""
    p = sub.add_parser(
        "drives",
        description="List the drive rule library (rules/ and $WAVECHECK_RULES), or show one "
        "drive's figures with their status and full sources.",
    )
    p.add_argument("drive", nargs="?", metavar="ID", help="drive id or path to a .toml rule file")
    SHOW.add_argument(p)  # the same formats as LIST
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """List or show drives; returns 0 (a bad id or file raises RuleError → exit 2)."""
    if args.drive:
        sys.stdout.write(SHOW.render(args.format, load_drive(args.drive)))
    else:
        sys.stdout.write(LIST.render(args.format, list_drives()))
    return 0


def _number(value: Fraction) -> int | float:
    return int(value) if value.denominator == 1 else float(value)


def _figure_json(fig: Figure, unit: str, drive: Drive) -> dict[str, Any]:
    return {
        unit: _number(fig.value),
        "status": fig.status,
        "source": fig.source,
        "source_text": drive.sources.get(fig.source, ""),
        "note": fig.note,
    }


def drive_json(drive: Drive) -> dict[str, Any]:
    """The drive as JSON-ready data: times in ns, rates in Hz, every figure with its source."""
    return {
        "id": drive.id,
        "name": drive.name,
        "kind": drive.kind,
        "interface": drive.interface,
        "active_edge": drive.active_edge,
        "edge": {"status": drive.edge_status, "source": drive.edge_source, "note": drive.edge_note},
        "step_type": drive.step_type,
        "opto": drive.opto,
        "path": str(drive.path),
        "limits": {r: _figure_json(f, "value_ns", drive) for r, f in drive.limits.items()},
        "max_rate": _figure_json(drive.max_rate, "value_hz", drive) if drive.max_rate else None,
        "drive_rate_hz": _number(r) if (r := drive.step_rate()[0]) is not None else None,
        "complete": drive.complete,
        "notes": list(drive.notes),
        "sources": dict(drive.sources),
    }


def _us(fig: Figure | None) -> str:
    if fig is None:
        return "-"
    return f"{float(fig.value / 1000):g}{fig.mark}"


def _table(drives: list[Drive]) -> str:
    head = ("id", "name", "kind", "edge", "high", "low", "setup", "hold", "max rate")
    rows: list[tuple[str, ...]] = [head]
    for d in drives:
        rate = d.max_rate
        rate_text = "-" if rate is None else format_frequency(rate.value) + rate.mark
        edge = d.active_edge + d.edge_mark
        name = d.name if len(d.name) <= 40 else d.name[:39] + "…"
        rows.append(
            (d.id, name, d.kind, edge, *(_us(d.limits.get(r)) for r in _COLUMNS), rate_text)
        )
    widths = [max(len(r[i]) for r in rows) for i in range(len(head))]
    lines = ["  ".join(c.ljust(w) for c, w in zip(r, widths, strict=True)).rstrip() for r in rows]
    lines.append(
        f"{len(drives)} drives; times are minimums in µs at the drive input; "
        f"{MARK_LEGEND}; '-' = not stated (not checked). `wavecheck drives ID` shows sources."
    )
    return "\n".join(lines)


def _show(d: Drive) -> str:
    out = [f"{d.id}: {d.name}", f"  kind       {d.kind}", f"  interface  {d.interface}"]
    if d.step_type is not None:
        out.append(f"  step type  {d.step_type}")
    edge = f"  edge       {d.active_edge}{d.edge_mark}"
    if d.edge_status:
        edge += f"  [{d.edge_status}, {d.edge_source}]"
    if d.edge_note:
        edge += f"  {d.edge_note}"
    out.append(edge)
    if d.opto is not None:
        out.append(f"  opto       {'yes' if d.opto else 'no'}")
    out.append(f"  file       {d.path}")
    out.append("  figures (minimum times at the drive input; max_rate a maximum):")
    figures: list[tuple[str, Figure, str]] = [
        (r, d.limits[r], format_time(d.limits[r].value / 10**9))
        for r in TIME_RULES
        if r in d.limits
    ]
    if d.max_rate:
        figures.append(("max_rate", d.max_rate, format_frequency(d.max_rate.value)))
    for rule, fig, text in figures:
        line = f"    {rule:<13}{text + fig.mark:<11}{fig.status:<17}[{fig.source}]"
        out.append(line + (f"  {fig.note}" if fig.note else ""))
    missing = [r for r in _COLUMNS if r not in d.limits] + ([] if d.max_rate else ["max_rate"])
    if missing:
        out.append(f"    not stated (not checked): {', '.join(missing)}")
    rate = d.step_rate()[0]
    if rate is not None:
        out.append(f"  drive step rate limit: {format_frequency(rate)}")
    if d.notes:
        out.append("  notes:")
        out += [f"    - {n}" for n in d.notes]
    out.append("  sources:")
    out += [f"    [{k}] {v}" for k, v in d.sources.items()]
    return "\n".join(out)


def _library_json(drives: list[Drive]) -> dict[str, Any]:
    return {"drives": [drive_json(d) for d in drives]}


#: ``--format`` of one drive (``wavecheck drives ID``) and of the library: text or JSON.
SHOW = Formats({"text": lambda d: _show(d) + "\n", "json": json_text(drive_json)}, "output format")
LIST = Formats({"text": lambda ds: _table(ds) + "\n", "json": json_text(_library_json)})
