"""Saleae Logic 2's digital CSV export: ``Time [s],Channel 0,Channel 1,…``, one row per change.

The times are decimal text in seconds, relative to the trigger (may be negative), printed to a
fixed number of digits, so they are exact only when the sample period is a multiple of the last
digit. The sample period is therefore taken from ``--samplerate`` (each time must round to a
sample within half a printed digit, else the file is refused), or recovered from the times as
the greatest common divisor of their differences, which must be coarser than the printed digit:
when it is the printed digit itself, the times may be rounded samples of a rate that is not a
whole number of digits (6 MHz printed to 1 ns), and the file is refused with the fix (give
``--samplerate``, the rate set in Logic 2). Ticks are samples; tick 0 is the first row.
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
from wavecheck.units import shown

__all__ = ["HEADER", "read_saleae_csv"]

#: How a Logic 2 digital CSV export begins.
HEADER = b"Time [s],"
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


def read_saleae_csv(
    path: str | os.PathLike[str],
    *,
    samplerate: Fraction | None = None,
    resolution_s: Fraction | None = None,
) -> Capture:
    """Read a Logic 2 digital CSV export.

    Raises:
        CaptureError: not such an export, a bad row, or times not on a common sample grid.
    """
    with open(path, encoding="utf-8-sig", errors="replace", newline="") as f:
        header = f.readline(_MAX_HEADER)
        names = [n.strip() for n in header.rstrip("\r\n").split(",")]
        if len(names) < 2 or names[0] != "Time [s]":
            raise CaptureError(path, "line 1", "not a Saleae Logic 2 digital CSV export")
        rows: list[tuple[int, int]] = []
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
    if any(b <= a for a, b in zip(scaled, scaled[1:], strict=False)):
        i = next(i for i, (a, b) in enumerate(zip(scaled, scaled[1:], strict=False)) if b <= a)
        raise CaptureError(path, f"line {i + 3}", "times do not increase")
    unit = Fraction(1, 10**digits)
    notes: list[str] = []
    if samplerate is not None:
        exact = [Fraction(s) * unit * samplerate for s in scaled]
        ticks = [round(x) for x in exact]
        slack = unit * samplerate / 2
        bad = next(
            (i for i, (x, k) in enumerate(zip(exact, ticks, strict=True)) if abs(x - k) > slack),
            None,
        )
        if bad is not None:
            raise CaptureError(
                path,
                f"line {bad + 2}",
                f"time {float(scaled[bad] * unit):.12g} s is not on the grid of "
                f"{samplerate} Hz samples (was the capture made at another rate?)",
            )
        rate = samplerate
    else:
        g = 0
        for s in scaled[1:]:
            g = math.gcd(g, s - scaled[0])
        if g <= 1:
            raise CaptureError(
                path,
                None,
                f"the times are printed to {digits} decimals and share no coarser grid, so the "
                "sample period cannot be told exactly (a rate such as 6 MHz is rounded); give "
                "--samplerate, the rate set in Logic 2",
            )
        rate = 1 / (g * unit)
        ticks = [(s - scaled[0]) // g for s in scaled]
        notes.append(
            f"sample period {g * unit} s recovered from the times (their common grid); "
            "give --samplerate if Logic 2 sampled faster"
        )
    if max(abs(ticks[0]), abs(ticks[-1])) >= _MAX_TICK:
        raise CaptureError(path, None, f"the times reach beyond 2^62 samples of {rate} Hz")
    tb = Timebase.from_samplerate(rate)
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
        format="saleae-csv",
        timebase=tb,
        resolution_ticks=res,
        samplerate_hz=rate,
        start=0,
        end=int(t[-1]),
        channels=channels,
        notes=notes,
    )
