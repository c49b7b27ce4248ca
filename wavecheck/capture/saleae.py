"""Saleae's digital CSV exports, one row per change: Logic 2's ``Time [s],Channel 0,…`` and
Logic 1.x's ``Time[s], Channel 0, …`` (which Kingst's software writes too).

The times are decimal text in seconds, relative to the trigger (may be negative), printed to a
fixed number of digits, so they are exact only when the sample period is a multiple of the last
digit. The sample period is therefore taken from ``--samplerate`` (each time must round to a
sample within half a printed digit, else the file is refused), or recovered from the times as
the greatest common divisor of their differences, which must be coarser than the printed digit:
when it is the printed digit itself, the times may be rounded samples of a rate that is not a
whole number of digits (6 MHz printed to 1 ns), and the file is refused with the fix (give
``--samplerate``, the rate set in Logic 2). Ticks are samples; tick 0 is the first row.

The first row is where the export begins and the last (when nothing changes in it) where it
ends; a range exported from the middle of a capture puts them off the sample grid. The sample
period is then that of the other rows, a note names the rows off it, and they keep their exact
times on a finer tick (the resolution stays one sample); where no tick can hold them exactly (a
given rate that is no whole number of printed digits) they are read as the sample before them.

Logic 1.x prints a time to 15 decimals as a binary float (``0.000882958333333`` at 24 MHz), so
its last digits are float noise: its times are read to the nearest nanosecond.
"""

from __future__ import annotations

import math
import os
from fractions import Fraction

import numpy as np

from wavecheck.capture.common import resolution_of
from wavecheck.capture.edges import Capture, Channel
from wavecheck.errors import CaptureError
from wavecheck.timebase import Timebase
from wavecheck.units import format_time, shown

__all__ = ["HEADER", "HEADER_1X", "read_saleae_csv"]

#: How a Logic 2 digital CSV export begins.
HEADER = b"Time [s],"
#: How a Logic 1.x digital CSV export begins (``Time[s], Channel 0, Channel 1``).
HEADER_1X = b"Time[s],"
#: Logic 1.x's float times are kept to this many decimals (1 ns): below it they are noise.
_DIGITS_1X = 9
_MAX_HEADER = 1 << 16
#: Most digits of a time (Logic 2 prints seconds to 9 decimals: a day is 14 digits).
_MAX_DIGITS = 30
#: The largest tick (int64, with room for sums of two ticks).
_MAX_TICK = 2**62


def _decimal(path: str | os.PathLike[str], text: str, line: int) -> tuple[int, int]:
    """``text`` as (integer, digits after the point): ``"-0.0125"`` → (−125, 4)."""
    t = text.strip()
    neg = t.startswith("-")
    body = t[1:] if neg or t.startswith("+") else t
    whole, _, frac = body.partition(".")
    if not (whole or frac) or not (whole or "0").isdigit() or not (frac or "0").isdigit():
        raise CaptureError(
            path, f"line {line}", f"time {shown(t)} is not a decimal number of seconds"
        )
    if len(whole) + len(frac) > _MAX_DIGITS:
        raise CaptureError(
            path, f"line {line}", f"time {shown(t)} has more than {_MAX_DIGITS} digits"
        )
    value = int((whole or "0") + frac)
    return (-value if neg else value), len(frac)


def _nearest(value: int, step: int) -> int:
    """``value`` rounded to a multiple of ``step``, in units of ``step`` (half away from 0)."""
    q, r = divmod(abs(value), step)
    q += 2 * r >= step
    return q if value >= 0 else -q


def _text(value: int, digits: int) -> str:
    """``value`` units of 10^-digits s as decimal text (``-0.0125``)."""
    sign = "-" if value < 0 else ""
    whole, frac = divmod(abs(value), 10**digits)
    return f"{sign}{whole}.{frac:0{digits}d}" if digits else f"{sign}{whole}"


def _found_grid(
    path: str | os.PathLike[str], scaled: list[int], digits: int, ends: list[int]
) -> tuple[list[int], list[int], int, int]:
    """The ticks of the times, which of the ``ends`` rows are off the other rows' grid, the
    tick and the sample period (both in printed digits).

    The sample period is the greatest common divisor of the other rows' differences (a 500 kHz
    export whose first row is 9.893632465 s: 2 us, not the 5 ns that row would make it); the
    tick is that of every row, so that an end row off the grid keeps its exact time."""
    inner = [i for i in range(len(scaled)) if i not in ends]
    if len(inner) < 2:
        inner, ends = list(range(len(scaled))), []
    base = scaled[inner[0]]
    g_sample = 0
    for i in inner:
        g_sample = math.gcd(g_sample, scaled[i] - base)
    g_tick = g_sample
    for i in ends:
        g_tick = math.gcd(g_tick, scaled[i] - base)
    if g_sample <= 1:
        raise CaptureError(
            path,
            None,
            f"the times are printed to {digits} decimals and share no coarser grid, so the "
            "sample period cannot be told exactly (a rate such as 6 MHz is rounded); give "
            "--samplerate, the rate set in Logic",
        )
    off = [i for i in ends if (scaled[i] - base) % g_sample]
    return [(s - base) // g_tick for s in scaled], off, g_tick, g_sample


def _given_grid(
    path: str | os.PathLike[str],
    scaled: list[int],
    unit: Fraction,
    samplerate: Fraction,
    ends: list[int],
    lines: list[int],
) -> tuple[list[int], list[int]]:
    """The ticks of the times on the grid of ``samplerate`` samples (each within half a printed
    digit of a sample) and which of the ``ends`` rows are off it (read as the sample before).

    Raises:
        CaptureError: another row is off the grid (names its line)."""
    exact = [Fraction(s) * unit * samplerate for s in scaled]
    ticks = [round(x) for x in exact]
    slack = unit * samplerate / 2
    off: list[int] = []
    for i, (x, k) in enumerate(zip(exact, ticks, strict=True)):
        if abs(x - k) <= slack:
            continue
        if i not in ends:
            raise CaptureError(
                path,
                f"line {lines[i]}",
                f"time {float(scaled[i] * unit):.12g} s is not on the grid of "
                f"{samplerate} Hz samples (was the capture made at another rate?)",
            )
        ticks[i] = math.floor(x)
        off.append(i)
    return ticks, off


def read_saleae_csv(
    path: str | os.PathLike[str],
    *,
    samplerate: Fraction | None = None,
    resolution_s: Fraction | None = None,
) -> Capture:
    """Read a Logic 2 or Logic 1.x digital CSV export.

    Raises:
        CaptureError: not such an export, a bad row, or times not on a common sample grid.
    """
    with open(path, encoding="utf-8-sig", errors="replace", newline="") as f:
        header = f.readline(_MAX_HEADER)
        names = [n.strip() for n in header.rstrip("\r\n").split(",")]
        if len(names) < 2 or names[0] not in ("Time [s]", "Time[s]"):
            raise CaptureError(path, "line 1", "not a Saleae Logic digital CSV export")
        old = names[0] == "Time[s]"
        rows: list[tuple[int, int]] = []
        lines: list[int] = []
        values: list[list[int]] = []
        for line, raw in enumerate(f, start=2):
            if not raw.strip():
                continue
            cells = raw.rstrip("\r\n").split(",")
            if len(cells) != len(names):
                raise CaptureError(
                    path, f"line {line}", f"{len(cells)} columns, the header has {len(names)}"
                )
            rows.append(_decimal(path, cells[0], line))
            lines.append(line)
            try:
                bits = [int(c) for c in cells[1:]]
            except ValueError:
                bits = [-1]
            if any(b not in (0, 1) for b in bits):
                raise CaptureError(
                    path, f"line {line}", f"values {','.join(cells[1:])[:60]!r} are not 0/1"
                )
            values.append(bits)
    if not rows:
        raise CaptureError(path, None, "no rows after the header")
    digits = max(d for _, d in rows)
    scaled = [v * 10 ** (digits - d) for v, d in rows]  # exact, in units of 10^-digits s
    notes: list[str] = []
    if old:
        notes.append("a Saleae Logic 1.x CSV export (Time[s]; Kingst's software writes it too)")
        if digits > _DIGITS_1X:
            scaled = [_nearest(v, 10 ** (digits - _DIGITS_1X)) for v in scaled]
            digits = _DIGITS_1X
            notes.append(
                "its times are binary floats printed to 15 decimals: read to the nearest ns"
            )
    if any(b <= a for a, b in zip(scaled, scaled[1:], strict=False)):
        i = next(i for i, (a, b) in enumerate(zip(scaled, scaled[1:], strict=False)) if b <= a)
        raise CaptureError(path, f"line {lines[i + 1]}", "times do not increase")
    unit = Fraction(1, 10**digits)
    # the first row is where the export begins, and the last, when nothing changes in it, where
    # it ends: times of the export's range, which need not be samples
    ends = [0] + ([len(rows) - 1] if len(rows) > 2 and values[-1] == values[-2] else [])
    if samplerate is not None:
        ticks, off = _given_grid(path, scaled, unit, samplerate, ends, lines)
        rate = samplerate
        period = tick = 1 / samplerate
        whole = period / unit  # the sample period in printed digits
        if off and whole.denominator == 1:  # the off rows kept exact on a finer tick
            g_tick = math.gcd(int(whole), *(scaled[i] for i in off))
            ticks = [s // g_tick for s in scaled]
            tick = g_tick * unit
    else:
        ticks, off, g_tick, g_sample = _found_grid(path, scaled, digits, ends)
        period = g_sample * unit
        rate = 1 / period
        tick = g_tick * unit
        notes.append(
            f"sample period {format_time(period)} recovered from the times (their common grid); "
            "give --samplerate if Logic sampled faster"
        )
    how = (
        f"a time of the export's range, not a sample: kept exact ({format_time(tick)} ticks)"
        if tick != period
        else "read as the sample before it, whose levels it shows"
    )
    for i in off:
        notes.append(
            f"line {lines[i]} (time {_text(scaled[i], digits)} s, the export's "
            f"{'start' if i == 0 else 'end'}) is off the {format_time(period)} sample grid of "
            f"the other rows: {how}"
        )
    if max(abs(ticks[0]), abs(ticks[-1])) >= _MAX_TICK:
        raise CaptureError(path, None, f"the times reach beyond 2^62 samples of {rate} Hz")
    tb = Timebase(tick)
    t = np.asarray(ticks, dtype=np.int64)
    t0 = int(t[0])
    t -= t0
    vals = np.asarray(values, dtype=np.int8)
    channels: list[Channel] = []
    for i, name in enumerate(names[1:]):
        col = vals[:, i]
        change = np.flatnonzero(col[1:] != col[:-1]) + 1
        channels.append(Channel(name=name, index=i, initial=int(col[0]), edges=t[change]))
    res, _ = resolution_of(path, tb, [], rate, resolution_s, notes)
    return Capture(
        path=str(path),
        format="saleae1-csv" if old else "saleae-csv",
        timebase=tb,
        resolution_ticks=res,
        samplerate_hz=rate,
        start=0,
        end=int(t[-1]),
        channels=channels,
        notes=notes,
    )
