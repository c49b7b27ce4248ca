"""A GTKWave save file that opens the capture at its worst violations.

``gtkwave FILE.gtkw`` then shows the mapped signals (named after their roles, inverted roles
drawn inverted so levels are the drive's input levels) with the primary marker on the worst
violation and the named markers ``A``…``Z`` on the next ones (GTKWave has one primary marker and
26 named ones). With no violation, the markers go to each rule's smallest margin. A comment line
per marker says which violation it is.

The dump file: a VCD capture is opened as it is (signals by their hierarchical names). Any
other capture (``.sr``, sigrok-cli formats) is written as a VCD beside the save file
(``FILE.vcd`` for ``FILE.gtkw``; :func:`companion_vcd`: a file of that name that is not an
earlier companion of the same save file is never replaced, the first free ``FILE-2.vcd``,
``FILE-3.vcd`` … is taken) with :func:`wavecheck.capture.vcd.writer.write_vcd`: the mapped
channels only, raw (not inverted), on the largest VCD timescale that holds every edge exactly.
A check keeps only small windows of the signals around the worst places
(:mod:`wavecheck.engine.windows`): the VCD then holds those windows, the level held between them,
and a comment in both files says so. A VCD capture needs no windows.

Marker times are in the dump's time unit (a ``$timescale`` of ``10 ns`` counts in ns, ``1 fs``
in fs), as GTKWave reads them. Markers go to distinct times: a place whose time is already marked
is skipped and the next one taken.

The view (measured through the Tcl interface of Debian's GTKWave 3.3): GTKWave draws
``2 ** -zoom`` time units per 200 pixels of its wave area, starting at ``[timestart]`` (rounded
down to a power of ten below one pixel), and opens at time 0 instead when the window would run
past the dump's last time. The save file sets the window ``[size]``, the signal pane width and a
collapsed signal search tree, so the wave area is :data:`WAVE_PIXELS` wide; the zoom and start put
the worst violation's interval (both edges) in the middle third of that window, the primary marker
on its first edge. A narrower wave area (another theme, a window manager that shrinks the window)
cuts the right side first.
"""

from __future__ import annotations

import io
import math
import os
import re
from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from wavecheck.capture.vcd.header import open_vcd, read_header
from wavecheck.capture.vcd.writer import VcdWire, write_vcd
from wavecheck.engine import Report
from wavecheck.errors import UsageError
from wavecheck.output import atomic_write
from wavecheck.report.plot import Place, choose_places
from wavecheck.units import SI_TIME, format_time

if TYPE_CHECKING:
    import numpy.typing as npt

__all__ = [
    "MAX_MARKERS",
    "WAVE_PIXELS",
    "WINDOW_SIZE",
    "View",
    "companion_vcd",
    "render_gtkw",
    "vcd_timescale",
    "view_of",
    "write_gtkw",
    "write_vcd_of",
]

#: Named markers A..Z plus the primary one.
MAX_MARKERS = 27
#: The window the save file asks for (pixels) and the width of its signal pane.
WINDOW_SIZE = (1200, 600)
SIGNALS_WIDTH = 220
#: Width of the wave area GTKWave 3.3 (Debian) draws in that window with the search tree collapsed.
WAVE_PIXELS = 916
_PIXELS_PER_FRAME = 200  # GTKWave shows 2 ** -zoom time units per 200 pixels
_UNITS = SI_TIME[:5]  # s down to ps: GTKWave's save files take no finer unit here


def vcd_timescale(tick_s: Fraction) -> tuple[int, str, Fraction]:
    """A VCD timescale ``(magnitude, unit)`` for a capture tick, and timescale steps per tick.

    The coarsest timescale (down to 1 ps) on which a tick is a whole number of steps; a tick that
    is not a whole number of picoseconds (24 MHz: 41.666… ns) gets 1 ps and steps per tick that
    are not whole — edges are then rounded to the nearest ps (the file is for viewing only).
    """
    for unit, exp in _UNITS:
        for magnitude in (100, 10, 1):
            steps = tick_s / (Fraction(magnitude) * Fraction(10) ** exp)
            if steps.denominator == 1:
                return magnitude, unit, steps
    return 1, "ps", tick_s * 10**12


def _round(ticks: int, steps_per_tick: Fraction) -> int:
    """Timescale steps of a tick count (nearest, halves up)."""
    num = ticks * steps_per_tick.numerator
    return (2 * num + steps_per_tick.denominator) // (2 * steps_per_tick.denominator)


def _vcd_header_names(path: str) -> tuple[dict[str, str], int]:
    """Name → hierarchical name of each var of a VCD (by its reference or its full name, when
    that is unique), and the magnitude of its timescale (``10`` for ``10 ns``; 1 when none)."""
    with open_vcd(path) as f:
        header, _ = read_header(path, f)
    full: dict[str, list[str]] = {}
    for var in header.vars:
        name = var.full_name
        full.setdefault(var.reference, []).append(name)
        full.setdefault(name, []).append(name)
    magnitude = int(header.timescale_text.split()[0]) if header.timescale_text else 1
    return {k: v[0] for k, v in full.items() if len(v) == 1}, magnitude


def _trace_names(names: dict[str, str], report: Report) -> dict[str, str]:
    """Role → the name GTKWave knows the signal by, in the capture's own VCD."""
    out: dict[str, str] = {}
    for role, sig in report.interface.signals.items():
        ch = sig.channel
        base = re.sub(r"#\d+$", "", ch)
        out[role] = names.get(ch) or names.get(base) or ch
    return out


def _round_all(ticks: npt.NDArray[np.int64], steps_per_tick: Fraction) -> npt.NDArray[np.int64]:
    """:func:`_round` of every element (exact: Python integers when int64 could overflow)."""
    num, den = steps_per_tick.numerator, steps_per_tick.denominator
    big = int(np.abs(ticks).max(initial=0)) * num * 2 + den >= 2**62
    t = ticks.astype(object) if big else ticks.astype(np.int64)
    return np.asarray((2 * t * num + den) // (2 * den), dtype=np.int64)


def _companion_mark(save: Path) -> str:
    """What the ``$comment`` of the VCD written for the save file ``save`` begins with."""
    return f"wavecheck: companion of {save.name}:"


def _same_path(a: Path, b: Path) -> bool:
    """True when ``a`` and ``b`` name one file (by name, or the same file when both exist)."""
    if os.path.abspath(a) == os.path.abspath(b) or a.resolve() == b.resolve():
        return True
    try:
        return os.path.samefile(a, b)
    except OSError:
        return False


def companion_vcd(save: str | os.PathLike[str]) -> Path:
    """Where the VCD of the save file ``save`` (``FILE.gtkw``) goes: ``FILE.vcd`` when it does
    not exist or is the companion wavecheck wrote for this same save file before; else the
    first free ``FILE-2.vcd``, ``FILE-3.vcd`` … A file wavecheck did not write (a capture, a
    symbolic link to one) is never replaced, and the save file itself is never its companion
    (``--gtkw FILE.vcd`` gets ``FILE-2.vcd``)."""
    save = Path(save)
    mark = _companion_mark(save).encode()
    for k in range(1, 10_000):
        candidate = save.with_name(f"{save.stem}{'' if k == 1 else f'-{k}'}.vcd")
        if _same_path(candidate, save):  # --gtkw FILE.vcd: the save file is not its companion
            continue
        if not os.path.lexists(candidate):
            return candidate
        try:
            if candidate.is_symlink() or not candidate.is_file():
                continue
            with open(candidate, "rb") as f:
                if mark in f.read(4096):
                    return candidate
        except OSError:
            continue
    raise UsageError(f"{save}: no free name for its companion VCD beside it")


def write_vcd_of(
    report: Report, path: str | os.PathLike[str], comment: str = ""
) -> tuple[int, str, Fraction]:
    """Write the mapped channels of ``report``'s capture as a VCD (raw levels), atomically.

    Variables are named after the roles (``step``, ``dir``, ``phase_A`` …) in scope
    ``wavecheck``. Only the windows kept around the worst places are written
    (:mod:`wavecheck.engine.windows`; the header comment says so). Returns the timescale used and
    the ticks → timescale-steps factor.
    """
    cap = report.capture
    magnitude, unit, factor = vcd_timescale(cap.timebase.tick_s)
    signals = report.traces
    channels = ", ".join(f"{role}={sig.channel!r}" for role, sig in signals.items())
    windows = "" if report.windows is None else f"; {report.windows.note}"
    write_vcd(
        path,
        [
            VcdWire(
                role.replace("-", "_"),
                sig.initial ^ int(sig.inverted),
                _round_all(np.asarray(sig.edges, dtype=np.int64) - cap.start, factor),
            )
            for role, sig in signals.items()
        ],
        timescale=f"{magnitude} {unit}",
        end=_round(cap.end - cap.start, factor),
        scope="wavecheck",
        comment=f"{comment}wavecheck: mapped channels of {cap.path} ({channels}); raw "
        f"levels{windows}",
        version="wavecheck",
    )
    return magnitude, unit, factor


def _zoom(window_units: Fraction, pixels: int = WAVE_PIXELS) -> float:
    """GTKWave's zoom that shows ``window_units`` (> 0) of the dump's time unit across ``pixels``."""
    return -math.log2(window_units * _PIXELS_PER_FRAME / pixels)


@dataclass(frozen=True)
class View:
    """What GTKWave opens at: ``start`` (``[timestart]``) and ``window`` (the time across
    :data:`WAVE_PIXELS`), both in the dump's time unit, and the save file's ``zoom``."""

    start: int
    window: Fraction

    @property
    def zoom(self) -> float:
        return _zoom(self.window)


def view_of(first: int, last: int, t_min: int, t_max: int) -> View:
    """The view of the interval ``[first, last]`` in a dump spanning ``[t_min, t_max]`` (dump units).

    The interval fills the middle third of the window (its length again as context each side;
    a zero-length interval counts as 1 unit). GTKWave opens at time 0 when ``start + window``
    exceeds ``t_max``, so near the dump's end the window must stay inside it even for the widest
    wave area the window can hold (``WINDOW_SIZE[0]`` pixels): the window is then narrowed while
    some context after ``last`` remains, and at the very end fits the planned wave area exactly.
    """
    length = max(last - first, 1)
    start = max(first - length, t_min)
    window = Fraction(3 * length)
    widest = Fraction(WINDOW_SIZE[0], WAVE_PIXELS)
    if start + widest * window > t_max:
        narrowed = (t_max - start) / widest
        window = (
            narrowed if start + narrowed >= last + Fraction(length, 4) else Fraction(t_max - start)
        )
    return View(start, max(window, Fraction(1)))


def _distinct(places: list[Place], times: list[int], n: int) -> list[tuple[Place, int]]:
    """The first ``n`` places whose marker times differ (a repeated time takes the next place)."""
    out: list[tuple[Place, int]] = []
    seen: set[int] = set()
    for p, t in zip(places, times, strict=True):
        if t not in seen and len(out) < n:
            seen.add(t)
            out.append((p, t))
    return out


def render_gtkw(
    report: Report,
    dump_path: str | os.PathLike[str],
    *,
    names: dict[str, str],
    unit_factor: Fraction | int,
    origin_tick: int = 0,
    save_path: str | os.PathLike[str] | None = None,
) -> str:
    """The save file's text.

    Args:
        report: the report (its violations become markers).
        dump_path: the VCD GTKWave opens.
        names: role → signal name in that VCD.
        unit_factor: dump time units per capture tick.
        origin_tick: the capture tick that is time 0 in the dump.
        save_path: where the save file goes (recorded in it).
    """
    from vcd.gtkw import GTKWFlag, GTKWSave

    buf = io.StringIO()
    save = GTKWSave(buf)
    save.comment(
        f"wavecheck: {report.capture.path} vs {report.drive.id}: {report.verdict.upper()}, "
        f"{report.total_violations} violation(s)"
    )
    if report.windows is not None and report.capture.format != "vcd":
        save.comment(report.windows.note)
    save.dumpfile(os.fspath(dump_path))
    if save_path is not None:
        save.savefile(os.fspath(save_path))

    factor = Fraction(unit_factor)

    def at(tick: int) -> int:
        return _round(tick - origin_tick, factor)

    candidates = choose_places(report, 4 * MAX_MARKERS)
    chosen = _distinct(candidates, [at(p.start_tick) for p in candidates], MAX_MARKERS)
    places = [p for p, _ in chosen]
    marks = [t for _, t in chosen]
    letters = "abcdefghijklmnopqrstuvwxyz"
    for k, p in enumerate(places):
        label = "primary marker" if k == 0 else f"marker {letters[k - 1].upper()}"
        what = "FAIL" if p.failed else "smallest margin"
        measured = (
            f"measured {format_time(p.measured_ns / 10**9)}, limit {format_time(p.limit_ns / 10**9)}"
            if p.measured_ns is not None and p.limit_ns is not None
            else p.detail
        )
        save.comment(
            f"{label}: {p.rule} {what} at {float(report.capture.timebase.seconds(p.start_tick)):.9f} s"
            f" ({measured})"
        )
    save.size(*WINDOW_SIZE)
    cap = report.capture
    if places:
        first, last = marks[0], at(places[0].end_tick)
        if last == first:  # a state change: show it with its neighbouring edges
            first, last = (at(t) for t in _neighbours(report, places[0].start_tick))
        view = view_of(min(first, marks[0]), max(last, marks[0]), at(cap.start), at(cap.end))
        save.zoom_markers(view.zoom, marks[0], **{letters[k]: m for k, m in enumerate(marks[1:])})
        save.timestart(view.start)
    else:
        save.zoom_markers(_zoom(Fraction(max(at(cap.end) - at(cap.start), 1))))
        save.timestart(at(cap.start))
    save.signals_width(SIGNALS_WIDTH)
    save.sst_expanded(False)
    with save.group(f"{report.drive.id}: {report.verdict.upper()}"):
        for role, sig in report.interface.signals.items():
            flags = GTKWFlag.bin | (GTKWFlag.invert if sig.inverted else GTKWFlag.none)
            label = role.upper() if not role.startswith("phase") else role
            alias = label if sig.channel.lower() == role.lower() else f"{label} ({sig.channel})"
            save.trace(names[role], alias=alias, datafmt="bin", extraflags=flags)
    return buf.getvalue()


def _neighbours(report: Report, tick: int) -> tuple[int, int]:
    """The mapped signals' last edge before ``tick`` and first edge after it (``tick`` itself
    where there is none)."""
    edges = np.concatenate(
        [np.asarray(sig.edges, dtype=np.int64) for sig in report.traces.values()]
    )
    before, after = edges[edges < tick], edges[edges > tick]
    return (
        int(before.max()) if len(before) else tick,
        int(after.min()) if len(after) else tick,
    )


def write_gtkw(report: Report, path: str | os.PathLike[str]) -> Path | None:
    """Write the save file to ``path`` (and the VCD beside it for a non-VCD capture).

    Returns the VCD written beside it (:func:`companion_vcd`), or None when the capture's own
    VCD is used.
    """
    path = Path(path)
    cap = report.capture
    if cap.format == "vcd":
        all_names, magnitude = _vcd_header_names(cap.path)
        names = _trace_names(all_names, report)
        text = render_gtkw(report, cap.path, names=names, unit_factor=magnitude, save_path=path)
        atomic_write(path, text)
        return None
    vcd_path = companion_vcd(path)
    magnitude, _, factor = write_vcd_of(report, vcd_path, _companion_mark(path) + " ")
    names = {role: "wavecheck." + role.replace("-", "_") for role in report.interface.signals}
    text = render_gtkw(
        report,
        vcd_path,
        names=names,
        unit_factor=factor * magnitude,  # markers count in the unit, not in timescale steps
        origin_tick=cap.start,
        save_path=path,
    )
    atomic_write(path, text)
    return vcd_path
