"""VCD reader: 1-bit wires of any scope into exact edge arrays, streamed in chunks.

Chosen by measurement (``../shared/reference/vcd-perf.md``, ``bench/vcd_read.py``): a vectorised
numpy tokenizer over fixed-size chunks beats pywellen and vcdvcd and lets us own the error
messages. The header is parsed in Python; the body is split into whitespace tokens with numpy,
timestamps are decoded digit column by digit column, id codes go through a lookup table (or a
packed-integer ``searchsorted`` for multi-character ids), and each chunk's changes are turned
into edges at once. Changes at a chunk's last timestamp are held back until the next chunk, so a
timestamp split over two chunks cannot create a fake edge. Memory: one chunk of text plus its
token arrays, plus the edge arrays (the pieces and, at the end, their concatenation).

Speed (``bench/README.md`` has the profiles): whitespace is found with two comparisons per byte,
timestamps are decoded 8 digits at a time in ``uint64`` words (SWAR), a change's timestamp is
counted rather than searched when a chunk holds only timestamps and changes, the sort by signal
is numpy's radix sort on ``int16``, and line numbers (for messages only) are counted from the
file when an error is raised. Chunks are 384 KiB: each chunk costs ~150 numpy calls whatever
its size, so 192 KiB chunks were ~9 % slower (round 6); with 1 MiB chunks the per-chunk token
arrays (several MB) are returned to the kernel and faulted in again chunk after chunk, which on
this VM costs more kernel time (0.5 s per 10 M changes) than the whole tokenizer. A whole read
writes each signal's edges into one growing buffer (peak RSS −20 % on 10 M changes).

Semantics (identical in :func:`wavecheck.capture.vcd.reference.read_vcd_reference`, the
deliberately simple path):

* times are the integer timestamps, ticks of ``$timescale``; changes before the first ``#`` are
  at 0; a timestamp smaller than the previous one is an error;
* several changes of one signal at one timestamp: the last one wins (no zero-width glitch);
* a change to the current level is not an edge;
* ``x``/``z`` (also ``u w -``) are unknown: the level before the first known value is not
  invented (:attr:`Channel.known_from`), a later unknown stretch is listed in
  :attr:`Channel.xz_times` / :attr:`Channel.xz_ends`, and edges compare known levels only; ``l``/``h`` read as 0/1;
* vectors, integers and reals are skipped (listed in :attr:`Capture.skipped` and a note), except
  a ``b`` change of a 1-bit signal, which is read as a scalar.
"""

from __future__ import annotations

import contextlib
import os
import re
from collections.abc import Iterable, Iterator
from dataclasses import replace
from fractions import Fraction
from typing import TYPE_CHECKING, BinaryIO

import numpy as np

from wavecheck.capture.edges import NEVER, Capture, Channel, Vector
from wavecheck.capture.vcd.header import (
    SignalEdges,
    build_capture,
    header_timebase,
    layout_of,
    open_vcd,
    read_header,
    vector_of,
    vectors_of,
)
from wavecheck.errors import CaptureError, UsageError
from wavecheck.progress import current

if TYPE_CHECKING:
    import numpy.typing as npt

    from wavecheck.capture.blocks import EdgeBlock

__all__ = ["DEFAULT_CHUNK_BYTES", "MAX_TOKEN_BYTES", "VcdBlocks", "read_vcd"]

DEFAULT_CHUNK_BYTES = 384 << 10  # see the note on chunk size in the module docstring
#: Longest token (or body ``$comment``) held whole: a 16-Mbit vector value. Longer is refused, so
#: a body without whitespace (binary junk, a sparse file) cannot take the memory.
MAX_TOKEN_BYTES = 16 << 20
_MAX_TIME_DIGITS = 19
_LEADING_WS = re.compile(rb"\s*")
_INT64_MAX = (1 << 63) - 1

# Byte classes of the body tokenizer. Whitespace is b" \t\n\v\f\r" (9 … 13 and 32), tested
# with two comparisons (:func:`_token_bounds`), ~10× faster than a 256-entry lookup per byte.
_K_BAD, _K_TIME, _K_SCALAR, _K_VEC, _K_KEYWORD, _K_SKIP, _K_VECID = 0, 1, 2, 3, 4, 5, 6
_KIND = np.zeros(256, dtype=np.int8)
_KIND[ord("#")] = _K_TIME
for _c in "01xXzZuUwWlLhH-":
    _KIND[ord(_c)] = _K_SCALAR
for _c in "bBrR":
    _KIND[ord(_c)] = _K_VEC
_KIND[ord("$")] = _K_KEYWORD
# Value codes: 0, 1, 2 = unknown (x u w -), 3 = z.
_VALUE = np.full(256, -1, dtype=np.int8)
for _c, _v in {"0": 0, "1": 1, "l": 0, "L": 0, "h": 1, "H": 1, "z": 3, "Z": 3}.items():
    _VALUE[ord(_c)] = _v
for _c in "xXuUwW-":
    _VALUE[ord(_c)] = 2
_BODY_KEYWORDS = {b"$dumpvars", b"$dumpall", b"$dumpon", b"$dumpoff", b"$end"}
# Timestamps of up to 16 digits are decoded 8 digits at a time in a uint64 (SWAR, see
# :func:`_digits8`); longer ones (≥ 10^16 ticks, rare) digit column by digit column.
_SWAR_DIGITS = 16
_U64 = np.uint64
# _KEEP[k]: the k most significant bytes of a little-endian uint64 (the last k characters)
_KEEP = np.array(
    [0] + [(0xFFFF_FFFF_FFFF_FFFF << (8 * (8 - k))) & 0xFFFF_FFFF_FFFF_FFFF for k in range(1, 9)],
    dtype=np.uint64,
)
_PAD = 16  # zero bytes before a chunk, so the 16 bytes before any token can be loaded


# ---------------------------------------------------------------------------------------------
# Fast path


def _runs(s: npt.NDArray[np.integer]) -> zip[tuple[int, int, int]]:
    """(signal, start, end) of each run of one signal in ``s`` (sorted): linear in the batch,
    not in the signal count."""
    cuts = np.flatnonzero(s[1:] != s[:-1]) + 1
    lo = np.concatenate(([0], cuts)) if len(s) else cuts
    hi = np.concatenate((cuts, [len(s)])) if len(s) else cuts
    return zip(s[lo].tolist(), lo.tolist(), hi.tolist(), strict=True)


class _EdgeBuilder:
    """Turns batches of time-ordered (signal, time, value) changes into per-signal edges.

    With ``whole`` (a whole read, :meth:`signals` at the end), each signal's edges are written
    into one buffer grown by doubling (``ndarray.resize``) instead of pieces joined at the end:
    no second copy of every edge at the end (peak RSS 190 → 153 MB on 10 M changes, CPU the
    same within noise; ``bench/README.md``, round 6)."""

    def __init__(self, nsig: int, whole: bool = False) -> None:
        self.nsig = nsig
        self.whole = whole
        self.grown = [np.zeros(0, np.int64) for _ in range(nsig)] if whole else []
        self.filled = [0] * nsig
        self.last_raw = np.full(nsig, -1, dtype=np.int8)
        self.last_known = np.full(nsig, -1, dtype=np.int8)
        self.known_from = np.zeros(nsig, dtype=np.int64)
        self.initial = np.zeros(nsig, dtype=np.int8)
        self.edges: list[list[npt.NDArray[np.int64]]] = [[] for _ in range(nsig)]
        self.xz: list[list[npt.NDArray[np.int64]]] = [[] for _ in range(nsig)]
        self.xz_end: list[list[npt.NDArray[np.int64]]] = [[] for _ in range(nsig)]
        self.count = 0

    def add(
        self,
        sig: npt.NDArray[np.integer],
        t: npt.NDArray[np.int64],
        v: npt.NDArray[np.int8],
    ) -> None:
        """Add changes (in file order, times non-decreasing, all later than earlier batches)."""
        if len(sig) == 0:
            return
        self.count += len(sig)
        # numpy's stable sort is a radix sort for 8/16-bit ints: ~3× faster than on int32
        key = sig.astype(np.int16, copy=False) if self.nsig <= 1 << 15 else sig
        order = np.argsort(key, kind="stable")
        s, t, v = sig[order], t[order], v[order]
        keep = np.ones(len(s), dtype=bool)
        keep[:-1] = (s[1:] != s[:-1]) | (t[1:] != t[:-1])  # last change at a timestamp wins
        if not keep.all():
            s, t, v = s[keep], t[keep], v[keep]
        n = len(s)
        gfirst = np.ones(n, dtype=bool)
        gfirst[1:] = s[1:] != s[:-1]
        glast = np.ones(n, dtype=bool)
        glast[:-1] = gfirst[1:]
        # x/z stretches (where they begin and where a known value comes back), counted only
        # once the signal has had a known level
        unknown = v >= 2
        if unknown.any() or (self.last_raw[s[gfirst]] >= 2).any():
            known = ~unknown
            prevraw = np.empty(n, dtype=np.int8)
            prevraw[1:] = v[:-1]
            prevraw[gfirst] = self.last_raw[s[gfirst]]
            kcum = np.cumsum(known)
            excl: npt.NDArray[np.int64] = kcum - known
            start_idx = np.maximum.accumulate(np.where(gfirst, np.arange(n), 0))
            before: npt.NDArray[np.int64] = excl - excl[start_idx]
            had_known = (before > 0) | (self.last_known[s] >= 0)
            evt = unknown & had_known & (prevraw >= 0) & (prevraw < 2)
            if evt.any():
                self._split(self.xz, s[evt], t[evt])
            back = known & had_known & (prevraw >= 2)
            if back.any():
                self._split(self.xz_end, s[back], t[back])
        self.last_raw[s[glast]] = v[glast]
        k = np.flatnonzero(v < 2)
        if len(k) == 0:
            return
        if len(k) == n:  # no x/z in the batch: the same arrays
            ks, kt, kv, kfirst, klast = s, t, v, gfirst, glast
        else:
            ks, kt, kv = s[k], t[k], v[k]
            kfirst = np.ones(len(ks), dtype=bool)
            kfirst[1:] = ks[1:] != ks[:-1]
            klast = np.ones(len(ks), dtype=bool)
            klast[:-1] = kfirst[1:]
        prev = np.empty(len(kv), dtype=np.int8)
        prev[1:] = kv[:-1]
        prev[kfirst] = self.last_known[ks[kfirst]]
        new = kfirst & (prev < 0)
        if new.any():
            self.initial[ks[new]] = kv[new]
            self.known_from[ks[new]] = kt[new]
        edge = (prev >= 0) & (kv != prev)
        if self.whole:
            self._grow(ks[edge], kt[edge])
        else:
            self._split(self.edges, ks[edge], kt[edge])
        self.last_known[ks[klast]] = kv[klast]

    def _split(
        self,
        into: list[list[npt.NDArray[np.int64]]],
        s: npt.NDArray[np.integer],
        t: npt.NDArray[np.int64],
    ) -> None:
        for i, a, b in _runs(s):
            # a copy, not a view: a view would keep this batch's whole array alive until every
            # channel is joined, doubling the peak memory of :meth:`channels`
            into[i].append(t[a:b].astype(np.int64, copy=True))

    def _grow(self, s: npt.NDArray[np.integer], t: npt.NDArray[np.int64]) -> None:
        """Append each run of one signal in ``s`` (sorted) to that signal's buffer."""
        for i, a, b in _runs(s):
            buf, n = self.grown[i], self.filled[i]
            need = n + b - a
            if need > len(buf):  # no view of the buffer exists before signals()
                buf.resize(max(need, 2 * len(buf), 4096), refcheck=False)
            buf[n:need] = t[a:b]
            self.filled[i] = need

    def signals(self) -> list[SignalEdges]:
        """Each signal's edges, joined (the pieces are released as they are joined)."""
        out: list[SignalEdges] = []
        for i in range(self.nsig):
            if self.whole:
                edges = self.grown[i]
                edges.resize(self.filled[i], refcheck=False)
                self.grown[i] = np.zeros(0, np.int64)
            else:
                edges = _concat(self.edges[i])
            self.edges[i] = []
            known = self.last_known[i] >= 0
            out.append(
                SignalEdges(
                    initial=int(self.initial[i]) if known else 0,
                    known_from=int(self.known_from[i]) if known else None,
                    edges=edges,
                    xz_times=_concat(self.xz[i]),
                    xz_ends=_ends(_concat(self.xz[i]), _concat(self.xz_end[i])),
                )
            )
        return out


#: The change-to-edge builder, shared with the other simulator-dump readers
#: (:mod:`wavecheck.capture.wellen`) so every format has the VCD reader's semantics.
EdgeBuilder = _EdgeBuilder


def _concat(parts: list[npt.NDArray[np.int64]]) -> npt.NDArray[np.int64]:
    if not parts:
        return np.zeros(0, dtype=np.int64)
    if len(parts) == 1:
        return parts[0]
    return np.concatenate(parts)


def _ends(starts: npt.NDArray[np.int64], back: npt.NDArray[np.int64]) -> npt.NDArray[np.int64]:
    """One end per x/z stretch: where a known value came back, :data:`NEVER` for the last
    stretch when none did."""
    if len(back) == len(starts):
        return back
    return np.concatenate([back, np.full(len(starts) - len(back), NEVER, dtype=np.int64)])


class _IdMap:
    """Maps id-code tokens to channel numbers (−2 = a skipped vector/real, −1 = unknown,
    −3 − k = vector ``k`` of the bits read: :class:`_BitPlan`)."""

    def __init__(
        self, ids: list[str], vector_ids: set[str], wanted: dict[str, int] | None = None
    ) -> None:
        wanted = wanted or {}
        allid = [(c, i) for i, c in enumerate(ids)] + [
            (c, -3 - wanted[c] if c in wanted else -2) for c in vector_ids
        ]
        self.maxlen = max((len(c.encode("latin-1")) for c, _ in allid), default=1)
        if self.maxlen == 1:
            self.lut = np.full(256, -1, dtype=np.int32)
            for c, i in allid:
                self.lut[c.encode("latin-1")[0]] = i
        else:
            keys = np.array([self._pack(c.encode("latin-1")) for c, _ in allid], dtype=np.uint64)
            vals = np.array([i for _, i in allid], dtype=np.int32)
            order = np.argsort(keys)
            self.keys, self.vals = keys[order], vals[order]

    @staticmethod
    def _pack(b: bytes) -> int:
        return int.from_bytes(b, "little")

    def lookup(
        self, a: npt.NDArray[np.uint8], start: npt.NDArray[np.int64], length: npt.NDArray[np.int64]
    ) -> npt.NDArray[np.int32]:
        """Channel numbers of the ids at ``a[start : start + length]``."""
        if self.maxlen == 1:
            if len(length) and int(length.min()) == int(length.max()) == 1:
                return self.lut[a[start]]
            one = length == 1
            out = np.full(len(start), -1, dtype=np.int32)
            out[one] = self.lut[a[start[one]]]
            return out
        ok = (length >= 1) & (length <= self.maxlen)
        packed = np.zeros(len(start), dtype=np.uint64)
        for k in range(self.maxlen):
            m = ok & (length > k)
            packed[m] |= a[start[m] + k].astype(np.uint64) << np.uint64(8 * k)
        pos = np.searchsorted(self.keys, packed)
        pos[pos >= len(self.keys)] = 0
        out = self.vals[pos].copy()
        out[(self.keys[pos] != packed) | ~ok] = -1
        return out


class _Body:
    """Streaming state of the fast body tokenizer."""

    def __init__(
        self,
        path: str | os.PathLike[str],
        idmap: _IdMap,
        builder: _EdgeBuilder,
        line0: int,
        offset0: int,
        source: BinaryIO | None = None,
        bits: list[list[tuple[int, int]]] | None = None,
    ) -> None:
        self.path = path
        self.idmap = idmap
        self.bits = bits or []  # per vector read: (bit position from the right, channel)
        self.builder = builder
        self.offset0 = offset0  # file offset of the next buffer
        # Line numbers are for messages only: with a seekable ``source`` they are counted when
        # an error is raised (newlines re-read from ``line_at`` on); else as the buffers go by.
        self.line0 = line0  # line number of the byte at file offset ``line_at``
        self.line_at = offset0
        self.source = source
        self.time: int | None = None  # current timestamp
        self.first_time: int | None = None
        self.pre_time_changes = False
        self.pend: (
            tuple[npt.NDArray[np.int32], npt.NDArray[np.int64], npt.NDArray[np.int8]] | None
        ) = None

    def advance(self, buf: bytes, n: int) -> None:
        """The first ``n`` bytes of ``buf`` are consumed: the next buffer starts after them."""
        if self.source is None:
            self.line0 += buf.count(b"\n", 0, n)
            self.line_at += n
        self.offset0 += n

    def error(self, buf: bytes, off: int, msg: str) -> CaptureError:
        if self.source is not None and self.line_at < self.offset0:
            self.line0 += _count_newlines(self.source, self.line_at, self.offset0)
            self.line_at = self.offset0
        line = self.line0 + buf.count(b"\n", 0, off)
        return CaptureError(self.path, f"line {line} (byte {self.offset0 + off})", msg)

    def feed(self, buf: bytes, final: bool, size: int | None = None) -> int:
        """Process ``buf[:size]`` (which ends at whitespace unless ``final``; all of ``buf`` when
        ``size`` is None); return bytes consumed."""
        a = np.frombuffer(buf, dtype=np.uint8, count=len(buf) if size is None else size)
        if len(a) == 0:
            if final:
                self._flush(final=True)
            return 0
        starts, ends = _token_bounds(a)
        kind = _KIND[a[starts]]
        consumed = len(a)
        vid: npt.NDArray[np.bool_] | None = None
        # only timestamps and scalar changes (the usual chunk): no keyword, vector or bad token
        if len(kind) and (int(kind.min()) < _K_TIME or int(kind.max()) > _K_SCALAR):
            # 1. $comment ... $end in the body is skipped whole (rare: a Python loop is fine)
            kw = np.flatnonzero((kind == _K_KEYWORD) & (ends - starts == 8))
            after = 0
            for i in (int(x) for x in kw):
                if i < after or buf[starts[i] : ends[i]] != b"$comment":
                    continue
                close = i + 1
                while close < len(kind) and buf[starts[close] : ends[close]] != b"$end":
                    close += 1
                if close == len(kind):
                    if final:
                        raise self.error(
                            buf, int(starts[i]), "$comment without $end (the file is cut off)"
                        )
                    consumed = int(starts[i])
                    kind, starts, ends = kind[:i], starts[:i], ends[:i]
                    break
                kind[i : close + 1] = _K_SKIP
                after = close + 1
            # 2. vector/real values take the next token as their id: resolve runs of b/r by parity
            isvec = kind == _K_VEC
            if isvec.any():
                idx = np.arange(len(kind))
                run_start = isvec.copy()
                run_start[1:] &= ~isvec[:-1]
                first = np.maximum.accumulate(np.where(run_start, idx, 0))
                vstart = isvec & ((idx - first) % 2 == 0)
                if vstart[-1]:
                    last = len(kind) - 1
                    if final:
                        raise self.error(
                            buf,
                            int(starts[last]),
                            "vector value without an id code (the file is cut off)",
                        )
                    consumed = min(consumed, int(starts[last]))
                    kind, starts, ends, vstart = (
                        kind[:last],
                        starts[:last],
                        ends[:last],
                        vstart[:last],
                    )
                vid = np.zeros(len(kind), dtype=bool)
                vid[1:] = vstart[:-1]
                kind[vid] = _K_VECID
                kind[vstart] = _K_SKIP
            # 3. the other keywords only mark sections of dumped values
            for i in (int(x) for x in np.flatnonzero(kind == _K_KEYWORD)):
                if buf[starts[i] : ends[i]] not in _BODY_KEYWORDS:
                    word = buf[starts[i] : min(ends[i], starts[i] + 30)].decode("latin-1")
                    raise self.error(
                        buf, int(starts[i]), f"unexpected {word!r} in the value changes"
                    )
            bad = np.flatnonzero(kind == _K_BAD)
            if len(bad):
                i = int(bad[0])
                tok = buf[starts[i] : min(ends[i], starts[i] + 30)]
                hint = " (NUL bytes: the file was cut off or padded)" if tok[:1] == b"\0" else ""
                raise self.error(
                    buf,
                    int(starts[i]),
                    f"unexpected {tok.decode('latin-1')!r} in the value changes{hint}",
                )
        # timestamps
        ts = np.flatnonzero(kind == _K_TIME)
        tvals = self._timestamps(buf, a, starts[ts], ends[ts])
        # scalar changes: value char + id
        sc = np.flatnonzero(kind == _K_SCALAR)
        sig = self.idmap.lookup(a, starts[sc] + 1, ends[sc] - starts[sc] - 1)
        val = _VALUE[a[starts[sc]]]
        if vid is not None and vid.any():
            vi = np.flatnonzero(vid)
            vsig = self.idmap.lookup(a, starts[vi], ends[vi] - starts[vi])
            if (vsig == -1).any():
                j = int(vi[np.flatnonzero(vsig == -1)[0]])
                code = buf[starts[j] : min(ends[j], starts[j] + 30)].decode("latin-1")
                raise self.error(buf, int(starts[j]), f"unknown id code {code!r}")
            if self.bits and (vsig <= -3).any():  # bits of vectors mapped as channels
                bi, bs, bv = self._bit_changes(a, starts, ends, vi[vsig <= -3], vsig[vsig <= -3])
                merged = np.concatenate([sc, bi])
                order = np.argsort(merged, kind="stable")
                sc = merged[order]
                sig = np.concatenate([sig, bs])[order]
                val = np.concatenate([val, bv])[order]
            onebit = vsig >= 0
            if onebit.any():  # "b1 !" on a 1-bit signal is a scalar change
                vi, vs = vi[onebit], vsig[onebit]
                vv = _VALUE[a[ends[vi - 1] - 1]]
                wrong = ((a[starts[vi - 1]] | 0x20) == ord("r")) | (vv < 0)
                if wrong.any():
                    j = int(vi[np.flatnonzero(wrong)[0]]) - 1
                    raise self.error(buf, int(starts[j]), "bad value for a 1-bit signal")
                merged = np.concatenate([sc, vi])
                order = np.argsort(merged, kind="stable")
                sc = merged[order]
                sig = np.concatenate([sig, vs])[order]
                val = np.concatenate([val, vv])[order]
        if len(sig) and (sig < 0).any():
            j = int(sc[np.flatnonzero(sig < 0)[0]])
            text = buf[starts[j] : min(ends[j], starts[j] + 30)].decode("latin-1")
            if ends[j] - starts[j] == 1:
                msg = f"value {text!r} without an id code (the file is cut off?)"
            else:
                msg = f"unknown id code in {text!r} (not declared by a $var, or a vector value without 'b')"
            raise self.error(buf, int(starts[j]), msg)
        # time of each change: the last timestamp before it
        if len(ts) + len(sc) == len(kind):  # only timestamps and changes: count, do not search
            k = sc - np.arange(1, len(sc) + 1)
        else:
            k = np.searchsorted(ts, sc) - 1
        if len(tvals):
            times = tvals[np.maximum(k, 0)]
            if (k < 0).any():
                times[k < 0] = self.time if self.time is not None else 0
        else:
            times = np.full(len(sc), self.time if self.time is not None else 0, dtype=np.int64)
        if self.time is None and len(sc) and (k < 0).any():
            self.pre_time_changes = True
        if len(tvals):
            if self.first_time is None:
                self.first_time = int(tvals[0])
            self.time = int(tvals[-1])
        self._emit(sig.astype(np.int32, copy=False), times, val, final)
        return consumed

    def _bit_changes(
        self,
        a: npt.NDArray[np.uint8],
        starts: npt.NDArray[np.int64],
        ends: npt.NDArray[np.int64],
        vi: npt.NDArray[np.int64],
        code: npt.NDArray[np.int32],
    ) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.int32], npt.NDArray[np.int8]]:
        """The changes of the bits read from vector value tokens: each id token ``vi`` (its
        value ``bVALUE`` just before it) of vector ``-3 - code``, as (token index, channel,
        value code). A value shorter than the vector is extended on the left with its first
        digit when that is x/z, else with 0 (IEEE 1364's rule)."""
        first_digit = starts[vi - 1] + 1
        end = ends[vi - 1]
        length = end - first_digit
        lead = a[np.minimum(first_digit, len(a) - 1)] | 0x20
        pad = np.where((length > 0) & ((lead == ord("x")) | (lead == ord("z"))), lead, ord("0"))
        tok, chan, vals = [], [], []
        for k, plan in enumerate(self.bits):
            sel = np.flatnonzero(code == -3 - k)
            if not len(sel):
                continue
            for pos, channel in plan:
                inside = length[sel] > pos
                ch = np.where(inside, a[np.maximum(end[sel] - 1 - pos, 0)], pad[sel])
                tok.append(vi[sel])
                chan.append(np.full(len(sel), channel, np.int32))
                vals.append(_VALUE[ch.astype(np.uint8)])
        if not tok:
            z = np.zeros(0, np.int64)
            return z, np.zeros(0, np.int32), np.zeros(0, np.int8)
        v = np.concatenate(vals)
        if (v < 0).any():
            j = int(np.concatenate(tok)[np.flatnonzero(v < 0)[0]]) - 1
            raise self.error(bytes(a), int(starts[j]), "bad digit in a vector value")
        return np.concatenate(tok), np.concatenate(chan), v

    def _timestamps(
        self,
        buf: bytes,
        a: npt.NDArray[np.uint8],
        s: npt.NDArray[np.int64],
        e: npt.NDArray[np.int64],
    ) -> npt.NDArray[np.int64]:
        if len(s) == 0:
            return np.zeros(0, dtype=np.int64)
        ndig = e - s - 1
        if (ndig < 1).any():
            j = int(np.flatnonzero(ndig < 1)[0])
            raise self.error(buf, int(s[j]), "bad timestamp '#' (no number after it)")
        if (ndig > _MAX_TIME_DIGITS).any():
            j = int(np.flatnonzero(ndig > _MAX_TIME_DIGITS)[0])
            raise self.error(
                buf,
                int(s[j]),
                f"timestamp {_clip(buf[s[j] : e[j]])} has {int(ndig[j])} digits; times up to "
                f"2^63−1 ticks ({_INT64_MAX}, 19 digits) are supported",
            )
        out = _timestamps_swar(a, e, ndig) if int(ndig.max()) <= _SWAR_DIGITS else None
        if out is None:  # long or bad timestamps: column by column, with the exact messages
            out = self._timestamps_by_column(buf, a, s, e, ndig)
        prev = np.empty(len(out), dtype=np.int64)
        prev[1:] = out[:-1]
        prev[0] = self.time if self.time is not None else -1
        back = np.flatnonzero(out < prev)
        if len(back):
            j = int(back[0])
            raise self.error(
                buf,
                int(s[j]),
                f"time goes backwards: #{int(out[j])} after #{int(prev[j])} "
                "(a cut-off or corrupted file?)",
            )
        return out

    def _timestamps_by_column(
        self,
        buf: bytes,
        a: npt.NDArray[np.uint8],
        s: npt.NDArray[np.int64],
        e: npt.NDArray[np.int64],
        ndig: npt.NDArray[np.int64],
    ) -> npt.NDArray[np.int64]:
        """Timestamps digit column by digit column (any length; 2^63 − 1 checked exactly)."""
        out = np.zeros(len(s), dtype=np.int64)
        bad = np.zeros(len(s), dtype=bool)
        over = np.zeros(len(s), dtype=bool)
        last = e - 1
        scale = 1
        for col in range(int(ndig.max())):
            # right-aligned digit columns; short numbers read the '#' (or before), masked out
            dig = a[np.maximum(last - col, 0)].astype(np.int64) - 48
            valid = ndig > col
            bad |= valid & ((dig < 0) | (dig > 9))
            add = np.where(valid & ~bad, dig, 0) * scale  # 19th digit: at most 9·10^18 < 2^63
            if col == _MAX_TIME_DIGITS - 1:
                over |= out > _INT64_MAX - add  # the sum would pass 2^63 − 1
                add[over] = 0
            out += add
            scale *= 10
        if bad.any():
            j = int(np.flatnonzero(bad)[0])
            raise self.error(
                buf,
                int(s[j]),
                f"bad timestamp {buf[s[j] : e[j]][:30].decode('latin-1')!r} (not a whole number)",
            )
        if over.any():
            j = int(np.flatnonzero(over)[0])
            raise self.error(
                buf,
                int(s[j]),
                f"timestamp {buf[s[j] : e[j]].decode('latin-1')!r} is larger than 2^63−1 "
                f"({_INT64_MAX}), the largest time wavecheck holds",
            )
        return out

    def _emit(
        self,
        sig: npt.NDArray[np.int32],
        t: npt.NDArray[np.int64],
        v: npt.NDArray[np.int8],
        final: bool,
    ) -> None:
        if self.pend is not None:
            ps, pt, pv = self.pend
            sig, t, v = np.concatenate([ps, sig]), np.concatenate([pt, t]), np.concatenate([pv, v])
            self.pend = None
        if not final and len(t):
            # hold back the changes at the last timestamp: the next chunk may add to it
            cut = int(np.searchsorted(t, t[-1], side="left"))
            self.pend = (sig[cut:], t[cut:], v[cut:])
            sig, t, v = sig[:cut], t[:cut], v[:cut]
        self.builder.add(sig, t, v)

    def _flush(self, final: bool) -> None:
        self._emit(np.zeros(0, np.int32), np.zeros(0, np.int64), np.zeros(0, np.int8), final)


def read_vcd(
    path: str | os.PathLike[str],
    *,
    samplerate: Fraction | None = None,
    resolution_s: Fraction | None = None,
    chunk_bytes: int = DEFAULT_CHUNK_BYTES,
    max_token_bytes: int = MAX_TOKEN_BYTES,
    source: BinaryIO | None = None,
) -> Capture:
    """Read the 1-bit signals of a VCD file (fast, streaming path).

    Args:
        path: the VCD file.
        samplerate: the rate the capture was sampled at, in Hz, if known (sets the resolution);
            otherwise sigrok's ``$comment`` ("… at 8 MHz") is used, else the VCD is exact.
        resolution_s: the resolution in seconds, overriding the sample rate's period.
        chunk_bytes: bytes of text tokenized at a time (tests use tiny values).
        max_token_bytes: the longest token (or body ``$comment``) accepted.
        source: an open binary stream to read instead of opening ``path`` (a pipe); ``path``
            then only names it in messages.

    Raises:
        CaptureError: the file cannot be read as a VCD; the message gives the line.
    """
    if chunk_bytes < 1:
        raise UsageError(f"chunk_bytes must be positive, got {chunk_bytes}")
    with contextlib.nullcontext(source) if source is not None else open_vcd(path) as f:
        header, rest = read_header(path, f)
        notes: list[str] = []
        tb = header_timebase(header, notes)
        lay = layout_of(header)
        notes += lay.notes
        builder = _EdgeBuilder(len(lay.ids), whole=True)
        body = _Body(
            path,
            _IdMap(lay.ids, lay.vector_ids),
            builder,
            header.body_line,
            header.body_offset,
            f if source is None and f.seekable() else None,
        )
        for _ in _read_body(f, body, rest, chunk_bytes, max_token_bytes):
            pass
    cap = build_capture(
        path,
        header,
        lay,
        tb,
        builder.signals(),
        body.first_time,
        body.time,
        body.pre_time_changes,
        notes,
        samplerate,
        resolution_s,
    )
    cap.vectors = vectors_of(header)
    cap.bit_source = None if source is not None else os.fspath(path)
    return cap


def _read_body(
    f: BinaryIO, body: _Body, rest: bytes, chunk_bytes: int, max_token_bytes: int
) -> Iterator[bool]:
    """Feed the VCD body after the header (``rest``, then ``f``) to ``body`` chunk by chunk,
    yielding after each chunk whether it was the last (every change then given)."""
    buf = rest
    eof = False
    want = chunk_bytes
    report = current()
    size = _file_size(f)
    while True:
        while not eof and len(buf) < want:
            block = f.read(want - len(buf))
            if not block:
                eof = True
            buf += block
        if eof and len(buf) <= want:
            body.feed(buf, final=True)
            yield True
            break
        cut = _last_ws(buf, want)
        n = body.feed(buf, final=False, size=cut + 1) if cut >= 0 else 0
        body.advance(buf, n)
        report(body.offset0, size)
        buf = buf[n:]
        if not n and len(buf) > max_token_bytes:
            lead = _LEADING_WS.match(buf).end()  # type: ignore[union-attr]  # always matches
            raise body.error(
                buf,
                lead,
                f"a token (or $comment) longer than {max_token_bytes} bytes starts here: "
                "not VCD text (binary data, NUL padding?)",
            )
        # nothing consumed: a token or $comment longer than a chunk, read more (up to the cap)
        want = chunk_bytes if n else min(max(2 * want, len(buf) + 1), max_token_bytes + 1)
        yield False


class VcdBlocks:
    """A VCD read block by block (:class:`wavecheck.capture.blocks.BlockSource`): after each
    chunk of text, the edges of ``channels`` (indices; None: every one) and every channel's
    levels becoming known and x/z stretches; the other channels are only counted. The same
    tokenizer and edge builder as :func:`read_vcd` (same arguments).

    A bit of a vector mapped as a channel (:meth:`Capture.bit` on the skeleton: ``stout[3]``)
    becomes a channel numbered after the file's, its edges read from the vector's value changes
    in the same pass (before :meth:`blocks`).

    The header is read once, here; with ``source`` (an open stream such as standard input,
    ``path`` then only names it) the body is read from it by the one call of :meth:`blocks`."""

    def __init__(
        self,
        path: str | os.PathLike[str],
        *,
        samplerate: Fraction | None = None,
        resolution_s: Fraction | None = None,
        chunk_bytes: int = DEFAULT_CHUNK_BYTES,
        max_token_bytes: int = MAX_TOKEN_BYTES,
        channels: Iterable[int] | None = None,
        source: BinaryIO | None = None,
    ) -> None:
        self.path = path
        self.samplerate, self.resolution_s = samplerate, resolution_s
        self.chunk_bytes, self.max_token_bytes = max(1, chunk_bytes), max_token_bytes
        self._stream = source is not None
        #: a stream's body bytes the header read took (a file is opened again at its body)
        self._body: tuple[BinaryIO, bytes] | None = None
        if source is not None:
            self.header, rest = read_header(path, source)
            self._body = (source, rest)
        else:
            with open_vcd(path) as f:
                self.header, _ = read_header(path, f)
        self._setup(channels)

    def _setup(self, channels: Iterable[int] | None) -> None:
        """The layout, builder and skeleton of ``self.header`` (also the FST reader's)."""
        self.notes: list[str] = []
        self.tb = header_timebase(self.header, self.notes)
        self.lay = layout_of(self.header)
        self.notes += self.lay.notes
        n = len(self.lay.ids)
        self.wanted = set(range(n) if channels is None else channels)
        self.counts = [0] * n
        self.first_time: int | None = None
        self.last_time: int | None = None
        self.pre_time = False
        self.builder = _EdgeBuilder(n)
        self.vectors = vectors_of(self.header)
        self.bit_ids: dict[str, int] = {}  # id code -> vector number among those read
        self.bit_plan: list[list[tuple[int, int]]] = []  # per vector: (position, channel)
        self.bit_channels: list[Channel] = []
        self.skeleton = self._assemble(0, 0, end=False)

    def want(self, channels: Iterable[int]) -> None:
        """Extract the edges of ``channels`` only (from the next block on)."""
        self.wanted = set(channels)

    def _assemble(self, first: int | None, last: int | None, end: bool = True) -> Capture:
        b = self.builder
        sigs = [
            SignalEdges(
                initial=int(b.initial[i]) if b.last_known[i] >= 0 else 0,
                known_from=int(b.known_from[i]) if b.last_known[i] >= 0 else None,
                edges=np.zeros(0, np.int64),
                xz_times=np.zeros(0, np.int64),
                xz_ends=np.zeros(0, np.int64),
            )
            if end
            else SignalEdges(
                0, 0, np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros(0, np.int64)
            )
            for i in range(len(self.lay.ids))
        ]
        cap = build_capture(
            self.path, self.header, self.lay, self.tb, sigs, first, last, self.pre_time,
            list(self.notes), self.samplerate, self.resolution_s,
        )  # fmt: skip
        for ch, k in zip(cap.channels, self.counts, strict=False):
            ch.counted = k
        cap.vectors = dict(self.vectors)
        cap.bit_reader = self._bit
        b = self.builder
        for ch in self.bit_channels:
            i = ch.index
            known = end and i < b.nsig and b.last_known[i] >= 0
            cap.channels.append(
                replace(
                    ch,
                    initial=int(b.initial[i]) if known else 0,
                    known_from=int(b.known_from[i]) if known else 0,
                    never_known=end and not known,
                    counted=self.counts[i] if i < len(self.counts) else 0,
                )
            )
        return cap

    def _bit(self, key: str, vec: Vector, bit: int) -> Channel:
        """Bit ``bit`` (declared index) of vector ``key`` as a new channel, read in the pass."""
        pos = vec.position(bit)
        if pos is None:
            raise UsageError(
                f"{self.path}: {key}{vec.range_text} has no bit {bit} "
                f"(bits {min(vec.msb, vec.lsb)} to {max(vec.msb, vec.lsb)})"
            )
        ids = {
            d.id_code for d in self.header.vars if (v := vector_of(d)) is not None and v.key == key
        }
        ids &= self.lay.vector_ids
        if not ids:
            raise UsageError(f"{self.path}: vector {key!r} has no value changes to read")
        k = next((self.bit_ids[c] for c in ids if c in self.bit_ids), len(self.bit_plan))
        if k == len(self.bit_plan):
            self.bit_plan.append([])
            self.bit_ids.update(dict.fromkeys(ids, k))
        index = len(self.lay.ids) + len(self.bit_channels)
        self.bit_plan[k].append((pos, index))
        self.wanted.add(index)
        self.counts.append(0)
        ch = Channel(f"{key}[{bit}]", index, 0, np.zeros(0, np.int64), counted=0)
        self.bit_channels.append(ch)
        return ch

    def blocks(self) -> Iterator[EdgeBlock]:
        """The edges after each chunk of text (the changes of its last timestamp held back)."""
        b = self.builder = _EdgeBuilder(len(self.lay.ids) + len(self.bit_channels))
        if self._body is not None:
            f, rest = self._body
            self._body = None
        elif self._stream:
            raise UsageError(f"{self.path}: a stream is read once (its blocks were taken already)")
        else:  # a file: opened again at its body (the header was read once, above)
            f, rest = open_vcd(self.path), b""
            f.seek(self.header.body_offset)
        with f:  # a stream too: read once, closed at its end (standard input stays open)
            body = _Body(
                self.path, _IdMap(self.lay.ids, self.lay.vector_ids, self.bit_ids), b,
                self.header.body_line, self.header.body_offset,
                f if not self._stream and f.seekable() else None, self.bit_plan,
            )  # fmt: skip
            known = np.zeros(b.nsig, dtype=bool)
            started = False
            for final in _read_body(f, body, rest, self.chunk_bytes, self.max_token_bytes):
                if body.time is None and not final:
                    continue
                end = NEVER
                if not final and body.time is not None:
                    pend = body.pend
                    end = body.time if pend is None else min(body.time, int(pend[1][0]))
                start = None
                if not started:
                    start = 0 if body.pre_time_changes else (body.first_time or 0)
                    started = True
                block, known = self._take(end, start, known)
                yield block
            self.first_time, self.last_time = body.first_time, body.time
            self.pre_time = body.pre_time_changes

    def _take(
        self, end: int, start: int | None, known: npt.NDArray[np.bool_]
    ) -> tuple[EdgeBlock, npt.NDArray[np.bool_]]:
        """The builder's edges, levels now known (``known``: those known before) and x/z
        stretches as a block ending at ``end``; the builder is emptied."""
        from wavecheck.capture.blocks import EdgeBlock

        b = self.builder
        block = EdgeBlock(end=end, start=start)
        now = b.last_known >= 0
        for i in np.flatnonzero(now & ~known).tolist():
            block.known[i] = (int(b.known_from[i]), int(b.initial[i]))
        for i in range(b.nsig):
            if b.edges[i]:
                e = _concat(b.edges[i])
                b.edges[i] = []
                self.counts[i] += len(e)
                if i in self.wanted:
                    block.edges[i] = e
            if b.xz[i]:
                block.xz_starts[i] = _concat(b.xz[i])
                b.xz[i] = []
            if b.xz_end[i]:
                block.xz_ends[i] = _concat(b.xz_end[i])
                b.xz_end[i] = []
        return block, now

    def capture(self) -> Capture:
        """The whole capture without edges (after :meth:`blocks`)."""
        return self._assemble(self.first_time, self.last_time)


def _clip(token: bytes, keep: int = 30) -> str:
    """``token`` for a message: quoted, cut to ``keep`` bytes with an ellipsis."""
    text = repr(token[:keep].decode("latin-1"))
    return text + "…" if len(token) > keep else text


def _file_size(f: BinaryIO) -> int | None:
    """Size of an open file in bytes, or None when it cannot be told (a pipe)."""
    try:
        return os.fstat(f.fileno()).st_size or None
    except (OSError, AttributeError, ValueError):
        return None


def _last_ws(buf: bytes, limit: int) -> int:
    """Index of the last whitespace byte in ``buf[:limit]`` (−1 if none)."""
    return max(buf.rfind(c, 0, limit) for c in (b"\n", b" ", b"\t", b"\r", b"\f", b"\v"))


def _count_newlines(f: BinaryIO, start: int, stop: int) -> int:
    """Newlines in bytes ``start … stop`` of the seekable ``f`` (its position is kept)."""
    here = f.tell()
    try:
        f.seek(start)
        count = 0
        while start < stop:
            block = f.read(min(1 << 20, stop - start))
            if not block:
                break
            count += block.count(b"\n")
            start += len(block)
        return count
    finally:
        f.seek(here)


def _token_bounds(
    a: npt.NDArray[np.uint8],
) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.int64]]:
    """Start and end (exclusive) of each whitespace-separated token of ``a`` (non-empty).

    Whitespace is 9 … 13 and 32 (``(a − 9) mod 256 > 4`` and ``a ≠ 32`` is a token byte); the
    token bounds are where that changes, every other one a start.
    """
    framed = np.zeros(len(a) + 2, dtype=bool)  # whitespace on both sides: bounds pair up
    notws = framed[1:-1]
    np.greater(a - np.uint8(9), 4, out=notws)
    notws &= a != 32
    bounds = np.flatnonzero(framed[1:] != framed[:-1])
    return bounds[0::2], bounds[1::2]


def _timestamps_swar(
    a: npt.NDArray[np.uint8], e: npt.NDArray[np.int64], ndig: npt.NDArray[np.int64]
) -> npt.NDArray[np.int64] | None:
    """Values of the timestamps whose ``ndig[i]`` (1 … 16) digits end at ``e[i]`` (exclusive),
    or None if any is not all digits (the caller then finds and names it).

    The 8 bytes before each end (and the 8 before those, for the numbers longer than 8 digits)
    are loaded as little-endian ``uint64`` words through an overlapping view with a 1-byte
    stride, and each word is decoded 8 digits at once (:func:`_digits8`).
    """
    at = e - 8  # the word whose last byte is a[e - 1]
    value, bad = _digits8(_words_at(a, at), np.minimum(ndig, 8))
    long = np.flatnonzero(ndig > 8)
    if len(long):
        high, bad_high = _digits8(_words_at(a, at[long] - 8), ndig[long] - 8)
        value[long] += high * _U64(10**8)
        bad[long] |= bad_high
    if bad.any():
        return None
    return value.view(np.int64)


def _words_at(a: npt.NDArray[np.uint8], at: npt.NDArray[np.int64]) -> npt.NDArray[np.uint64]:
    """The little-endian ``uint64`` made of ``a[i : i + 8]`` for each ``i`` in ``at`` (−16 ≤ i ≤
    len(a) − 8; bytes before ``a`` read as zeros): one gather from an overlapping view of ``a``
    with a 1-byte stride."""
    if len(a) >= 8:
        words = np.ndarray((len(a) - 7,), dtype=np.uint64, buffer=a, strides=(1,))
        out = words[np.maximum(at, 0)]
    else:
        out = np.zeros(len(at), dtype=np.uint64)
    early = np.flatnonzero(at < 0)
    if len(early):  # the first tokens of ``a``: from a copy with zeros in front
        head = np.zeros(_PAD + 16, dtype=np.uint8)
        head[_PAD : _PAD + min(16, len(a))] = a[:16]
        hwords = np.ndarray((len(head) - 7,), dtype=np.uint64, buffer=head, strides=(1,))
        out[early] = hwords[at[early] + _PAD]
    return out


def _digits8(
    word: npt.NDArray[np.uint64], keep: npt.NDArray[np.int64]
) -> tuple[npt.NDArray[np.uint64], npt.NDArray[np.bool_]]:
    """The number written by the last ``keep`` (0 … 8) characters of each 8-byte little-endian
    ``word``, and whether any of those is not a digit.

    Characters before them count as leading zeros. XOR with ``"0"`` maps ``"0"…"9"`` to 0 … 9
    and every other byte above 9; ``(x + 0x76) | x`` has its top bit set exactly for a byte
    above 9. Then pairs, quads and octets of digits are combined by multiply-and-add.
    """
    mask = _KEEP[keep]
    x = (word & mask) ^ (_U64(0x3030_3030_3030_3030) & mask)
    bad = (((x + _U64(0x7676_7676_7676_7676)) | x) & _U64(0x8080_8080_8080_8080)) != 0
    x = (x & _U64(0x00FF_00FF_00FF_00FF)) * _U64(10) + (
        (x >> _U64(8)) & _U64(0x00FF_00FF_00FF_00FF)
    )
    x = (x & _U64(0x0000_FFFF_0000_FFFF)) * _U64(100) + (
        (x >> _U64(16)) & _U64(0x0000_FFFF_0000_FFFF)
    )
    x = (x & _U64(0xFFFF_FFFF)) * _U64(10_000) + (x >> _U64(32))
    return x, bad
