"""Native sigrok ``.sr`` (srzip) reader: streams the logic chunks and keeps only the edges.

Layout (``../shared/reference/sigrok.md`` §5): a zip (read by :mod:`~wavecheck.capture.zipdir`)
with ``version`` (1 or 2), ``metadata`` (a GLib key file, read as libsigrok reads it:
:mod:`~wavecheck.capture.keyfile`; ``samplerate``, ``total probes``, ``probeN`` names,
``unitsize``, ``capturefile``) and
the raw samples in ``logic-1`` or ``logic-1-1``, ``logic-1-2``, …, concatenated in numeric order.
Each sample is ``unitsize`` bytes, little-endian, bit n = probe n+1.

Memory is bounded by one read of ``chunk_bytes`` plus the edges: samples are never all in memory.
Per read, the samples are compared with themselves shifted by one sample (and the first with the
last sample of the previous read), so edge finding is numpy work over the changed samples only. An edge seen
at sample i (its value differs from sample i−1) has tick i; the tick is one sample period.

Speed (measured with ``bench/run.py``; profile notes in ``bench/README.md``): inflating the
deflated chunks is most of the work, so members are inflated straight from the file with
zlib-ng when it is installed (2–3× faster than the system zlib, CRC-32 included), bypassing
``ZipExtFile``'s buffering; the changed samples are found by comparing 8-byte words with the
same bytes one sample earlier, and looking inside the differing words only (``_changed_words``,
each such word's XOR once) and the changed bits of all channels sorted out together
(``_EdgeFinder._sparse``; bench/README.md).
"""

from __future__ import annotations

import os
import re
import struct
import zlib
from collections.abc import Iterable, Iterator
from fractions import Fraction
from typing import TYPE_CHECKING, Any, BinaryIO

import numpy as np

from wavecheck.capture.edges import Capture, Channel
from wavecheck.capture.keyfile import KeyFileError, parse_keyfile, unescape
from wavecheck.capture.srzip import EXACT_SECTION
from wavecheck.capture.zipdir import ZIP_DEFLATED, ZIP_STORED, Archive, Entry, ZipError
from wavecheck.errors import CaptureError, UnitError, UsageError
from wavecheck.progress import current
from wavecheck.timebase import Timebase
from wavecheck.units import SAMPLE_RATE, format_frequency, format_time, parse_frequency

if TYPE_CHECKING:
    import numpy.typing as npt

    from wavecheck.capture.blocks import EdgeBlock


def _load_zlib() -> Any:
    """zlib-ng (inflate and CRC-32 2–3× faster, same stream format), else the system zlib."""
    try:
        from zlib_ng import zlib_ng
    except ImportError:  # pragma: no cover - zlib-ng is a dependency; stay usable without it
        return zlib
    return zlib_ng


_zlib: Any = _load_zlib()

__all__ = [
    "DEFAULT_CHUNK_BYTES",
    "MAX_MEMBER_BYTES",
    "MAX_TOTAL_BYTES",
    "SrBlocks",
    "SrMetadata",
    "read_sr",
    "read_sr_metadata",
]

DEFAULT_CHUNK_BYTES = 1 << 20  # bytes scanned at a time: stays in cache (bench/README.md)
MAX_MEMBER_BYTES = 1 << 30  # one chunk member inflated (sigrok writes 4–10 MiB)
MAX_TOTAL_BYTES = 1 << 40  # the whole capture inflated (1 TiB: 1e12 samples at unitsize 1)
_MAX_METADATA_BYTES = 1 << 20
_READ_COMPRESSED = 1 << 20  # compressed bytes read from the file at a time
_READ_ERRORS: tuple[type[BaseException], ...] = (
    ZipError, zlib.error, _zlib.error, EOFError, OSError
)  # fmt: skip
_DIGITS = re.compile(r"[0-9]+")


class SrMetadata:
    """What a ``.sr`` file's ``metadata`` says, plus its ordered chunk members."""

    def __init__(
        self,
        samplerate: Fraction | None,
        samplerate_text: str | None,
        total_probes: int,
        unitsize: int,
        probes: dict[int, str],
        members: list[Entry],
        total_analog: int,
    ) -> None:
        self.samplerate = samplerate
        self.samplerate_text = samplerate_text
        self.total_probes = total_probes
        self.unitsize = unitsize
        self.probes = probes  # probe index from 0 → name (enabled probes only)
        self.members = members
        self.total_analog = total_analog
        self.ignored: list[str] = []  # members named like chunks that libsigrok does not read
        self.exact_source: str | None = None  # set when [wavecheck] says edges=exact

    @property
    def nsamples(self) -> int:
        return sum(m.file_size for m in self.members) // self.unitsize


def _open_zip(path: str | os.PathLike[str], again: Archive | None = None) -> Archive:
    """The zip at ``path``, or ``again`` (its directory read before) with the file opened again."""
    try:
        return Archive(path) if again is None else again.reopen()
    except FileNotFoundError:
        raise CaptureError(path, None, "no such file") from None
    except IsADirectoryError:
        raise CaptureError(path, None, "is a folder, not a capture file") from None
    except ZipError as err:
        raise CaptureError(
            path, None, f"not a sigrok .sr file: {err} (truncated or not a zip archive)"
        ) from None
    except OSError as err:
        raise CaptureError(path, None, f"cannot open: {err.strerror or err}") from None


def _value(path: str | os.PathLike[str], group: dict[str, str], key: str) -> str | None:
    """The value of ``key`` as ``g_key_file_get_string`` gives it (None: no such key)."""
    raw = group.get(key)
    return None if raw is None else _unescaped(path, key, raw)


def _unescaped(path: str | os.PathLike[str], key: str, raw: str) -> str:
    """``raw`` unescaped (:func:`~wavecheck.capture.keyfile.unescape`), else a CaptureError."""
    try:
        return unescape(raw)
    except KeyFileError as err:
        raise CaptureError(path, "metadata", f"{key}={raw!r} cannot be read: {err}") from None


def _int(path: str | os.PathLike[str], dev: dict[str, str], key: str) -> int | None:
    text = _value(path, dev, key)
    if text is None:
        return None
    text = text.strip()
    if not re.fullmatch(r"\d{1,9}", text):
        raise CaptureError(path, "metadata", f"{key}={text!r} is not a whole number")
    return int(text)


def read_sr_metadata(
    path: str | os.PathLike[str],
    zf: Archive,
    *,
    max_member_bytes: int = MAX_MEMBER_BYTES,
    max_total_bytes: int = MAX_TOTAL_BYTES,
) -> SrMetadata:
    """Parse and sanity-check ``version`` and ``metadata``; list the chunk members in order.

    Raises:
        CaptureError: naming the member or metadata key that is wrong.
    """
    names = set(zf.namelist())
    for member in ("version", "metadata"):
        if member not in names:
            raise CaptureError(path, None, f"no {member!r} member: not a sigrok .sr file")
    _refuse_overlaps(path, zf)
    for member in ("version", "metadata"):
        if zf.getinfo(member).file_size > _MAX_METADATA_BYTES:
            raise CaptureError(path, f"member {member}", "is implausibly large (corrupt file?)")
    try:
        version = zf.read("version").strip()
        raw_meta = zf.read("metadata")
    except _READ_ERRORS as err:
        raise CaptureError(path, "metadata", f"cannot be unpacked: {err}") from None
    if version not in (b"1", b"2"):
        raise CaptureError(
            path, "member version", f"unsupported .sr version {version[:10]!r} (known: 1, 2)"
        )
    try:
        groups = parse_keyfile(raw_meta.decode("utf-8"))
    except (UnicodeDecodeError, KeyFileError) as err:
        raise CaptureError(path, "metadata", f"cannot be parsed: {err}") from None
    if "device 1" not in groups:
        raise CaptureError(path, "metadata", "has no [device 1] section")
    dev = groups["device 1"]
    total = _int(path, dev, "total probes")
    unitsize = _int(path, dev, "unitsize")
    if total is None or total < 1:
        raise CaptureError(path, "metadata", "no logic channels ('total probes' missing or 0)")
    if unitsize is None:
        raise CaptureError(
            path, "metadata", "no 'unitsize' (the file holds no logic data; sigrok ignores it too)"
        )
    if not 1 <= unitsize <= 64:
        raise CaptureError(path, "metadata", f"unitsize={unitsize} is not 1 … 64 bytes per sample")
    if total > 8 * unitsize:
        raise CaptureError(
            path,
            "metadata",
            f"total probes={total} does not fit in unitsize={unitsize} bytes ({8 * unitsize} bits)",
        )
    probes: dict[int, str] = {}
    for key, value in dev.items():
        match = re.fullmatch(r"probe(\d+)", key)
        if match:
            number = int(match.group(1))
            if not 1 <= number <= total:
                raise CaptureError(
                    path, "metadata", f"{key}={value!r} is outside total probes={total}"
                )
            probes[number - 1] = _unescaped(path, key, value)
    rate_text = _value(path, dev, "samplerate")
    rate_text = rate_text.strip() if rate_text is not None else None
    rate: Fraction | None = None
    if rate_text is not None:
        try:
            rate = parse_frequency(rate_text.strip(), default_unit="Hz")
        except UnitError:
            raise CaptureError(
                path, "metadata", f"samplerate={rate_text!r} is not a frequency"
            ) from None
        if rate <= 0:
            raise CaptureError(path, "metadata", f"samplerate={rate_text!r} must be positive")
    base = (_value(path, dev, "capturefile") or "logic-1").strip()
    ignored: list[str] = []
    if base in names:
        members = [zf.getinfo(base)]
    else:
        members, ignored = _chunk_members(path, zf, base)
    total_bytes = 0
    for info in members:
        if info.file_size % unitsize:
            raise CaptureError(
                path,
                f"member {info.filename}",
                f"is {info.file_size} bytes, not a whole number of {unitsize}-byte samples",
            )
        if info.file_size > max_member_bytes:
            raise CaptureError(
                path,
                f"member {info.filename}",
                f"would unpack to {info.file_size} bytes, more than the {max_member_bytes}-byte "
                "limit for one chunk (a decompression bomb or corrupt file?)",
            )
        total_bytes += info.file_size
    if total_bytes > max_total_bytes:
        raise CaptureError(
            path,
            None,
            f"would unpack to {total_bytes} bytes, more than the {max_total_bytes}-byte limit "
            "(a decompression bomb or corrupt file?)",
        )
    if total_bytes == 0:
        raise CaptureError(path, None, "holds no samples")
    analog = _int(path, dev, "total analog") or 0
    meta = SrMetadata(rate, rate_text, total, unitsize, probes, members, analog)
    meta.ignored = ignored
    exact = groups.get(EXACT_SECTION, {})
    if (_value(path, exact, "edges") or "").strip() == "exact":
        meta.exact_source = (_value(path, exact, "source") or "").strip() or "unnamed"
    return meta


def _chunk_members(
    path: str | os.PathLike[str], zf: Archive, base: str
) -> tuple[list[Entry], list[str]]:
    """The chunk members ``base-1``, ``base-2``, … in order, and the names that look like chunks
    but are not read.

    libsigrok (``session_driver.c``) opens ``"%s-%d" % (base, n)`` by exact name for n = 1, 2, …
    and stops at the first missing one, so ``logic-1-02`` or ``logic-1-0`` are never read. A
    later chunk after a missing one is refused as a gap (sigrok would silently stop there). Time
    and memory are linear in the members present, whatever numbers they carry.

    Raises:
        CaptureError: no chunk, a gap, or a chunk name twice.
    """
    prefix = base + "-"
    present: dict[int, Entry] = {}
    unreachable = 0  # chunk names with a number too large to ever be reached
    ignored: list[str] = []
    for info in zf.infolist():
        name = info.filename
        if not name.startswith(prefix):
            continue
        tail = name[len(prefix) :]
        if not _DIGITS.fullmatch(tail):
            continue
        if tail[0] == "0":
            ignored.append(name)
        elif len(tail) > 18:
            unreachable += 1
        elif int(tail) in present:
            raise CaptureError(path, f"member {name}", "appears twice in the zip directory")
        else:
            present[int(tail)] = info
    members: list[Entry] = []
    while (chunk := present.get(len(members) + 1)) is not None:
        members.append(chunk)
    if not present and not unreachable:
        raise CaptureError(path, None, f"no logic data (no member {base!r} or {base}-1)")
    if len(members) < len(present) + unreachable:
        top = "a huge number" if unreachable else str(max(present))
        raise CaptureError(
            path,
            f"member {base}-{len(members) + 1}",
            f"is missing ({len(present) + unreachable} chunks present, numbered up to {top}); "
            "the capture has a gap",
        )
    return members, ignored


def _name_len(info: Entry) -> int:
    """Length in bytes of the entry's name as stored (UTF-8 under flag bit 11, else cp437)."""
    if info.filename.isascii():
        return len(info.filename)  # the same in both (and no cp437 codec to import)
    if info.flag_bits & 0x800:
        return len(info.filename.encode("utf-8", "surrogateescape"))
    return len(info.filename.encode("cp437", "replace"))


def _refuse_overlaps(path: str | os.PathLike[str], zf: Archive) -> None:
    """Refuse entries whose ranges overlap: each takes at least its 30-byte local header, its
    name and its compressed data, within its room (:attr:`Entry.end_offset
    <wavecheck.capture.zipdir.Entry.end_offset>`: up to the next entry's local header, or the
    central directory). Two directory entries sharing bytes are how a zip bomb makes a small
    file inflate many times (a 1 MB file with 1,000 entries on one 1 GiB stream). Linear in
    the entries.

    Raises:
        CaptureError: two entries overlap, or one reaches into the central directory.
    """
    at: dict[int, str] = {}
    for info in zf.infolist():
        at.setdefault(info.header_offset, info.filename)  # of entries at one offset, the first
    for info in zf.infolist():
        need = info.header_offset + 30 + _name_len(info) + info.compress_size
        if need > info.end_offset:
            other = repr(at[info.end_offset]) if info.end_offset in at else "the zip directory"
            raise CaptureError(
                path,
                None,
                f"zip entries {info.filename!r} and {other} overlap (bytes "
                f"{info.header_offset}…{need} and {info.end_offset}…): refused as a zip bomb or "
                "a corrupt archive",
            )


class _EdgeFinder:
    """Edges of the enabled bits over a stream of sample blocks: the positions of the wanted bits'
    changes (:meth:`want`; all at first), only the number of changes of the others."""

    def __init__(self, unitsize: int, bits: list[int]) -> None:
        self.unitsize = unitsize
        self.bits = bits
        # byte column → [(bit within byte, output slot)]
        self.columns: dict[int, list[tuple[int, int]]] = {}
        for slot, bit in enumerate(bits):
            self.columns.setdefault(bit // 8, []).append((bit % 8, slot))
        self.last: bytes | None = None  # the previous block's last sample
        self.initial = [0] * len(bits)
        self.parts: list[list[npt.NDArray[np.int64]]] = [[] for _ in bits]
        self.wanted = [True] * len(bits)
        self.counted = [0] * len(bits)
        """Changes of each slot so far (wanted or not)."""
        self.nsamples = 0
        self.partial = b""
        """The bytes of a sample not yet complete (:meth:`add_bytes`)."""
        self._ne = np.empty(0, dtype=bool)  # reused: fresh memory is costly to touch

    def want(self, slots: Iterable[int]) -> None:
        """Keep the positions of ``slots``' changes only; the others are only counted."""
        keep = set(slots)
        self.wanted = [slot in keep for slot in range(len(self.bits))]

    def _found(self, slot: int, pos: npt.NDArray[np.int64] | int) -> None:
        """Changes of ``slot`` at sample ``pos`` (ascending), or a number of changes (``int``)."""
        if isinstance(pos, int):
            self.counted[slot] += pos
            return
        self.counted[slot] += len(pos)
        self.parts[slot].append(pos)

    def add_bytes(self, data: bytes) -> None:
        """Add the next bytes of the stream, however they are cut: a sample split between two
        calls is kept in :attr:`partial` until its other part comes."""
        if self.partial:
            data, self.partial = self.partial + data, b""
        whole = len(data) - len(data) % self.unitsize
        if whole < len(data):
            self.partial = data[whole:]
        self.add(np.frombuffer(data, dtype=np.uint8, count=whole))

    def add(self, block: npt.NDArray[np.uint8]) -> None:
        """Add whole samples (``len(block)`` a multiple of ``unitsize``)."""
        us = self.unitsize
        n = len(block) // us
        if n == 0:
            return
        base = self.nsamples
        first = bytes(block[:us])
        if self.last is None:
            for col, slots in self.columns.items():
                for bit, slot in slots:
                    self.initial[slot] = (first[col] >> bit) & 1
        elif first != self.last:
            for col, slots in self.columns.items():
                d0 = first[col] ^ self.last[col]
                for bit, slot in slots:
                    if (d0 >> bit) & 1:
                        self._found(
                            slot, np.array([base], dtype=np.int64) if self.wanted[slot] else 1
                        )
        self.last = bytes(block[(n - 1) * us : n * us])
        self.nsamples += n
        if n == 1:
            return
        self._ne = ne = _grow(self._ne, (len(block) - us) // 8)
        changed = _changed_words(block[: n * us], us, ne, DENSE_WORDS)
        if changed is None:  # dense: most samples change
            self._dense(block[: n * us], base)
        elif len(changed[0]):
            self._sparse(*changed, base)

    def _sparse(
        self, word_at: npt.NDArray[np.int64], xor: npt.NDArray[np.uint64], base: int
    ) -> None:
        """:meth:`add` for the differing words of a block (:func:`_changed_words`): their
        changed bytes (byte G of the block after its first sample is sample G // unitsize + 1
        of it), then a bit matrix (bit of the sample × changed byte) whose set bits, in order,
        are the changes grouped by bit with the samples ascending: a few numpy calls a block,
        whatever the number of channels."""
        xb = xor.view(np.uint8)  # each word's bytes in memory order
        nz = (xb != 0).nonzero()[0]  # on bools: numpy's nonzero is slow on uint8
        at, xb = word_at[nz >> 3] + (nz & 7), xb[nz]
        us, n = self.unitsize, len(at)
        bits = np.unpackbits(xb, bitorder="little").reshape(n, 8)
        if us > 1:  # byte c of a sample holds bits 8c … 8c + 7
            spread = np.zeros((n, us, 8), dtype=np.uint8)
            spread[np.arange(n), at % us] = bits
            bits, at = spread.reshape(n, 8 * us), at // us
        bits = np.ascontiguousarray(bits.T)
        hit = bits.reshape(-1).view(bool).nonzero()[0]
        ends = np.searchsorted(hit, np.arange(0, (8 * us + 1) * n, n)).tolist()
        pos = at[hit % n]
        pos += base + 1
        for slot, bit in enumerate(self.bits):
            lo, hi = ends[bit], ends[bit + 1]
            if hi > lo:
                self._found(slot, pos[lo:hi] if self.wanted[slot] else hi - lo)

    def _dense(self, block: npt.NDArray[np.uint8], base: int) -> None:
        """:meth:`add` where most samples change: the XOR of every byte with the one a sample
        earlier, bit by bit (the unwanted bits only counted)."""
        us = self.unitsize
        xor = np.bitwise_xor(block[us:], block[:-us]).reshape(-1, us)
        scratch = np.empty(len(xor), dtype=np.uint8)
        for col, slots in self.columns.items():
            dv = xor[:, col]
            for bit, slot in slots:
                np.right_shift(dv, bit, out=scratch)
                hit = np.bitwise_and(scratch, 1, out=scratch).view(bool)  # 0/1: numpy's fast path
                if self.wanted[slot]:
                    pos = hit.nonzero()[0]
                    if len(pos):
                        pos += base + 1
                        self._found(slot, pos)
                else:
                    self._found(slot, int(np.count_nonzero(hit)))

    def edges(self, slot: int) -> npt.NDArray[np.int64]:
        """The positions found for ``slot`` since the last call (empty if not wanted)."""
        parts = self.parts[slot]
        self.parts[slot] = []
        if not parts:
            return np.zeros(0, dtype=np.int64)
        if len(parts) == 1:
            return parts[0]
        return np.concatenate(parts)


EdgeFinder = _EdgeFinder  # public: capture/binary.py scans raw samples with it


#: The share of differing 8-byte words above which :func:`_changed_words` leaves the block to a
#: plain XOR of every byte (positions of 8 bytes per differing word cost more than that).
DENSE_WORDS = 0.25


def _grow(buf: npt.NDArray[np.bool_], size: int) -> npt.NDArray[np.bool_]:
    """``buf`` if it holds ``size`` items, else a larger one (reused from block to block)."""
    return buf if len(buf) >= size else np.empty(size, dtype=bool)


def _changed_words(
    block: npt.NDArray[np.uint8],
    step: int,
    scratch: npt.NDArray[np.bool_] | None = None,
    dense: float | None = None,
) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.uint64]] | None:
    """Where ``block[step:]`` differs from ``block[:-step]`` (the sample before), by 8-byte
    words: the index into ``block[step:]`` of each differing word's first byte (ascending), and
    the XOR of the word, whose bytes in memory are the XOR of the bytes there (0 where equal).

    Changes are sparse (a few per thousand samples), so 8-byte words of the block are compared
    with the same bytes one sample earlier (an unaligned ``uint64`` view, no XOR written over
    every byte); the last ``size % 8`` bytes make one more word, padded with 0. ``scratch``
    (≥ (len − step) // 8 bools) is reused if given. None when more than the share ``dense``
    (if given) of the words differ: then the caller XORs every byte instead.
    """
    size = len(block) - step
    if size <= 0:
        return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.uint64)
    cur, prev = block[step:], block[:size]
    words = size // 8
    if scratch is None or len(scratch) < words:
        scratch = np.empty(words, dtype=bool)
    ne = scratch[:words]
    cur64, prev64 = cur[: 8 * words].view(np.uint64), prev[: 8 * words].view(np.uint64)
    np.not_equal(cur64, prev64, out=ne)
    w = ne.nonzero()[0]  # 1-D: flatnonzero's ravel and dispatch cost ~5 µs a block
    if dense is not None and len(w) > dense * words:
        return None
    at, xor = w << 3, np.bitwise_xor(cur64[w], prev64[w])
    if 8 * words < size and cur[8 * words :].tobytes() != prev[8 * words :].tobytes():
        last = np.bitwise_xor(cur[8 * words :], prev[8 * words :]).tobytes()
        at = np.append(at, 8 * words)
        xor = np.append(xor, np.frombuffer(last.ljust(8, b"\0"), dtype=np.uint64))
    return at, xor


def _member_blocks(zf: Archive, raw: BinaryIO, info: Entry, step: int) -> Iterator[bytes]:
    """The inflated bytes of chunk member ``info`` in blocks of at most ``step`` bytes.

    Stored and deflated members are read straight from the file (``raw``): the local header is
    skipped, the data inflated with zlib-ng (or zlib) and its CRC-32 checked at the end, like
    ``zipfile`` does. Anything else (encrypted, bzip2, lzma) goes through ``zipfile``. Data
    reaching past the entry's room (``info.end_offset``: the next entry) is refused.

    Raises:
        ZipError: a bad local header or CRC; zlib errors for a corrupt stream.
    """
    if info.flag_bits & 1 or info.compress_type not in (ZIP_STORED, ZIP_DEFLATED):
        yield from zf.blocks(info, step)
        return
    raw.seek(info.header_offset)
    head = raw.read(30)
    if len(head) < 30 or head[:4] != b"PK\x03\x04":
        raise ZipError("bad local file header")
    name_len, extra_len = struct.unpack("<HH", head[26:30])
    start = info.header_offset + 30 + name_len + extra_len
    if start + info.compress_size > info.end_offset:
        raise ZipError("its data overlaps the next zip entry (a zip bomb?)")
    raw.seek(start)
    left_in, left_out, crc = info.compress_size, info.file_size, 0
    if info.compress_type == ZIP_STORED:
        while left_in:
            data = raw.read(min(step, left_in))
            if not data:
                return  # truncated: the caller compares the byte count
            left_in -= len(data)
            crc = _zlib.crc32(data, crc)
            yield data
    else:
        inflater = _zlib.decompressobj(-15)
        tail = b""
        while True:
            if left_in and len(tail) < _READ_COMPRESSED:
                comp = raw.read(min(left_in, _READ_COMPRESSED))
                left_in = left_in - len(comp) if comp else 0
                tail = tail + comp if tail else comp
            # at most one byte more than declared, so an overlong member is noticed
            out = inflater.decompress(tail, max(1, min(step, left_out + 1)))
            tail = inflater.unconsumed_tail
            if out:
                left_out -= len(out)
                crc = _zlib.crc32(out, crc)
                yield out
            if inflater.eof or left_out < 0 or (not out and not tail and not left_in):
                break
        if left_out:
            return  # short or long: the caller compares the byte count
    if crc != info.CRC:
        raise ZipError(f"Bad CRC-32 for file {info.filename!r}")


#: Below this a stated sample rate is warned about: no logic analyzer samples that slowly, and
#: none could resolve a step pulse (the same bound refuses ``--samplerate``: units.SAMPLE_RATE).
UNLIKELY_RATE_HZ = SAMPLE_RATE.refuse_below or Fraction(1000)
#: A capture said to last longer than this is warned about (a rate written wrong, most likely).
UNLIKELY_SECONDS = 24 * 3600


def _unlikely_rate(meta: SrMetadata, rate: Fraction) -> list[str]:
    """A warning when the metadata's rate is one no capture has (5 Hz for a 5 MHz SPI
    capture): the times would be off by the same factor."""
    seconds = meta.nsamples / rate
    if rate >= UNLIKELY_RATE_HZ and seconds <= UNLIKELY_SECONDS:
        return []
    why = (
        f"below {format_frequency(UNLIKELY_RATE_HZ)}, which no logic analyzer samples at"
        if rate < UNLIKELY_RATE_HZ
        else "an unlikely length for a logic analyzer's capture"
    )
    return [
        f"warning: the metadata states samplerate={meta.samplerate_text}: {meta.nsamples} "
        f"samples would last {_length(seconds)} ({why}); every time below is scaled by it. "
        "If the capture was made at another rate, give it: --samplerate RATE"
    ]


def _length(seconds: Fraction) -> str:
    """A long duration for people: ``4 days``, ``2.5 h``, else :func:`format_time`."""
    if seconds >= 2 * 86400:
        return f"{float(seconds / 86400):.3g} days"
    if seconds >= 2 * 3600:
        return f"{float(seconds / 3600):.3g} h"
    return format_time(seconds)


def _rate_notes(
    path: str | os.PathLike[str], meta: SrMetadata, samplerate: Fraction | None, require_rate: bool
) -> tuple[Fraction | None, list[str]]:
    """The sample rate to use and the notes on where it comes from."""
    notes: list[str] = []
    rate = meta.samplerate
    if samplerate is not None:
        if samplerate <= 0:
            raise UsageError(f"--samplerate must be positive, got {samplerate} Hz")
        if rate is not None and rate != samplerate:
            notes.append(
                f"sample rate {format_frequency(samplerate)} given by the user overrides "
                f"the file's {meta.samplerate_text}"
            )
        elif rate is None:
            notes.append(
                f"the file states no sample rate; using {format_frequency(samplerate)} "
                "given by the user"
            )
        rate = samplerate
    elif rate is not None:
        notes += _unlikely_rate(meta, rate)
    if rate is None and require_rate:
        raise CaptureError(
            path,
            "metadata",
            "states no samplerate, so its time base is unknown (give it, e.g. --samplerate 12MHz)",
        )
    if rate is None:
        notes.append(
            "the file states no sample rate: edges and durations are in samples; "
            "times need --samplerate (e.g. --samplerate 12MHz)"
        )
    return rate, notes


def _scan(
    path: str | os.PathLike[str],
    zf: Archive,
    raw: BinaryIO,
    meta: SrMetadata,
    finder: _EdgeFinder,
    chunk_bytes: int,
) -> Iterator[None]:
    """Inflate every chunk member into ``finder``, yielding after each block of samples."""
    step = max(meta.unitsize, chunk_bytes - chunk_bytes % meta.unitsize)
    report = current()
    total = sum(info.file_size for info in meta.members)
    done = 0
    for info in meta.members:
        got = 0
        try:
            for data in _member_blocks(zf, raw, info, step):
                got += len(data)
                finder.add_bytes(data)
                report(done + got, total)
                yield
            finder.partial = b""  # a member's last partial sample is not joined to the next's
        except _READ_ERRORS as err:
            raise CaptureError(
                path,
                f"member {info.filename}",
                f"is corrupt after {got} bytes: {err} (the file is damaged)",
            ) from None
        if got != info.file_size:
            raise CaptureError(
                path,
                f"member {info.filename}",
                f"gave {got} bytes, not the {info.file_size} it declares (the file is damaged)",
            )
        done += got


def _assemble(
    path: str | os.PathLike[str],
    meta: SrMetadata,
    rate: Fraction | None,
    notes: list[str],
    resolution_s: Fraction | None,
    channels: list[Channel],
    nsamples: int,
    end_notes: bool = True,
) -> Capture:
    """The capture of ``channels`` with the reader's notes, time base and resolution
    (``end_notes=False``: leave out the notes known only after the samples, for a skeleton)."""
    notes = list(notes)
    if end_notes and meta.ignored:
        listed = ", ".join(meta.ignored[:5]) + (" …" if len(meta.ignored) > 5 else "")
        notes.append(
            f"ignored {len(meta.ignored)} member(s) named like chunks that libsigrok never "
            f"reads (it opens {meta.members[0].filename.rsplit('-', 1)[0]}-1, -2, … by exact "
            f"name): {listed}"
        )
    if end_notes and meta.total_analog:
        notes.append(f"skipped {meta.total_analog} analog channel(s)")
    disabled = meta.total_probes - len(meta.probes)
    if end_notes and disabled:
        notes.append(f"{disabled} of {meta.total_probes} logic channels were disabled")
    # untimed (no rate): a placeholder of 1 s per sample, flagged by time_known=False
    tb = Timebase.from_samplerate(rate if rate is not None else 1)
    res = 1
    if meta.exact_source is not None and resolution_s is None:
        res = 0
        notes.append(
            f"the file states its edges are exact (simulated by {meta.exact_source}, each "
            "edge on its sample): resolution 0"
        )
    elif meta.exact_source is not None and resolution_s is not None:
        ticks = resolution_s / tb.tick_s
        res = -((-ticks.numerator) // ticks.denominator)
        notes.append(f"resolution set to {res} samples by the user (the file says exact)")
    elif resolution_s is not None:
        ticks = resolution_s / tb.tick_s
        res = -((-ticks.numerator) // ticks.denominator)
        if ticks < 1:
            notes.append(
                f"resolution {float(resolution_s * 10**9):g} ns is finer than the sample "
                "period; using one sample"
            )
            res = 1
        elif res != 1:
            notes.append(f"resolution set to {res} samples by the user")
    return Capture(
        path=str(path),
        format="sr",
        timebase=tb,
        resolution_ticks=res,
        samplerate_hz=rate,
        start=0,
        end=nsamples,
        channels=channels,
        notes=notes,
        time_known=rate is not None,
    )


def read_sr(
    path: str | os.PathLike[str],
    *,
    samplerate: Fraction | None = None,
    resolution_s: Fraction | None = None,
    chunk_bytes: int = DEFAULT_CHUNK_BYTES,
    max_member_bytes: int = MAX_MEMBER_BYTES,
    max_total_bytes: int = MAX_TOTAL_BYTES,
    require_rate: bool = True,
) -> Capture:
    """Read a sigrok ``.sr`` file chunk by chunk into edge arrays (tick = one sample).

    Args:
        path: the ``.sr`` file.
        samplerate: sample rate in Hz; required when the metadata has none, and overrides it
            (with a note) when it differs.
        resolution_s: resolution in seconds, if coarser than one sample period.
        chunk_bytes: bytes inflated and scanned at a time (tests use tiny values).
        max_member_bytes / max_total_bytes: refuse files that would unpack to more.
        require_rate: with False, a file without a sample rate (and none given) is read anyway
            as an untimed capture (``time_known`` False: counts only, ticks are samples).

    Raises:
        CaptureError: unreadable zip, bad metadata, missing/corrupt chunk (names the member).
    """
    if chunk_bytes < 1:
        raise UsageError(f"chunk_bytes must be positive, got {chunk_bytes}")
    with _open_zip(path) as zf:
        meta = read_sr_metadata(
            path, zf, max_member_bytes=max_member_bytes, max_total_bytes=max_total_bytes
        )
        rate, notes = _rate_notes(path, meta, samplerate, require_rate)
        bits = sorted(meta.probes)
        finder = _EdgeFinder(meta.unitsize, bits)
        for _ in _scan(path, zf, zf.raw, meta, finder, chunk_bytes):
            pass
        channels = [
            Channel(name=meta.probes[bit], index=bit, initial=finder.initial[slot],
                    edges=finder.edges(slot))
            for slot, bit in enumerate(bits)
        ]  # fmt: skip
    return _assemble(path, meta, rate, notes, resolution_s, channels, finder.nsamples)


class SrBlocks:
    """A ``.sr`` read block by block (:class:`wavecheck.capture.blocks.BlockSource`): the
    edges of ``channels`` (indices; None: every channel) after each inflated block, the other
    channels only counted. Same scan as :func:`read_sr` (same arguments)."""

    def __init__(
        self,
        path: str | os.PathLike[str],
        *,
        samplerate: Fraction | None = None,
        resolution_s: Fraction | None = None,
        chunk_bytes: int = DEFAULT_CHUNK_BYTES,
        channels: Iterable[int] | None = None,
    ) -> None:
        self.path = path
        self.resolution_s = resolution_s
        self.chunk_bytes = max(1, chunk_bytes)
        with _open_zip(path) as zf:
            self.meta = read_sr_metadata(path, zf)
        self._zip = zf  # its directory, for blocks()
        self.rate, self.notes = _rate_notes(path, self.meta, samplerate, True)
        self.bits = sorted(self.meta.probes)
        self.wanted = set(self.bits if channels is None else channels)
        self.counts = dict.fromkeys(self.bits, 0)
        self.initial = dict.fromkeys(self.bits, 0)
        self.nsamples = 0
        self._finder: _EdgeFinder | None = None
        self.skeleton = _assemble(path, self.meta, self.rate, self.notes, resolution_s,
                                  self._channels(), 0, end_notes=False)  # fmt: skip

    def _channels(self) -> list[Channel]:
        return [
            Channel(self.meta.probes[b], b, self.initial[b], np.zeros(0, np.int64),
                    counted=self.counts[b])
            for b in self.bits
        ]  # fmt: skip

    def want(self, channels: Iterable[int]) -> None:
        """Extract the edges of ``channels`` only (from the next block on)."""
        self.wanted = set(channels)
        if self._finder is not None:
            self._finder.want(slot for slot, b in enumerate(self.bits) if b in self.wanted)

    def blocks(self) -> Iterator[EdgeBlock]:
        """The edges after each inflated block of samples."""
        from wavecheck.capture.blocks import EdgeBlock

        with _open_zip(self.path, self._zip) as zf:
            finder = self._finder = _EdgeFinder(self.meta.unitsize, self.bits)
            finder.want(slot for slot, b in enumerate(self.bits) if b in self.wanted)
            first = True
            for _ in _scan(self.path, zf, zf.raw, self.meta, finder, self.chunk_bytes):
                block = EdgeBlock(end=finder.nsamples, start=0 if first else None)
                if first:
                    for slot, b in enumerate(self.bits):
                        self.initial[b] = finder.initial[slot]
                        block.known[b] = (0, finder.initial[slot])
                    first = False
                for slot, b in enumerate(self.bits):
                    self.counts[b] = finder.counted[slot]
                    if finder.wanted[slot]:
                        e = finder.edges(slot)
                        if len(e):
                            block.edges[b] = e
                yield block
            self.nsamples = finder.nsamples

    def capture(self) -> Capture:
        """The whole capture without edges (after :meth:`blocks`)."""
        return _assemble(self.path, self.meta, self.rate, self.notes, self.resolution_s,
                         self._channels(), self.nsamples)  # fmt: skip
