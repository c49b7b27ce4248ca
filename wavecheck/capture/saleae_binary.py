"""Saleae Logic 2's digital binary export: one file per channel (``digital_0.bin``, …).

Format (Saleae's support articles "Binary Export Format - Logic 2" for version 0 and "Binary and
CSV Export Formats - 2025 Update" for version 1; little-endian, IEEE 754 doubles): an 8-byte
identifier ``<SALEAE>``, ``int32 version``, ``int32 type`` (0 digital, 1 analog), then

- version 0: ``uint32 initial_state``, ``double begin_time``, ``double end_time``, ``uint64
  num_transitions`` and that many ``double`` transition times (seconds); no sample rate;
- version 1: ``uint64 chunk_count`` and per chunk ``uint32 initial_state``, ``double
  sample_rate``, ``double begin_time``, ``double end_time``, ``uint64 num_transitions`` and the
  times. A gap between chunks is missing data (a channel off, or USB bandwidth saturated).

Each transition toggles the level. Times are doubles, so they are put on the sample grid: tick
= round((t − t0) × rate) for the earliest begin time t0 of the channels read, and a time more than
0.05 sample off the grid is refused (the wrong ``--samplerate``?). The rate is the file's
(version 1; a whole number of Hz expected) or ``--samplerate`` (required for version 0). A gap
between chunks becomes an unknown stretch of the channel (never bridged): every interval that
touches it is excluded by the checks, and a level that differs after it is an edge at its end.

A capture is a folder of ``digital_N.bin`` files (channel N, named ``Channel N`` as Logic 2
names them by default; ``analog_N.bin`` files are skipped with a note), or one such file.
"""

from __future__ import annotations

import os
import re
import struct
from fractions import Fraction
from pathlib import Path
from typing import TYPE_CHECKING, BinaryIO

import numpy as np

from wavecheck.capture.common import resolution_of
from wavecheck.capture.edges import NEVER, Capture, Channel
from wavecheck.errors import CaptureError, UnitError
from wavecheck.timebase import Timebase
from wavecheck.units import check_finite, format_frequency

if TYPE_CHECKING:
    import numpy.typing as npt

__all__ = ["MAGIC", "holds_export", "read_saleae_binary"]

#: How every Logic 2 binary export file begins.
MAGIC = b"<SALEAE>"
_DIGITAL = re.compile(r"digital_(\d{1,6})\.bin")
_ANALOG = re.compile(r"analog_(\d{1,6})\.bin")
_TIMES_PER_READ = 1 << 20
_GRID_SLACK = 0.05  # samples
#: The largest time (s, from the trigger) and sample rate (Hz) a chunk may state.
_MAX_SECONDS = 10**9
_MAX_RATE = 1e15
#: The largest tick a time may give (int64, with room for sums of two ticks).
_MAX_TICK = 2.0**62


class _Chunk:
    """One continuous stretch of one channel: its level at ``begin``, rate and times."""

    def __init__(
        self,
        initial: int,
        rate: float | None,
        begin: float,
        end: float,
        times: npt.NDArray[np.float64],
    ) -> None:
        self.initial = initial
        self.rate = rate
        self.begin = begin
        self.end = end
        self.times = times


def holds_export(folder: str | os.PathLike[str]) -> bool:
    """True when ``folder`` holds at least one ``digital_N.bin`` starting with :data:`MAGIC`."""
    try:
        names = os.listdir(folder)
    except OSError:
        return False
    for name in names:
        if _DIGITAL.fullmatch(name):
            try:
                with open(Path(folder) / name, "rb") as f:
                    if f.read(len(MAGIC)) == MAGIC:
                        return True
            except OSError:
                continue
    return False


def _read(f: BinaryIO, size: int, label: str, what: str, offset: int) -> bytes:
    data = f.read(size)
    if len(data) != size:
        raise CaptureError(label, f"byte {offset}", f"the file ends inside {what} (cut short?)")
    return data


def _chunks(path: Path, label: str) -> tuple[int, list[_Chunk]]:
    """The version and the chunks of one digital export file.

    Raises:
        CaptureError: not such a file, analog data, an unknown version, or a cut or bogus file.
    """
    try:
        size = path.stat().st_size
        f = open(path, "rb")  # noqa: SIM115 - closed below
    except OSError as err:
        raise CaptureError(label, None, f"cannot open: {err.strerror or err}") from None
    with f:
        head = f.read(16)
        if len(head) < 16 or head[:8] != MAGIC:
            raise CaptureError(
                label, None, "not a Saleae Logic 2 binary export (no <SALEAE> header)"
            )
        version, kind = struct.unpack("<ii", head[8:16])
        if kind == 1:
            raise CaptureError(
                label, None, "is an analog export (type 1); export the digital channels"
            )
        if kind != 0:
            raise CaptureError(
                label, "byte 12", f"data type {kind} is neither digital (0) nor analog (1)"
            )
        if version not in (0, 1):
            raise CaptureError(
                label, "byte 8", f"export version {version} is not known (0 and 1 are)"
            )
        offset = 16
        count = 1
        if version == 1:
            (count,) = struct.unpack("<Q", _read(f, 8, label, "the chunk count", offset))
            offset += 8
        chunks: list[_Chunk] = []
        for k in range(count):
            if version == 0:
                initial, begin, end, n = struct.unpack(
                    "<IddQ", _read(f, 28, label, "the header", offset)
                )
                rate: float | None = None
                offset += 28
            else:
                initial, rate, begin, end, n = struct.unpack(
                    "<IdddQ", _read(f, 36, label, f"chunk {k}'s header", offset)
                )
                offset += 36
            if initial not in (0, 1):
                raise CaptureError(
                    label, f"byte {offset}", f"initial state {initial} is not 0 or 1"
                )
            _check_header(label, f"byte {offset - (28 if version == 0 else 36)}", rate, begin, end)
            if n * 8 > size - offset:
                raise CaptureError(
                    label, f"byte {offset}",
                    f"declares {n} transitions, more than the {size - offset} bytes left hold",
                )  # fmt: skip
            parts = []
            left = n
            while left:
                take = min(left, _TIMES_PER_READ)
                raw = _read(f, 8 * take, label, "the transition times", offset)
                parts.append(np.frombuffer(raw, dtype="<f8"))
                offset += 8 * take
                left -= take
            times = np.concatenate(parts) if parts else np.zeros(0, dtype=np.float64)
            _check_seconds(label, f"chunk {k}: transition", times)
            chunks.append(_Chunk(initial, rate, begin, end, times))
            if k + 1 < count and offset >= size:
                raise CaptureError(
                    label, f"byte {offset}", f"the file ends after chunk {k} of {count}"
                )
        if offset != size:
            raise CaptureError(label, f"byte {offset}", f"{size - offset} bytes follow the data")
    if not chunks:
        raise CaptureError(label, None, "holds no chunks of data")
    return version, chunks


def _check_seconds(label: str, what: str, seconds: npt.ArrayLike) -> None:
    """Refuse a time that is NaN, infinite or beyond :data:`_MAX_SECONDS` (one line)."""
    try:
        check_finite(seconds, lambda i: f"{what} {i}: time (s)", limit=_MAX_SECONDS)
    except UnitError as err:
        raise CaptureError(label, None, str(err)) from None


def _check_header(label: str, where: str, rate: float | None, begin: float, end: float) -> None:
    """Refuse a chunk header whose rate or times cannot be a capture's."""
    if rate is not None and not 0 < rate <= _MAX_RATE:
        raise CaptureError(
            label, where, f"sample rate {rate!r} Hz is not a rate (0 to 1e15 Hz expected)"
        )
    for name, value in (("begin", begin), ("end", end)):
        if not abs(value) <= _MAX_SECONDS:
            raise CaptureError(label, where, f"{name} time {value!r} s is not a capture's time")
    if end < begin:
        raise CaptureError(label, where, f"end time {end!r} s is before the begin {begin!r} s")


def _exact_rate(rate: float) -> Fraction:
    """A rate stated as a double, exact: the nearest whole number of Hz when it is one to 1e-9,
    else the nearest fraction with a small denominator."""
    whole = round(rate)
    if whole > 0 and abs(rate - whole) <= 1e-9 * rate:
        return Fraction(whole)
    return Fraction(rate).limit_denominator(1000)


def read_saleae_binary(
    path: str | os.PathLike[str],
    *,
    samplerate: Fraction | None = None,
    resolution_s: Fraction | None = None,
) -> Capture:
    """Read a Logic 2 digital binary export: a folder of ``digital_N.bin``, or one file.

    Raises:
        CaptureError: no digital files, a bad file, rates that disagree, no rate (version 0),
            or times that are not on the sample grid.
    """
    p = Path(path)
    notes: list[str] = []
    if p.is_dir():
        found = sorted(
            (int(m.group(1)), p / name) for name in os.listdir(p) if (m := _DIGITAL.fullmatch(name))
        )
        analog = [n for n in os.listdir(p) if _ANALOG.fullmatch(n)]
        if analog:
            notes.append(f"skipped {len(analog)} analog file(s) ({', '.join(sorted(analog)[:4])})")
        if not found:
            raise CaptureError(
                path, None, "holds no digital_N.bin files of a Saleae Logic 2 binary export"
            )
    else:
        m = _DIGITAL.fullmatch(p.name)
        found = [(int(m.group(1)) if m else 0, p)]
    files = [(n, f, *_chunks(f, str(f) if p.is_dir() else str(path))) for n, f in found]
    stated = {c.rate for _, _, _, chunks in files for c in chunks if c.rate is not None}
    if len(stated) > 1:
        listed = ", ".join(f"{r:g} Hz" for r in sorted(stated))
        raise CaptureError(
            path, None, f"its chunks were sampled at different rates ({listed}); not supported"
        )
    rate: Fraction
    if samplerate is not None:
        rate = samplerate
        if stated and _exact_rate(next(iter(stated))) != samplerate:
            notes.append(
                f"sample rate {format_frequency(samplerate)} given by the user overrides the "
                f"file's {format_frequency(_exact_rate(next(iter(stated))))}"
            )
    elif stated:
        rate = _exact_rate(next(iter(stated)))
    else:
        raise CaptureError(
            path, None,
            "a version 0 export states no sample rate, and its times are rounded doubles; give "
            "--samplerate, the rate set in Logic 2 (e.g. --samplerate 500MHz)",
        )  # fmt: skip
    t0 = min(c.begin for _, _, _, chunks in files for c in chunks)
    r = float(rate)
    tb = Timebase.from_samplerate(rate)
    channels: list[Channel] = []
    ends: list[int] = []
    end_tick = 0
    for number, file, _version, chunks in files:
        label = str(file)
        edges: list[npt.NDArray[np.int64]] = []
        xz_times: list[int] = []
        xz_ends: list[int] = []
        level_before: int | None = None
        first_initial = chunks[0].initial
        last_end: int | None = None
        for c in chunks:
            begin = _tick(label, c.begin, t0, r)
            end = _tick(label, c.end, t0, r)
            if last_end is not None:
                if begin < last_end:
                    raise CaptureError(label, None, "its chunks overlap or are out of time order")
                if begin > last_end:  # missing data: unknown from the last end to this begin
                    xz_times.append(last_end)
                    xz_ends.append(begin)
                if level_before is not None and c.initial != level_before:
                    edges.append(np.array([begin], dtype=np.int64))
            x = (c.times - t0) * r
            if len(x) and not np.all(np.abs(x) < _MAX_TICK):
                raise CaptureError(
                    label, None, f"times beyond 2^62 samples of {format_frequency(rate)}"
                )
            ticks = np.rint(x)
            off = np.abs(x - ticks) > _GRID_SLACK
            if off.any():
                i = int(np.argmax(off))
                raise CaptureError(
                    label, f"transition {i}",
                    f"time {c.times[i]:.12g} s is not on the grid of {format_frequency(rate)} "
                    "samples (was the capture made at another rate? give --samplerate)",
                )  # fmt: skip
            t = ticks.astype(np.int64)
            if len(t) and (np.any(np.diff(t) <= 0) or t[0] < begin or t[-1] > end):
                raise CaptureError(
                    label, None, "transition times do not increase within their chunk"
                )
            if len(t) and edges and len(edges[-1]) and t[0] <= edges[-1][-1]:
                raise CaptureError(
                    label, None, "two transitions fall on one sample where chunks meet"
                )
            edges.append(t)
            level_before = c.initial ^ (len(t) & 1)
            last_end = end
            end_tick = max(end_tick, end)
        all_edges = np.concatenate(edges) if edges else np.zeros(0, dtype=np.int64)
        channels.append(
            Channel(
                name=f"Channel {number}",
                index=number,
                initial=first_initial,
                edges=all_edges,
                known_from=_tick(label, chunks[0].begin, t0, r),
                xz_times=np.asarray(xz_times, dtype=np.int64),
                xz_ends=np.asarray(xz_ends, dtype=np.int64),
            )
        )
        ends.append(last_end if last_end is not None else 0)
    for ch, last in zip(channels, ends, strict=True):
        if last < end_tick:  # this channel's data stops before the capture's end
            ch.xz_times = np.append(ch.xz_times, last).astype(np.int64)
            ch.xz_ends = np.append(ch.xz_ends, NEVER).astype(np.int64)
        if len(ch.xz_times) or ch.known_from:
            gaps = len(ch.xz_times) + (1 if ch.known_from else 0)
            notes.append(f"{ch.name}: {gaps} stretch(es) without data (unknown, never bridged)")
    res, _ = resolution_of(path, tb, [], rate, resolution_s, notes)
    return Capture(
        path=str(path),
        format="saleae-bin",
        timebase=tb,
        resolution_ticks=res,
        samplerate_hz=rate,
        start=0,
        end=end_tick,
        channels=channels,
        notes=notes,
    )


def _tick(label: str, t: float, t0: float, rate: float) -> int:
    """Time ``t`` (s) as a tick from ``t0``; refused when it is not near a sample."""
    x = (t - t0) * rate
    if not abs(x) < _MAX_TICK:
        raise CaptureError(label, None, f"time {t!r} s is beyond 2^62 samples of {rate:g} Hz")
    k = round(x)
    if abs(x - k) > _GRID_SLACK:
        raise CaptureError(
            label,
            None,
            f"time {t:.12g} s is not on the grid of {rate:g} Hz samples (give --samplerate)",
        )
    return int(k)
