"""Edge blocks: what every capture source hands the engine, a time slice at a time.

A :class:`BlockSource` gives a capture's *skeleton* first (channel names and indices, time base,
resolution: a :class:`~wavecheck.capture.edges.Capture` whose channels hold no edges), then
:class:`EdgeBlock` s in time order, then the finished skeleton (start, end, notes, each channel's
edge count). Sources: :class:`wavecheck.capture.sr.SrBlocks` (``.sr``),
:class:`wavecheck.capture.vcd.reader.VcdBlocks` (VCD, bits of vectors included),
:class:`wavecheck.capture.binary.SampleBlocks` (raw samples, the live device); any capture in
memory is a :class:`MemorySource` (one block, or cut into blocks of any size down to one edge:
the tests' way); :func:`wavecheck.capture.open.open_source` picks one for a file. :func:`assemble`
turns blocks back into a capture (the first part read to tell roles from the waveforms).
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator
from typing import Protocol

import numpy as np

from wavecheck.capture.edges import NEVER, Capture, Channel, EdgeArray, Vector
from wavecheck.record import field, record, replace

__all__ = [
    "BlockSource",
    "EdgeBlock",
    "MemorySource",
    "WHOLE",
    "capture_blocks",
    "assemble",
    "skeleton_of",
]


@record
class EdgeBlock:
    """The edges of one time slice ``[previous block's end, end)``.

    Attributes:
        end: every edge and x/z event before this tick has been given (this or earlier blocks).
        edges: channel index → its edges in the slice (increasing ticks); channels without
            edges in the slice may be absent.
        known: channel index → (known_from, level) for a channel whose level became known in
            this slice (a ``.sr`` gives every channel at tick 0 in its first block).
        xz_starts / xz_ends: channel index → where x/z stretches began / where a known value came
            back, in this slice (:attr:`Channel.xz_times` / :attr:`Channel.xz_ends`).
        start: the capture's first tick, once known (given in the first block).
    """

    end: int
    edges: dict[int, EdgeArray] = field(default_factory=dict)
    known: dict[int, tuple[int, int]] = field(default_factory=dict)
    xz_starts: dict[int, EdgeArray] = field(default_factory=dict)
    xz_ends: dict[int, EdgeArray] = field(default_factory=dict)
    start: int | None = None


class BlockSource(Protocol):
    """A capture read block by block (module docstring)."""

    skeleton: Capture
    """Names, indices, time base and resolution; no edges (known before any block)."""

    def blocks(self) -> Iterator[EdgeBlock]:
        """The blocks in time order (once)."""

    def capture(self) -> Capture:
        """After :meth:`blocks`: the whole capture without edges (start, end, notes,
        :attr:`Channel.counted` edge counts, levels and unknown stretches)."""

    def want(self, channels: Iterable[int]) -> None:
        """Extract the edges of ``channels`` (indices) only; the others are only counted."""


def skeleton_of(capture: Capture) -> Capture:
    """``capture`` without its edges and x/z stretches (each channel's edge count kept)."""
    empty = np.zeros(0, dtype=np.int64)
    chans = [
        replace(c, edges=empty.copy(), xz_times=empty.copy(), xz_ends=empty.copy(),
                counted=c.edge_count)
        for c in capture.channels
    ]  # fmt: skip
    return replace(capture, channels=chans, notes=list(capture.notes))


#: ``block_edges`` of a capture in memory given as one block.
WHOLE = 1 << 62


class MemorySource:
    """A capture in memory as a block source: one block (the default), or blocks of about
    ``block_edges`` edges each (over all channels; at least one distinct tick per block: the
    tests' way to cut a capture anywhere)."""

    def __init__(self, capture: Capture, block_edges: int = WHOLE) -> None:
        self.whole = capture
        self.block_edges = max(1, block_edges)
        self.skeleton = skeleton_of(capture)
        self.skeleton.bit_reader = self._bit

    def _bit(self, key: str, vec: Vector, bit: int) -> Channel:
        """A vector's bit: read into the capture (its edges come with the blocks), given to the
        skeleton without them."""
        ch = self.whole.bit(key, bit)
        empty = np.zeros(0, dtype=np.int64)
        return replace(ch, edges=empty, xz_times=empty, xz_ends=empty, counted=ch.edge_count)

    def blocks(self) -> Iterator[EdgeBlock]:
        if self.block_edges >= WHOLE:
            yield _one_block(self.whole)
        else:
            yield from capture_blocks(self.whole, self.block_edges)

    def capture(self) -> Capture:
        return self.skeleton

    def want(self, channels: Iterable[int]) -> None:
        pass  # the capture is in memory already


def _one_block(capture: Capture) -> EdgeBlock:
    """Every edge of ``capture`` as one block."""
    block = EdgeBlock(end=NEVER, start=capture.start)
    for c in capture.channels:
        if len(c.edges):
            block.edges[c.index] = c.edges
        if not c.never_known:
            block.known[c.index] = (c.known_from, c.initial)
        if len(c.xz_times):
            block.xz_starts[c.index] = c.xz_times
        ends = c.xz_ends[c.xz_ends != NEVER]
        if len(ends):
            block.xz_ends[c.index] = ends
    return block


def assemble(
    skeleton: Capture, blocks: Iterable[EdgeBlock], end: int | None = None, before: int = NEVER
) -> Capture:
    """The capture that ``blocks`` of a source with ``skeleton`` make (its channels' edges, levels
    and unknown stretches); ``end``: its last tick (default the skeleton's, or the last edge seen
    when that is later: a capture read only in part); ``before``: only what happened before that
    tick (a first part that does not depend on how the blocks were cut)."""
    parts: dict[int, list[EdgeArray]] = {c.index: [] for c in skeleton.channels}
    xz: dict[int, list[EdgeArray]] = {c.index: [] for c in skeleton.channels}
    back: dict[int, list[EdgeArray]] = {c.index: [] for c in skeleton.channels}
    known: dict[int, tuple[int, int]] = {}
    k: tuple[int, int] | None
    start = skeleton.start
    last = skeleton.end
    for block in blocks:
        if block.start is not None:
            start = block.start
        for i, e in block.edges.items():
            parts.setdefault(i, []).append(e)
            last = max(last, int(e[-1])) if len(e) else last
        for i, e in block.xz_starts.items():
            xz.setdefault(i, []).append(e)
        for i, e in block.xz_ends.items():
            back.setdefault(i, []).append(e)
        for i, k in block.known.items():
            known.setdefault(i, k)
    empty = np.zeros(0, dtype=np.int64)

    def joined(arrays: list[EdgeArray]) -> EdgeArray:
        out = np.concatenate(arrays).astype(np.int64, copy=False) if arrays else empty.copy()
        return out[: int(np.searchsorted(out, before, side="left"))] if before < NEVER else out

    chans = []
    for c in skeleton.channels:
        starts = joined(xz.get(c.index, []))
        ends = joined(back.get(c.index, []))
        if len(ends) < len(starts):
            ends = np.concatenate([ends, np.full(len(starts) - len(ends), NEVER, np.int64)])
        k = known.get(c.index)
        chans.append(
            replace(
                c,
                edges=joined(parts.get(c.index, [])),
                initial=k[1] if k else 0,
                known_from=k[0] if k else start,
                never_known=k is None,
                xz_times=starts,
                xz_ends=ends,
                counted=None,
            )
        )
    return replace(
        skeleton,
        start=start,
        end=last if end is None else end,
        channels=chans,
        notes=list(skeleton.notes),
    )


def _events(ch: Channel) -> EdgeArray:
    ends = ch.xz_ends[ch.xz_ends != NEVER]
    return np.concatenate([ch.edges, ch.xz_times, ends, np.array([ch.known_from], np.int64)])


def capture_blocks(capture: Capture, block_edges: int) -> Iterator[EdgeBlock]:
    """Cut ``capture`` into blocks of about ``block_edges`` events (edges, x/z starts and ends)."""
    chans = capture.channels
    ticks = np.unique(np.concatenate([_events(c) for c in chans] or [np.zeros(1, np.int64)]))
    ticks = ticks.astype(np.int64)
    cuts = ticks[:: max(1, block_edges)][1:]  # each block ends before a cut
    bounds = [*cuts.tolist(), NEVER]
    lo = None
    for k, hi in enumerate(bounds):
        block = EdgeBlock(end=hi, start=capture.start if k == 0 else None)
        for c in chans:
            e = c.edges
            a = 0 if lo is None else int(np.searchsorted(e, lo, side="left"))
            b = int(np.searchsorted(e, hi, side="left"))
            if b > a:
                block.edges[c.index] = e[a:b]
            if not c.never_known and (lo is None or lo <= c.known_from) and c.known_from < hi:
                block.known[c.index] = (c.known_from, c.initial)
            for name, arr in (("xz_starts", c.xz_times), ("xz_ends", c.xz_ends)):
                sel = (arr >= (lo if lo is not None else np.iinfo(np.int64).min)) & (arr < hi)
                if sel.any():
                    getattr(block, name)[c.index] = arr[sel]
        lo = hi
        yield block
