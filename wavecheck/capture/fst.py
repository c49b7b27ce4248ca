"""FST read natively: GTKWave's block format decoded with zlib and numpy.

FST (GTKWave's Fast Signal Trace; Icarus's ``vvp -fst``, Verilator, GTKWave's ``vcd2fst``) is a
sequence of blocks, each a type byte and a big-endian 8-byte length (itself included): a
header (times, time scale, writer), a geometry block (each signal's width), a hierarchy block
(scopes and variables, gzip-compressed) and value-change blocks. A value-change block holds the
signals' values at its start (the *frame*), then each signal's changes compressed on its own,
then a table of where each signal's data starts (with aliases), then the block's times.

Only the 1-bit signals' changes (and a vector's, when a bit of it is mapped) are
decompressed, each signal's at once, and decoded with numpy (LEB128 varints: a 1-bit
signal's change is one varint holding the time-index delta and the value). The result is what
GTKWave's ``fst2vcd`` followed by the VCD reader gives (the same header, names, frame rule and
timestamps): :class:`FstFile` builds the :class:`~wavecheck.capture.vcd.header.VcdHeader`
``fst2vcd`` would print, :func:`scalar_changes` and :func:`vector_changes` the changes it
would write (:mod:`wavecheck.capture.fst_source` makes edges of them).

Facts from GTKWave's ``fstapi.c`` (``fstReaderProcessHier``, ``fstReaderIterBlocks2``) and
GTKWave's FST notes; the code is this project's own. Not read here: FastLZ-packed changes
(``vcd2fst -F``; :class:`FstUnsupported`, the caller falls back to ``fst2vcd`` or pywellen).
Everything is bounded: lengths are checked against the file and decompression ratios before
anything is allocated, and a malformed file is a :class:`~wavecheck.errors.CaptureError`
naming the byte.
"""

from __future__ import annotations

import mmap
import os
import zlib
from dataclasses import dataclass
from fractions import Fraction
from typing import TYPE_CHECKING

import numpy as np

from wavecheck.capture.vcd.header import (
    MAX_VARS,
    SCALAR_VALUES,
    VarDecl,
    VcdHeader,
    decode_name,
    not_utf8_notes,
)
from wavecheck.errors import CaptureError
from wavecheck.timebase import Timebase

if TYPE_CHECKING:
    import numpy.typing as npt

__all__ = [
    "FRAME_CODES", "FstFile", "FstUnsupported", "VcBlock", "scalar_changes", "varints",
    "vector_changes",
]  # fmt: skip

_HDR, _VCDATA, _BLACKOUT, _GEOM, _HIER = 0, 1, 2, 3, 4
_VCDATA_DYN_ALIAS, _HIER_LZ4, _HIER_LZ4DUO, _VCDATA_DYN_ALIAS2 = 5, 6, 7, 8
_ZWRAPPER, _SKIP = 254, 255
_VC_TYPES = (_VCDATA, _VCDATA_DYN_ALIAS, _VCDATA_DYN_ALIAS2)
_HEADER_BYTES = 329  # the header block's length field's value
_ENDIAN_TEST = 2.7182818284590452354  # e, stored as a double: the header's magic

# fstapi.c's tables (vartypes, modtypes): the words fst2vcd prints in $var and $scope
_VAR_TYPES = (
    "event integer parameter real real_parameter reg supply0 supply1 time tri triand trior "
    "trireg tri0 tri1 wand wire wor port sparray realtime string bit logic int shortint "
    "longint byte enum shortreal"
).split()
_REAL_TYPES = {3, 4, 20, 29}  # real, real_parameter, realtime, shortreal
_PORT = 18
_SCOPE_TYPES = (
    "module task function begin fork generate struct union class interface package program "
    "vhdl_architecture vhdl_procedure vhdl_function vhdl_record vhdl_process vhdl_block "
    "vhdl_for_generate vhdl_if_generate vhdl_generate vhdl_package"
).split()
_SCOPE, _UPSCOPE, _ATTRBEGIN = 254, 255, 252  # 253 (attribute end) is skipped as any byte
#: fst2vcd's timescale text per exponent (fstReaderProcessHier); others print as 1 ns
_UNITS = {0: "s", -3: "ms", -6: "us", -9: "ns", -12: "ps", -15: "fs", -18: "as", -21: "zs"}
#: the longest name fst2vcd keeps (FST_ID_NAM_ATTR_SIZ); longer ones are cut
_NAME_BYTES = 65536
#: value code of a 1-bit change's non-binary values, in the order of FST_RCV_STR "xzhuwl-?"
#: (0, 1, 2 = unknown, 3 = z, -1 = not a VCD value: '?')
_RCV = np.array([2, 3, 1, 2, 2, 0, 2, -1], dtype=np.int8)
#: value code of a value character (the VCD reader's scalar values, either case; -1: not one)
FRAME_CODES = np.full(256, -1, dtype=np.int8)
for _c, _v in SCALAR_VALUES.items():
    FRAME_CODES[ord(_c)] = FRAME_CODES[ord(_c.upper())] = _v
#: most bytes one deflate stream can expand a byte to (zlib's limit is ~1032), plus slack
_MAX_RATIO = 1100


class FstUnsupported(Exception):
    """A valid FST this reader does not decode (FastLZ packing: ``vcd2fst -F``)."""


@dataclass
class VcBlock:
    """Where one value-change block's parts are (offsets in the file)."""

    kind: int
    start: int  # offset of its length field
    length: int  # its length field's value
    begin: int  # its first time
    frame: tuple[int, int, int, int]  # offset, uncompressed, compressed length, signal count
    waves: int  # offset of the pack-type byte (signal data offsets count from here)
    waves_count: int  # signals described
    pack: int  # pack-type byte
    index: tuple[int, int]  # offset and length of the position table
    times: tuple[int, int, int, int]  # offset, uncompressed, compressed length, count


class _Cursor:
    """Reads varints and strings from ``data`` from ``pos``, errors naming ``base + pos``."""

    def __init__(self, fst: FstFile, data: bytes | mmap.mmap, pos: int, base: int, what: str):
        self.fst, self.data, self.pos, self.base, self.what = fst, data, pos, base, what

    def fail(self, msg: str) -> CaptureError:
        return self.fst.error(self.base + self.pos, f"{self.what}: {msg}")

    def byte(self) -> int:
        if self.pos >= len(self.data):
            raise self.fail("cut off")
        self.pos += 1
        return self.data[self.pos - 1]

    def varint(self) -> int:
        value = shift = 0
        while True:
            b = self.byte()
            value |= (b & 0x7F) << shift
            if not b & 0x80:
                return value
            shift += 7
            if shift > 63:
                raise self.fail("a number longer than 64 bits")

    def u64(self) -> int:
        if self.pos + 8 > len(self.data):
            raise self.fail("cut off")
        self.pos += 8
        return int.from_bytes(self.data[self.pos - 8 : self.pos], "big")

    def svarint(self) -> int:
        """A signed LEB128 varint (sign-extended from bit 6 of its last byte)."""
        value = shift = 0
        while True:
            b = self.byte()
            value |= (b & 0x7F) << shift
            shift += 7
            if not b & 0x80:
                return value - (1 << shift) if b & 0x40 else value
            if shift > 63:
                raise self.fail("a number longer than 64 bits")

    def text(self) -> bytes:
        end = self.data.find(b"\0", self.pos)
        if end < 0:
            raise self.fail("a name without its end")
        raw = bytes(self.data[self.pos : end])
        self.pos = end + 1
        return raw[:_NAME_BYTES]


def varints(data: npt.NDArray[np.uint8]) -> npt.NDArray[np.uint64]:
    """The LEB128 varints that fill ``data`` exactly (ValueError: cut off or too long)."""
    if len(data) == 0:
        return np.zeros(0, np.uint64)
    last = data < 0x80
    if not last[-1]:
        raise ValueError("the last number is cut off")
    ends = np.flatnonzero(last)
    if len(ends) == len(data):  # every varint one byte
        return data.astype(np.uint64)
    wide = np.diff(ends, prepend=-1)
    longest = int(wide.max())
    if longest > 10:
        raise ValueError(f"a number of {longest} bytes (at most 10)")
    size = wide.astype(np.uint8)
    del wide
    # Horner from each varint's last (most significant) byte down to its first; few arrays of
    # the varints' count live at once (a block's time table can hold millions)
    out = (data[ends] & 0x7F).astype(np.uint64)
    seven = np.uint64(7)
    for k in range(1, longest):
        inside = size > k
        np.subtract(ends, 1, out=ends)
        lower = data[np.maximum(ends, 0)] & 0x7F
        np.left_shift(out, seven, out=out, where=inside)
        np.bitwise_or(out, lower, out=out, where=inside)
    return out


class FstFile:
    """An FST file's layout: header, hierarchy (as the VCD header ``fst2vcd`` prints) and
    value-change blocks; :meth:`time_table`, :meth:`positions`, :meth:`wave` and
    :meth:`frame` give a block's parts (the geometry block is not read: fst2vcd takes the
    widths from the hierarchy).

    Raises (constructor):
        CaptureError: not a readable FST (the message names the byte).
        FstUnsupported: a valid FST packed in a way this reader does not decode.
    """

    def __init__(self, path: str | os.PathLike[str]) -> None:
        self.path = path
        try:
            with open(path, "rb") as f:
                size = os.fstat(f.fileno()).st_size
                self.data: bytes | mmap.mmap = (
                    mmap.mmap(f.fileno(), 0, access=mmap.ACCESS_READ) if size else b""
                )
        except OSError as err:
            raise CaptureError(path, None, f"cannot open: {err.strerror or err}") from None
        self.size = len(self.data)
        if self.size >= 17 and self.data[0] == _ZWRAPPER:  # the whole file gzipped (vcd2fst -c)
            full = int.from_bytes(self.data[9:17], "big")
            inner = self._inflate(17, self.size - 17, full, "gzip-wrapped file", always=True)
            self.close()
            self.data, self.size = inner, len(inner)
        self.blocks: list[VcBlock] = []
        self.lengths: list[int] = []  # per handle (index handle-1): its declared width
        self._scan()

    def close(self) -> None:
        if isinstance(self.data, mmap.mmap):
            self.data.close()

    def error(self, at: int, msg: str) -> CaptureError:
        return CaptureError(self.path, f"byte {at}", f"not a readable FST file: {msg}")

    # --- the block list -------------------------------------------------------------------

    def _scan(self) -> None:
        d, pos = self.data, 0
        if self.size < 1 + _HEADER_BYTES or d[0] != _HDR:
            raise self.error(0, "no FST header block")
        hier: tuple[int, int, int] | None = None
        while pos < self.size:
            kind = d[pos]
            if pos + 9 > self.size:
                raise self.error(pos, "a block cut off in its length")
            length = int.from_bytes(d[pos + 1 : pos + 9], "big")
            if kind == _SKIP or (length == 0 and kind in _VC_TYPES):
                break  # fst2vcd stops here: a file still being written
            if length < 8 or pos + 1 + length > self.size:
                raise self.error(
                    pos, f"block of type {kind} has length {length}, but the file has "
                    f"{self.size - pos - 1} bytes from there (cut off?)",
                )  # fmt: skip
            body = pos + 9
            if kind == _HDR:
                if pos != 0 or length != _HEADER_BYTES:
                    raise self.error(pos, f"a header block of length {length} (expected 329)")
                self._header(body)
            elif kind in _VC_TYPES:
                blk = self._vc_block(kind, pos + 1, length)
                if blk.pack == ord("F"):
                    raise FstUnsupported("changes packed with FastLZ")
                self.blocks.append(blk)
            elif kind in (_HIER, _HIER_LZ4, _HIER_LZ4DUO):
                hier = (kind, pos + 1, length)
            elif kind not in (_BLACKOUT, _GEOM):  # widths come from the hierarchy, as in fst2vcd
                raise self.error(pos, f"unknown block type {kind}")
            pos += 1 + length
        if hier is None:
            raise self.error(pos, "no hierarchy block")
        self.header = self._hierarchy(*hier)

    def _header(self, at: int) -> None:
        c = _Cursor(self, self.data, at, 0, "header")
        c.u64(), c.u64()  # start and end time (fst2vcd prints the blocks' times)
        if np.frombuffer(self.data[at + 16 : at + 24], "<f8")[0] != _ENDIAN_TEST:
            raise self.error(at + 16, "the header's check number is wrong (not an FST file)")
        c.pos += 8
        c.pos += 5 * 8  # writer's memory use, scope, variable, signal and block counts
        exp = int.from_bytes(self.data[c.pos : c.pos + 1], "big", signed=True)
        c.pos += 1
        self.version = bytes(self.data[c.pos : c.pos + 128]).split(b"\0", 1)[0]
        unit = _UNITS.get(exp - exp % 3 if -21 <= exp <= 2 else -9, "ns")
        mag = 10 ** (exp % 3) if -21 <= exp <= 2 else 1
        self.timescale_text = f"{mag} {unit}"
        self.tick = (mag, unit)

    def _inflate(self, at: int, packed: int, full: int, what: str, always: bool = False) -> bytes:
        """``packed`` bytes at ``at``: as they are when ``packed == full`` (unless ``always``),
        else inflated (zlib or gzip) to exactly ``full`` bytes."""
        if at + packed > self.size:
            raise self.error(at, f"{what}: {packed} bytes past the end of the file")
        data = self.data[at : at + packed]
        if packed == full and not always:
            return bytes(data)
        if full > _MAX_RATIO * packed + (1 << 20):
            raise self.error(at, f"{what}: {packed} bytes said to expand to {full}")
        inflate = zlib.decompressobj(47)
        try:
            out = inflate.decompress(data, full + 1)
        except zlib.error as err:
            raise self.error(at, f"{what}: bad compressed data ({err})") from None
        if not inflate.eof:
            raise self.error(at, f"{what}: the compressed data is cut off")
        if len(out) != full:
            raise self.error(at, f"{what}: expands to {len(out)} bytes, not {full}")
        return out

    def _unlz4(self, at: int, packed: int, full: int, what: str) -> bytes:
        """``packed`` bytes at ``at`` LZ4-decompressed (one LZ4 block) to ``full`` bytes."""
        if packed < 0 or at + packed > self.size:
            raise self.error(at, f"{what}: {packed} bytes past the end of the file")
        return _lz4(self, self.data[at : at + packed], full, at, what)

    def _vc_block(self, kind: int, at: int, length: int) -> VcBlock:
        end = at + length
        c = _Cursor(self, self.data, at + 8, 0, "value change block")
        begin = c.u64()
        if begin >= 1 << 63:
            raise self.error(at + 8, f"value change block starting at time {begin} (≥ 2^63)")
        c.u64(), c.u64()  # end time, memory the reader needs
        f_full, f_packed, f_count = c.varint(), c.varint(), c.varint()
        frame = (c.pos, f_full, f_packed, f_count)
        c.pos += f_packed
        waves_count = c.varint()
        waves = c.pos
        pack = c.byte()
        if end - 24 < c.pos:
            raise c.fail(f"block of {length} bytes too short for its parts")
        t = _Cursor(self, self.data, end - 24, 0, "value change block's time table")
        t_full, t_packed, t_count = t.u64(), t.u64(), t.u64()
        index_end = end - 24 - t_packed - 8
        if index_end < c.pos:
            raise t.fail(f"time table of {t_packed} bytes does not fit its block")
        index_len = _Cursor(self, self.data, index_end, 0, "position table").u64()
        index_at = index_end - index_len
        if index_at < c.pos:
            raise self.error(index_end, f"position table of {index_len} bytes does not fit")
        if t_count > t_full:
            raise t.fail(f"{t_count} times in {t_full} bytes")
        return VcBlock(
            kind, at, length, begin, frame, waves, waves_count, pack, (index_at, index_len),
            (end - 24 - t_packed, t_full, t_packed, t_count),
        )  # fmt: skip

    # --- the hierarchy ----------------------------------------------------------------------

    def _hierarchy(self, kind: int, at: int, length: int) -> VcdHeader:
        c = _Cursor(self, self.data, at + 8, 0, "hierarchy block")
        full = c.u64()
        if kind == _HIER:  # gzip
            raw = self._inflate(at + 16, length - 16, full, "hierarchy", always=True)
        elif kind == _HIER_LZ4:
            raw = self._unlz4(at + 16, length - 16, full, "hierarchy")
        else:  # LZ4 twice: the once-compressed length first
            once = c.u64()
            if once > _MAX_RATIO * length + (1 << 20):
                raise c.fail(f"{length} bytes said to expand to {once}")
            raw = _lz4(self, self._unlz4(at + 24, length - 24, once, "hierarchy"), full, at)
        c = _Cursor(self, raw, 0, at + 16, "hierarchy (uncompressed)")
        scope: list[str] = []
        decls: list[VarDecl] = []
        not_utf8: list[str] = []
        handles = 0
        while c.pos < len(raw):
            tag = c.byte()
            if tag == _SCOPE:
                kind = c.byte()
                name = c.text()
                c.text()  # component
                said = (_SCOPE_TYPES[kind] if kind < len(_SCOPE_TYPES) else "module").encode()
                scope.append(decode_name((said + b" " + name).split()[-1], not_utf8))
            elif tag == _UPSCOPE:
                if scope:
                    scope.pop()
            elif tag == _ATTRBEGIN:
                c.byte(), c.byte(), c.text(), c.varint()  # fst2vcd prints none by default
            elif tag < len(_VAR_TYPES):
                c.byte()  # direction
                name = c.text()
                size, alias = c.varint(), c.varint()
                if alias == 0:
                    handles += 1
                    handle = handles
                    self.lengths.append(size)  # fst2vcd decodes by this width (signal_lens)
                else:
                    handle = alias
                if len(decls) >= MAX_VARS:
                    raise c.fail(f"more than {MAX_VARS} variables")
                if tag in _REAL_TYPES:
                    size = 32 if tag == 29 else 64
                elif tag == _PORT:
                    size = max(size - 2, 0) // 3
                words = name.split()
                if not words or size < 1:
                    raise c.fail(f"variable {name[:40]!r} of {size} bits (fst2vcd writes "
                                 "no readable $var for it)")  # fmt: skip
                ref = (
                    b" ".join(words[:-1]) + words[-1]
                    if len(words) > 1 and words[-1].startswith(b"[")
                    else b" ".join(words)
                )
                decls.append(
                    VarDecl(_VAR_TYPES[tag], size, str(handle), decode_name(ref, not_utf8),
                            tuple(scope), 0)
                )  # fmt: skip
            # other tags (attribute end, unknown) are skipped byte by byte, as fst2vcd does
        notes = not_utf8_notes(not_utf8)
        mag, unit = self.tick
        tb = Timebase.from_timescale(mag, unit)
        if not Fraction(1, 10**15) <= tb.tick_s <= 100:
            raise self.error(0, f"time scale {mag} {unit} is outside 1 fs … 100 s")
        version = " ".join(decode_name(self.version, []).split())
        return VcdHeader(tb, self.timescale_text, decls, [], 0, 0, version, notes)

    # --- a block's changes ------------------------------------------------------------------

    def frame(self, b: VcBlock) -> bytes:
        """The values of every signal at the block's start (``lengths`` bytes each)."""
        at, full, packed, _ = b.frame
        return self._inflate(at, packed, full, "frame")

    def time_table(self, b: VcBlock) -> npt.NDArray[np.int64]:
        """The block's times (ticks, increasing)."""
        at, full, packed, count = b.times
        raw = self._inflate(at, packed, full, "time table")
        try:
            deltas = varints(np.frombuffer(raw, np.uint8))
        except ValueError as err:
            raise self.error(at, f"time table: {err}") from None
        if len(deltas) < count:
            raise self.error(at, f"time table: {len(deltas)} times, {count} declared")
        if count and int(deltas[:count].max()) >= 1 << 63:
            raise self.error(at, "time table: a time beyond 2^63 ticks")
        times = deltas[:count].view(np.int64)
        np.cumsum(times, out=times)  # in place: a block's table can hold millions of times
        if count and (int(times[-1]) < 0 or bool((times[1:] < times[:-1]).any())):
            raise self.error(at, "time table: a time beyond 2^63 ticks")  # the sum wrapped
        return times

    def positions(self, b: VcBlock) -> tuple[list[int], list[int]]:
        """Each handle's (index handle-1) offset of its changes from ``b.waves`` (0: none in
        this block) and their length in bytes, aliases resolved (fstReaderIterBlocks2)."""
        at, length = b.index
        c = _Cursor(self, self.data[at : at + length], 0, at, "position table")
        n = b.waves_count
        if n > len(self.lengths) + 1 or n > MAX_VARS:
            raise c.fail(f"{n} signals, the file declares {len(self.lengths)}")
        offs = [0] * (n + 1)
        alias = [0] * (n + 1)  # > 0: handle index + 1 whose data this one shares
        idx = prev_idx = pval = prev_alias = 0
        lens = [0] * (n + 1)
        has_prev = False
        while c.pos < length:
            first = c.data[c.pos]
            if b.kind == _VCDATA_DYN_ALIAS2 and first & 1:
                shval = c.svarint() >> 1
                if idx >= n + 1:
                    raise c.fail("more entries than signals")
                if shval > 0:
                    pval += shval
                    offs[idx] = pval
                    if has_prev:
                        lens[prev_idx] = pval - offs[prev_idx]
                    prev_idx, has_prev = idx, True
                else:
                    if shval < 0:
                        prev_alias = -shval
                    alias[idx] = prev_alias
                idx += 1
            elif b.kind != _VCDATA_DYN_ALIAS2:
                val = c.varint()
                if val == 0:
                    alias[min(idx, n)] = c.varint()
                    idx += 1
                elif val & 1:
                    pval += val >> 1
                    if idx >= n + 1:
                        raise c.fail("more entries than signals")
                    offs[idx] = pval
                    if has_prev:
                        lens[prev_idx] = pval - offs[prev_idx]
                    prev_idx, has_prev = idx, True
                    idx += 1
                else:
                    idx += val >> 1
            else:
                idx += c.varint() >> 1
            if idx > n + 1:
                raise c.fail(f"entries for {idx} signals, the block has {n}")
        if has_prev:
            lens[prev_idx] = (at - b.waves) - offs[prev_idx]
        for i in range(min(idx, n)):
            k = alias[i] - 1
            if offs[i] == 0 and 0 <= k < i:
                offs[i], lens[i] = offs[k], lens[k]
        if any(o + ln > at - b.waves or ln < 0 for o, ln in zip(offs, lens, strict=True)):
            raise c.fail("a signal's changes lie outside the block")
        return offs[:n], lens[:n]

    def wave(self, b: VcBlock, offset: int, length: int) -> npt.NDArray[np.uint8]:
        """A signal's changes in block ``b`` (decompressed)."""
        at = b.waves + offset
        c = _Cursor(self, self.data[at : at + length], 0, at, "signal changes")
        full = c.varint()
        if full == 0:
            return np.frombuffer(self.data[at + c.pos : at + length], np.uint8)
        if b.pack == ord("4"):
            raw = self._unlz4(at + c.pos, length - c.pos, full, "signal changes")
        else:
            raw = self._inflate(at + c.pos, length - c.pos, full, "signal changes", always=True)
        return np.frombuffer(raw, np.uint8)


def _lz4(fst: FstFile, data: bytes, full: int, at: int, what: str = "hierarchy") -> bytes:
    """One LZ4 block expanded to exactly ``full`` bytes (LZ4 expands a byte at most 255-fold)."""
    import lz4.block

    if full > 256 * len(data) + 64:
        raise fst.error(at, f"{what}: {len(data)} bytes said to expand to {full}")
    try:
        out = lz4.block.decompress(data, uncompressed_size=full)
    except (lz4.block.LZ4BlockError, ValueError) as err:
        raise fst.error(at, f"{what}: bad LZ4 data ({err})") from None
    if len(out) != full:
        raise fst.error(at, f"{what}: expands to {len(out)} bytes, not {full}")
    return out


def scalar_changes(
    fst: FstFile, data: npt.NDArray[np.uint8], ntimes: int, at: int
) -> tuple[npt.NDArray[np.signedinteger], npt.NDArray[np.int8]]:
    """A 1-bit signal's changes in a block: (time index, value code). Each is one varint:
    ``delta << 2 | value << 1`` for 0/1, ``delta << 4 | code << 1 | 1`` for x, z, … ."""
    if len(data) and int(data.max()) < 0x80:  # one byte each (deltas < 32): stay in uint8
        v: npt.NDArray[np.unsignedinteger] = data
    else:
        try:
            v = varints(data)
        except ValueError as err:
            raise fst.error(at, f"a signal's changes: {err}") from None
    one = v.dtype.type(1)
    binary = (v & one) == 0
    delta = np.where(binary, v >> v.dtype.type(2), v >> v.dtype.type(4))
    if len(v) and int(delta.max()) >= ntimes:
        raise fst.error(at, f"a signal's change at time {int(delta.max())} of {ntimes}")
    end = int(delta.sum(dtype=np.uint64))  # each < ntimes < 2^63, at most 2^32 of them
    if end >= ntimes:
        raise fst.error(at, f"a signal's change at time {end} of {ntimes}")
    idx: npt.NDArray[np.signedinteger] = np.cumsum(
        delta, dtype=np.int32 if ntimes < 1 << 31 else np.int64
    )
    codes = _RCV[(v >> one) & v.dtype.type(7)]
    codes[binary] = ((v[binary] >> one) & one).astype(np.int8)
    if (codes < 0).any():
        raise fst.error(at, "a signal's value '?' (not a VCD value)")
    return idx, codes


def vector_changes(
    fst: FstFile, data: bytes, width: int, ntimes: int, at: int
) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.uint8]]:
    """A vector's changes in a block: (time index, its digits as characters, one row each).
    Each is a varint ``delta << 1 | text`` then ``width`` characters (text) or its bits packed
    most significant first. A Python loop per change: only a vector a bit is mapped from."""
    idx: list[int] = []
    rows: list[bytes] = []
    pos, t, n = 0, 0, len(data)
    packed = (width + 7) // 8
    while pos < n:
        vli = shift = 0
        while True:
            if pos >= n or shift > 63:
                raise fst.error(at + pos, "a vector's changes are cut off")
            byte = data[pos]
            pos += 1
            vli |= (byte & 0x7F) << shift
            shift += 7
            if not byte & 0x80:
                break
        t += vli >> 1
        if t >= ntimes:
            raise fst.error(at + pos, f"a vector's change at time {t} of {ntimes}")
        size = width if vli & 1 else packed
        if pos + size > n:
            raise fst.error(at + pos, "a vector's changes are cut off")
        raw = data[pos : pos + size]
        pos += size
        if not vli & 1:
            bits = np.unpackbits(np.frombuffer(raw, np.uint8))[:width]
            raw = (bits + ord("0")).astype(np.uint8).tobytes()
        idx.append(t)
        rows.append(raw)
    chars = np.frombuffer(b"".join(rows), np.uint8).reshape(len(rows), width)
    return np.array(idx, np.int64), chars
