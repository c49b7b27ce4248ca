"""``wavecheck info CAPTURE``: format, sample rate / timescale, resolution, duration, channels.

JSON keys (a contract): ``format``, ``samplerate_hz`` (null for a VCD without one),
``resolution_ns``, ``duration_s``, ``channels`` [{name, index, initial, edges, rising, falling}];
also ``path``, ``tick_ns``, ``notes``, ``samples`` (the window in ticks) and ``time_known``.

A capture that states no sample rate (a ``.sr`` without one, and no ``--samplerate``) is still
listed: channels and edge counts in samples, with ``tick_ns``, ``resolution_ns`` and
``duration_s`` null and a note that times need ``--samplerate``.

``roles`` is the channel roles proposed from the waveforms (:func:`wavecheck.roles.propose`): the
axes with each role's channel and the evidence that decided it, shared lines, unassigned channels
with why, the ambiguities, and the ``--map`` line to copy (``map_args``).
"""

from __future__ import annotations

import argparse
import sys
from fractions import Fraction
from typing import TYPE_CHECKING, Any

from wavecheck.capture.edges import Capture
from wavecheck.cli._capture_args import (
    add_capture_arguments,
    capture_from_args,
    resolution_from_args,
)
from wavecheck.cli._formats import Formats, json_text
from wavecheck.engine.planning import resolve_resolution_ns
from wavecheck.report.text import note_line
from wavecheck.units import format_frequency, format_time, json_number

if TYPE_CHECKING:  # imported where used: the roles load numpy
    from wavecheck.roles import Proposal

__all__ = ["info_dict", "info_text", "register", "run"]


def register(sub: Any) -> None:
    p = sub.add_parser(
        "info",
        description="Show a capture's format, sample rate or timescale, resolution, duration, "
        "and per channel its name, initial level and number of edges.",
    )
    p.add_argument("capture", metavar="CAPTURE", help=".sr, VCD, or any sigrok-cli input format")
    FORMATS.add_argument(p)
    add_capture_arguments(p)
    p.set_defaults(func=run)


def info_dict(cap: Capture, resolution_ns: Fraction | None = None) -> dict[str, Any]:
    """The JSON form of ``wavecheck info`` (``resolution_ns``: the ``--resolution`` check would
    use, exact; default the capture's own)."""
    timed = cap.time_known
    res_ns = cap.resolution_ns if resolution_ns is None else resolution_ns
    return {
        "path": cap.path,
        "format": cap.format,
        "samplerate_hz": None if cap.samplerate_hz is None else json_number(cap.samplerate_hz),
        "tick_ns": json_number(cap.timebase.tick_ns) if timed else None,
        "resolution_ns": json_number(res_ns) if timed else None,
        "duration_s": float(cap.duration_s) if timed else None,
        "samples": cap.end - cap.start,
        "time_known": timed,
        "channels": [
            {
                "name": ch.name,
                "index": ch.index,
                "initial": None if ch.never_known else ch.initial,
                "edges": int(len(ch.edges)),
                "rising": ch.rising,
                "falling": ch.falling,
            }
            for ch in cap.channels
        ],
        "notes": list(cap.notes),
    }


def info_text(cap: Capture, resolution_ns: Fraction | None = None) -> str:
    """The text form of ``wavecheck info`` (``resolution_ns`` as for :func:`info_dict`)."""
    rate = "none stated" if cap.samplerate_hz is None else format_frequency(cap.samplerate_hz)
    res_ns = cap.resolution_ns if resolution_ns is None else resolution_ns
    res = "exact (0)" if res_ns == 0 else format_time(res_ns / 10**9)
    if cap.time_known:
        timing = [
            f"tick        {format_time(cap.timebase.tick_s)}"
            + (" (timescale)" if cap.format == "vcd" else ""),
            f"resolution  {res}",
            f"duration    {format_time(cap.duration_s)} ({cap.end - cap.start} ticks)",
        ]
    else:
        rate += " (times need --samplerate)"
        timing = [
            "tick        1 sample",
            "resolution  1 sample",
            f"duration    {cap.end - cap.start} samples",
        ]
    lines = [
        f"capture     {cap.path}",
        f"format      {cap.format}",
        f"sample rate {rate}",
        *timing,
        "",
    ]
    width = max([len("name")] + [len(ch.name) for ch in cap.channels])
    lines.append(
        f"{'index':>5}  {'name':<{width}}  initial  {'edges':>9}  {'rising':>9}  {'falling':>9}"
    )
    for ch in cap.channels:
        extra = ""
        if ch.never_known:
            extra += "  unknown (x/z) throughout"
        elif ch.known_from > cap.start:
            extra += f"  known from {format_time(cap.timebase.seconds(ch.known_from))}"
        if len(ch.xz_times):
            extra += f"  x/z {len(ch.xz_times)} times"
        lines.append(
            f"{ch.index:>5}  {ch.name:<{width}}  {'x' if ch.never_known else ch.initial:>7}  "
            f"{len(ch.edges):>9}  "
            f"{ch.rising:>9}  {ch.falling:>9}{extra}"
        )
    if not cap.channels:
        lines.append("(no 1-bit channels)")
    if cap.notes:
        lines.append("")
        lines += [note_line(n) for n in cap.notes]
    return "\n".join(lines)


def run(args: argparse.Namespace) -> int:
    """Run ``wavecheck info``: the capture, then the roles its waveforms suggest."""
    from wavecheck.roles import propose

    cap = capture_from_args(args, args.capture, require_time=False, resolution=False)
    seconds = resolution_from_args(args)  # kept exact, as check keeps it
    res_ns = None if seconds is None else resolve_resolution_ns(cap, seconds)[0]
    proposal = propose(cap) if cap.time_known else None
    sys.stdout.write(FORMATS.render(args.format, cap, res_ns, proposal))
    return 0


def _info_doc(cap: Capture, res_ns: Fraction | None, proposal: Proposal | None) -> dict[str, Any]:
    data = info_dict(cap, res_ns)
    if proposal is not None:
        data["roles"] = {**proposal.as_dict(), "map_args": proposal.map_args()}
    return data


def _info_text(cap: Capture, res_ns: Fraction | None, proposal: Proposal | None) -> str:
    text = info_text(cap, res_ns) + "\n"
    if proposal is None:
        return text
    head = (
        "roles (channels named after their roles, as check maps them without --map; "
        "what the waveforms say of them):"
        if proposal.named
        else "proposed roles (from the waveforms; names only help):"
    )
    return f"{text}\n{head}\n{proposal.text().rstrip(chr(10))}\n"


#: ``--format``: text or JSON.
FORMATS = Formats({"text": _info_text, "json": json_text(_info_doc)}, "output format")
