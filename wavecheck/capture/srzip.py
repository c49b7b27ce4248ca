"""The one sigrok ``.sr`` (srzip) writer: packed sample bytes, or exact edge arrays.

An srzip file (libsigrok's ``output/srzip.c``; ``../shared/reference/sigrok.md`` §5) is a zip of
``version`` (``"2"``, stored), ``metadata`` (an INI text, deflated) and the logic samples cut into
members ``logic-1-1``, ``logic-1-2`` … of ``chunk_bytes`` each (deflated). A sample is
``unitsize`` bytes, little-endian, channel ``i`` in bit ``i``.

:func:`sr_metadata` builds the metadata text, :func:`samples_from_edges` packs edge arrays into
sample bytes, :func:`write_sr` writes the file from sample bytes (one buffer or an iterable of
member-sized pieces, for files larger than memory) and :func:`write_sr_edges` from edges.

A writer of simulated data (stepgen) adds :func:`exact_edges_section`: a ``[wavecheck]`` group
that libsigrok ignores, saying every edge lies exactly on its sample, so the reader
(:mod:`wavecheck.capture.sr`) gives resolution 0 instead of one sample period.
"""

from __future__ import annotations

import io
import os
from collections.abc import Iterable, Mapping, Sequence
from typing import TYPE_CHECKING, BinaryIO

import numpy as np

from wavecheck.capture.keyfile import escape
from wavecheck.capture.zipdir import ZIP_DEFLATED
from wavecheck.output import atomic_path

if TYPE_CHECKING:
    import numpy.typing as npt

__all__ = [
    "EXACT_SECTION",
    "SR_CHUNK_BYTES",
    "SrZip",
    "exact_edges_section",
    "rate_text",
    "samples_from_edges",
    "sr_metadata",
    "write_sr",
    "write_sr_edges",
]

#: libsigrok's member size: 4 MiB of sample bytes per ``logic-1-N``.
SR_CHUNK_BYTES = 4 * 1024 * 1024
#: Metadata group (ignored by libsigrok, which reads only ``[global]`` and ``[device N]``) in
#: which ``edges=exact`` states that the samples are simulated: each edge is exactly at its sample.
EXACT_SECTION = "wavecheck"


def exact_edges_section(source: str) -> str:
    """The metadata text stating exact edges, ``source`` naming the simulation (one line)."""
    one_line = " ".join(source.split())
    return f"\n[{EXACT_SECTION}]\nedges=exact\nsource={escape(one_line)}\n"


def rate_text(hz: int) -> str:
    """A sample rate as libsigrok writes it: ``"20 MHz"``, ``"125 kHz"``, ``"3 Hz"``."""
    for div, unit in ((10**9, "GHz"), (10**6, "MHz"), (10**3, "kHz")):
        if hz % div == 0:
            return f"{hz // div} {unit}"
    return f"{hz} Hz"


def sr_metadata(
    probes: Sequence[str] | Mapping[int, str],
    *,
    samplerate: int | str | None,
    unitsize: int | None = None,
    total_probes: int | None = None,
    total_analog: int | None = 0,
    extra: str = "",
) -> str:
    """The ``metadata`` member's text (names escaped as GLib's key files want them).

    Args:
        probes: channel names, in bit order; or bit number → name (unnamed bits get none).
        samplerate: Hz (written as :func:`rate_text`), a text as is, or None for no rate.
        unitsize: bytes per sample (default: enough for ``total_probes``); 0 writes none.
        total_probes: the ``total probes`` count (default: the number of probes).
        total_analog: the ``total analog`` count; None writes none.
        extra: text appended after the device section.
    """
    named = dict(probes) if isinstance(probes, Mapping) else dict(enumerate(probes))
    total = len(named) if total_probes is None else total_probes
    unit = max(1, (total + 7) // 8) if unitsize is None else unitsize
    lines = ["[global]", "sigrok version=0.5.2", "", "[device 1]", "capturefile=logic-1"]
    lines.append(f"total probes={total}")
    if samplerate is not None:
        lines.append(
            f"samplerate={rate_text(samplerate) if isinstance(samplerate, int) else samplerate}"
        )
    if total_analog is not None:
        lines.append(f"total analog={total_analog}")
    lines += [f"probe{i + 1}={escape(name)}" for i, name in sorted(named.items())]
    if unit:
        lines.append(f"unitsize={unit}")
    return "\n".join(lines) + "\n" + extra


def samples_from_edges(
    edges: Sequence[npt.NDArray[np.int64]],
    initial: Sequence[int],
    n_samples: int,
    *,
    unitsize: int | None = None,
) -> npt.NDArray[np.uint8]:
    """Packed sample bytes (``n_samples × unitsize``): channel ``i`` = bit ``i``.

    ``edges[i]`` are sample numbers (non-decreasing, in 0 … n_samples − 1); each toggles channel
    ``i`` from that sample on (two at one sample cancel). ``initial[i]`` is its level at sample 0.
    """
    nch = len(edges)
    unit = max(1, (nch + 7) // 8) if unitsize is None else unitsize
    if nch > 8 * unit:
        raise ValueError(f"{nch} channels do not fit in {unit} byte(s) per sample")
    if unit > 8:
        raise ValueError(f"unitsize {unit} > 8 is not supported")
    ts = [np.asarray(e, dtype=np.int64) for e in edges]
    t = np.concatenate(ts) if ts else np.zeros(0, dtype=np.int64)
    if len(t) and (int(t.min()) < 0 or int(t.max()) >= n_samples):
        raise ValueError(f"edge sample numbers must lie in 0 … {n_samples - 1}")
    masks = np.concatenate(
        [np.full(len(e), 1 << i, dtype=np.uint64) for i, e in enumerate(ts)]
        or [np.zeros(0, dtype=np.uint64)]
    )
    start = np.uint64(sum((int(level) & 1) << i for i, level in enumerate(initial)))
    order = np.argsort(t, kind="stable")
    t, masks = t[order], masks[order]
    # the value from each change on: start XOR every mask so far; the last change at a sample wins
    values = np.bitwise_xor.accumulate(masks) ^ start if len(t) else masks
    last = np.ones(len(t), dtype=bool)
    last[:-1] = t[1:] != t[:-1]
    t, values = t[last], values[last]
    starts = np.concatenate(([0], t))
    vals = np.concatenate(([start], values)).astype(np.uint64)
    lengths = np.diff(np.concatenate((starts, [n_samples])))
    dtype = {1: "<u1", 2: "<u2", 4: "<u4"}.get(unit, "<u8")  # one word per sample, little-endian
    words = np.repeat(vals.astype(dtype), lengths)
    if np.dtype(dtype).itemsize == unit:
        return words.view(np.uint8)
    return np.ascontiguousarray(words.view(np.uint8).reshape(-1, 8)[:, :unit]).reshape(-1)


def _pieces(samples: bytes | npt.NDArray[np.uint8], chunk_bytes: int) -> Iterable[bytes]:
    raw = (
        np.frombuffer(samples, dtype=np.uint8)
        if isinstance(samples, bytes)
        else np.ascontiguousarray(samples).view(np.uint8).reshape(-1)
    )
    for off in range(0, len(raw), chunk_bytes):
        yield raw[off : off + chunk_bytes].tobytes()


def write_sr(
    target: str | os.PathLike[str] | BinaryIO,
    samples: bytes | npt.NDArray[np.uint8] | Iterable[bytes],
    *,
    metadata: str,
    chunk_bytes: int = SR_CHUNK_BYTES,
    compression: int = ZIP_DEFLATED,
    compresslevel: int | None = None,
    version: str | bytes = "2",
) -> int:
    """Write an srzip file; returns the number of sample bytes written.

    Args:
        target: a path (written atomically) or a writable binary file (e.g. ``io.BytesIO``).
        samples: packed sample bytes, cut into ``logic-1-N`` members of ``chunk_bytes``; or an
            iterable of byte pieces, each written as one member as it comes.
        metadata: the ``metadata`` text (:func:`sr_metadata`).
        chunk_bytes: bytes per member (libsigrok: 4 MiB); a multiple of the unit size.
        compression: ``zipfile.ZIP_DEFLATED`` (libsigrok) or ``zipfile.ZIP_STORED``.
        compresslevel: the deflate level (default: zlib's).
        version: the ``version`` member (``"2"``).
    """
    if chunk_bytes < 1:
        raise ValueError(f"chunk_bytes must be positive, got {chunk_bytes}")
    pieces = _pieces(samples, chunk_bytes) if isinstance(samples, (bytes, np.ndarray)) else samples
    if isinstance(target, (str, os.PathLike)):
        with atomic_path(target) as tmp, open(tmp, "wb") as fh:
            return _write_zip(fh, pieces, metadata, compression, compresslevel, version)
    return _write_zip(target, pieces, metadata, compression, compresslevel, version)


class SrZip:
    """An srzip file written member by member into an open binary file: ``version`` and
    ``metadata`` at once, then each :meth:`add` a ``logic-1-N`` member; :meth:`close` ends the zip.
    Entries carry a fixed date (1980-01-01), so the bytes depend only on the input."""

    def __init__(
        self,
        fh: BinaryIO | io.BytesIO,
        metadata: str,
        *,
        compression: int = ZIP_DEFLATED,
        compresslevel: int | None = None,
        version: str | bytes = "2",
    ) -> None:
        import zipfile  # here: the .sr reader imports this module, and reads without zipfile

        self.zip = zipfile.ZipFile(fh, "w")
        self._entry = zipfile.ZipInfo
        self.compression = compression
        self.compresslevel = compresslevel
        self.members = 0
        self.bytes = 0
        self.zip.writestr(zipfile.ZipInfo("version"), version, compress_type=zipfile.ZIP_STORED)
        self.zip.writestr(
            zipfile.ZipInfo("metadata"),
            metadata,
            compress_type=zipfile.ZIP_DEFLATED,
            compresslevel=compresslevel,
        )

    def add(self, piece: bytes) -> None:
        """Write ``piece`` (whole samples) as the next ``logic-1-N`` member."""
        self.members += 1
        self.zip.writestr(
            self._entry(f"logic-1-{self.members}"),
            piece,
            compress_type=self.compression,
            compresslevel=self.compresslevel,
        )
        self.bytes += len(piece)

    def close(self) -> None:
        """Write the zip's central directory."""
        self.zip.close()


def _write_zip(
    fh: BinaryIO | io.BytesIO,
    pieces: Iterable[bytes],
    metadata: str,
    compression: int,
    compresslevel: int | None,
    version: str | bytes,
) -> int:
    z = SrZip(fh, metadata, compression=compression, compresslevel=compresslevel, version=version)
    for piece in pieces:
        z.add(piece)
    z.close()
    return z.bytes


def write_sr_edges(
    target: str | os.PathLike[str] | BinaryIO,
    names: Sequence[str],
    edges: Sequence[npt.NDArray[np.int64]],
    initial: Sequence[int],
    n_samples: int,
    *,
    samplerate: int | str | None,
    chunk_bytes: int = SR_CHUNK_BYTES,
    exact_source: str | None = None,
) -> int:
    """Write channels given as edges (sample numbers, see :func:`samples_from_edges`) as an
    srzip file, one bit per channel in ``names`` order; returns the number of sample bytes.

    ``exact_source``: the edges are simulated, exactly on their samples (not sampled from a
    signal); the metadata says so (:func:`exact_edges_section`), naming this source.
    """
    if len(names) != len(edges) or len(names) != len(initial):
        raise ValueError("names, edges and initial levels must have one entry per channel")
    unit = max(1, (len(names) + 7) // 8)
    raw = samples_from_edges(edges, initial, n_samples, unitsize=unit)
    extra = exact_edges_section(exact_source) if exact_source is not None else ""
    meta = sr_metadata(names, samplerate=samplerate, unitsize=unit, extra=extra)
    step = max(unit, chunk_bytes - chunk_bytes % unit)
    return write_sr(target, raw, metadata=meta, chunk_bytes=step)
