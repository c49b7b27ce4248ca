"""Edge blocks: what a streaming reader hands the streamed engine, a time slice at a time.

A :class:`BlockSource` gives a capture's *skeleton* first (channel names and indices, time base,
resolution: a :class:`~wavecheck.capture.edges.Capture` whose channels hold no edges), then
:class:`EdgeBlock` s in time order, then the finished skeleton (start, end, notes, each channel's
edge count). Readers: :func:`wavecheck.capture.sr.iter_sr_blocks` (``.sr``),
:func:`wavecheck.capture.vcd.reader.iter_vcd_blocks` (VCD); :func:`capture_blocks` cuts a capture
already in memory (the tests' way to get blocks of any size, down to one edge).
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field, replace
from fractions import Fraction
from typing import Protocol

import numpy as np

from wavecheck.capture.edges import NEVER, Capture, Channel, EdgeArray

__all__ = [
    "BlockSource",
    "EdgeBlock",
    "MemorySource",
    "capture_blocks",
    "open_stream",
    "skeleton_of",
]


@dataclass
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


class MemorySource:
    """Blocks cut from a capture in memory, about ``block_edges`` edges each (over all channels;
    at least one distinct tick per block)."""

    def __init__(self, capture: Capture, block_edges: int) -> None:
        self.whole = capture
        self.block_edges = max(1, block_edges)
        self.skeleton = skeleton_of(capture)

    def blocks(self) -> Iterator[EdgeBlock]:
        return capture_blocks(self.whole, self.block_edges)

    def capture(self) -> Capture:
        return self.skeleton

    def want(self, channels: Iterable[int]) -> None:
        pass  # the capture is in memory already


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


def open_stream(
    path: str,
    *,
    samplerate: Fraction | None = None,
    resolution_s: Fraction | None = None,
    input_format: str | None = None,
    chunk_bytes: int | None = None,
) -> BlockSource | None:
    """A block reader for ``path`` (a ``.sr`` or VCD file, told as
    :func:`wavecheck.capture.open.open_capture` tells them), or None when there is none (standard
    input, a pipe, FST/GHW, formats read through sigrok-cli, a VCD with options): read whole."""
    from wavecheck.capture.open import detect_format, is_stream

    if is_stream(path):
        return None
    fmt = (input_format.strip() if input_format else detect_format(path)).lower()
    if fmt in ("sr", "srzip", "sigrok"):
        from wavecheck.capture.sr import DEFAULT_CHUNK_BYTES, SrBlocks

        size = chunk_bytes or DEFAULT_CHUNK_BYTES
        return SrBlocks(path, samplerate=samplerate, resolution_s=resolution_s, chunk_bytes=size)
    if fmt == "vcd":
        from wavecheck.capture.vcd.reader import DEFAULT_CHUNK_BYTES as VCD_CHUNK
        from wavecheck.capture.vcd.reader import VcdBlocks

        size = chunk_bytes or VCD_CHUNK
        return VcdBlocks(path, samplerate=samplerate, resolution_s=resolution_s, chunk_bytes=size)
    return None
