"""An FST file as a block source, decoded natively (:mod:`wavecheck.capture.fst`).

The file is read one value-change block at a time: its 1-bit signals' changes are decoded with
numpy and given to the VCD reader's edge builder in slices of about :data:`SLICE_CHANGES`
changes, each an :class:`~wavecheck.capture.blocks.EdgeBlock`, so the capture is the one
``fst2vcd`` piped into the VCD reader gives (same names, aliases, vectors, notes, start and
end) at a fraction of the cost (``bench/fst_read.py``). The changes at a slice's last time are
held back to the next (the time can go on there). A bit of a vector mapped as a channel is
decoded from the vector's changes in the same pass.
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Iterator
from fractions import Fraction
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

from wavecheck.capture.edges import NEVER, Capture
from wavecheck.capture.fst import (
    FRAME_CODES,
    FstFile,
    FstUnsupported,
    VcBlock,
    scalar_changes,
    vector_changes,
)
from wavecheck.capture.vcd.reader import EdgeBuilder, VcdBlocks

if TYPE_CHECKING:
    from wavecheck.capture.blocks import EdgeBlock

__all__ = ["SLICE_CHANGES", "FstNativeBlocks", "read_native"]

#: Changes per block given to the engine (a value-change block of the file can hold millions;
#: slices keep the arrays small, so memory stays flat as in the VCD reader)
SLICE_CHANGES = 1 << 16

_Changes = tuple[npt.NDArray[np.int32], npt.NDArray[np.int64], npt.NDArray[np.int8]]


class FstNativeBlocks(VcdBlocks):
    """An FST file read block by block without ``fst2vcd`` (module docstring).

    Raises (constructor):
        CaptureError: not a readable FST file (the byte is named).
        FstUnsupported: packed in a way this reader does not decode (the caller falls back).
    """

    def __init__(
        self,
        path: str | os.PathLike[str],
        *,
        samplerate: Fraction | None = None,
        resolution_s: Fraction | None = None,
        channels: Iterable[int] | None = None,
        slice_changes: int = SLICE_CHANGES,
    ) -> None:
        self.path = path
        self.slice_changes = max(1, slice_changes)
        self.samplerate, self.resolution_s = samplerate, resolution_s
        self._stream = False
        self._body = None
        self.fst = FstFile(path)
        self.header = self.fst.header
        self._setup(channels)
        self.handles = [int(code) for code in self.lay.ids]
        codes = {d.id_code for d in self.header.vars}
        undeclared = [c for c in codes if self._width(int(c)) < 0]
        if undeclared:
            raise self.fst.error(0, f"a variable aliases signal {undeclared[0]}, never declared")
        wide = [h for h in self.handles if self._width(h) != 1]
        if wide:  # a 1-bit port: stored 3n+2 characters wide (extended VCD)
            raise FstUnsupported(f"signal {wide[0]} is declared 1 bit but stored wider")
        self.skeleton.format = "fst"
        self.skeleton.bit_source = str(path)

    def _width(self, handle: int) -> int:
        lengths = self.fst.lengths
        return lengths[handle - 1] if 0 < handle <= len(lengths) else -1

    def blocks(self) -> Iterator[EdgeBlock]:
        """The file's value-change blocks, each cut into slices of about
        :data:`SLICE_CHANGES` changes; each slice's last time's changes are held back."""
        fst = self.fst
        b = self.builder = EdgeBuilder(len(self.lay.ids) + len(self.bit_channels))
        known = np.zeros(b.nsig, dtype=bool)
        vectors = self._vector_plan()
        pend: _Changes | None = None
        first: int | None = None
        last: int | None = None
        pre_time = False
        for n, blk in enumerate(fst.blocks):
            times = fst.time_table(blk)
            if not len(times):
                continue
            if last is not None and int(times[0]) < last:
                raise fst.error(blk.start, f"time {int(times[0])} after time {last}")
            frame: list[_Changes] = []
            if first is None and n == 0 and blk.begin != int(times[0]):  # fst2vcd's rule
                frame.append(self._frame(blk, vectors))
                if blk.begin:
                    first = blk.begin
                    if first > int(times[0]):
                        raise fst.error(blk.start, f"time {int(times[0])} after time {first}")
                else:
                    pre_time = True
            start = None
            if first is None:
                first = int(times[0])
            if last is None:
                start = 0 if pre_time else first
            changes = self._changes(blk, len(times), vectors)
            total = sum(len(idx) for _, idx, _ in changes)
            cuts = np.linspace(0, len(times), max(1, -(-total // self.slice_changes)) + 1).astype(
                int
            )
            for k0, k1 in zip(cuts[:-1].tolist(), cuts[1:].tolist(), strict=True):
                if k1 <= k0:
                    continue
                parts = ([] if pend is None else [pend]) + frame
                frame = []
                for ch, idx, codes in changes:
                    a, z = np.searchsorted(idx, (k0, k1))
                    if z > a:
                        parts.append((np.full(z - a, ch, np.int32), times[idx[a:z]], codes[a:z]))
                last = int(times[k1 - 1])
                sig = np.concatenate([p[0] for p in parts]) if parts else np.zeros(0, np.int32)
                t = np.concatenate([p[1] for p in parts]) if parts else np.zeros(0, np.int64)
                v = np.concatenate([p[2] for p in parts]) if parts else np.zeros(0, np.int8)
                held = t == last
                pend = (sig[held], t[held], v[held])
                keep = ~held
                b.add(sig[keep], t[keep], v[keep])
                block, known = self._take(last, start, known)
                start = None
                yield block
        if last is None:
            raise fst.error(fst.size, "no value changes (no time in any block)")
        if pend is not None:
            b.add(*pend)
        block, known = self._take(NEVER, None, known)
        self.first_time, self.last_time, self.pre_time = first, last, pre_time
        fst.close()
        yield block

    def _vector_plan(self) -> list[tuple[int, int, list[tuple[int, int]]]]:
        """Per vector read for its bits: (handle, width, [(bit position, channel)])."""
        plan = []
        for k, bits in enumerate(self.bit_plan):
            code = next(c for c, j in self.bit_ids.items() if j == k)
            plan.append((int(code), self._width(int(code)), bits))
        return plan

    def _frame(
        self, blk: VcBlock, vectors: list[tuple[int, int, list[tuple[int, int]]]]
    ) -> _Changes:
        """The values at the block's start (its frame), as changes at its first time."""
        frame = np.frombuffer(self.fst.frame(blk), np.uint8)
        count = min(blk.frame[3], len(self.fst.lengths))
        widths = np.array(self.fst.lengths[:count], dtype=np.int64)
        offs = np.concatenate(([0], np.cumsum(widths)))
        if offs[-1] > len(frame):
            raise self.fst.error(blk.frame[0], f"frame of {len(frame)} bytes, {offs[-1]} needed")
        sig, val = [], []
        for i, h in enumerate(self.handles):
            if h <= count:
                sig.append(i)
                val.append(int(FRAME_CODES[frame[offs[h - 1]]]))
        for h, width, bits in vectors:
            if h <= count:
                chars = frame[offs[h - 1] : offs[h - 1] + width]
                for pos, channel in bits:
                    sig.append(channel)
                    val.append(int(FRAME_CODES[chars[width - 1 - pos]]))
        codes = np.array(val, dtype=np.int8)
        if (codes < 0).any():
            raise self.fst.error(blk.frame[0], "frame: a value that is not 0, 1, x, z, …")
        return np.array(sig, np.int32), np.full(len(sig), blk.begin, np.int64), codes

    def _changes(
        self, blk: VcBlock, ntimes: int, vectors: list[tuple[int, int, list[tuple[int, int]]]]
    ) -> list[tuple[int, npt.NDArray[np.signedinteger], npt.NDArray[np.int8]]]:
        """The block's changes of each channel (and of the bits read from vectors):
        (channel, time indices, value codes)."""
        fst = self.fst
        offs, lens = fst.positions(blk)
        out = []
        for i, h in enumerate(self.handles):
            if h <= len(offs) and offs[h - 1]:
                at = blk.waves + offs[h - 1]
                idx, codes = scalar_changes(
                    fst, fst.wave(blk, offs[h - 1], lens[h - 1]), ntimes, at
                )
                out.append((i, idx, codes))
        for h, width, bits in vectors:
            if h <= len(offs) and offs[h - 1]:
                at = blk.waves + offs[h - 1]
                raw = fst.wave(blk, offs[h - 1], lens[h - 1])
                idx, chars = vector_changes(fst, raw.tobytes(), width, ntimes, at)
                for pos, channel in bits:
                    codes = (
                        FRAME_CODES[chars[:, width - 1 - pos]] if len(idx) else np.zeros(0, np.int8)
                    )
                    if (codes < 0).any():
                        raise fst.error(at, "a vector value that is not 0, 1, x, z, …")
                    out.append((channel, idx, codes))
        return out

    def capture(self) -> Capture:
        """The whole capture without edges (after :meth:`blocks`), named an FST."""
        cap = super().capture()
        cap.format = "fst"
        cap.bit_source = str(self.path)
        return cap


def read_native(
    path: str | os.PathLike[str],
    *,
    samplerate: Fraction | None = None,
    resolution_s: Fraction | None = None,
) -> Capture:
    """The whole capture of an FST file, decoded natively (see :func:`read_fst`)."""
    from wavecheck.capture.blocks import assemble

    source = FstNativeBlocks(path, samplerate=samplerate, resolution_s=resolution_s)
    blocks = list(source.blocks())
    cap = assemble(source.capture(), blocks)
    cap.bit_reader = None  # a bit of a vector comes from the file again (load_bit)
    return cap
