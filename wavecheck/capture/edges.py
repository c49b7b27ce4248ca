"""The capture model every reader produces: named channels as exact edge arrays.

A channel is its initial level plus a strictly increasing ``int64`` array of edge times in ticks;
each edge toggles the level. There are no floats and no per-sample arrays here, so a capture of
hundreds of millions of samples costs only its edges.
"""

from __future__ import annotations

from collections.abc import Callable
from fractions import Fraction
from typing import Any

import numpy as np

from wavecheck.errors import UsageError
from wavecheck.record import field, record
from wavecheck.timebase import Timebase

__all__ = ["NEVER", "Capture", "Channel", "EdgeArray", "Vector"]

#: ``numpy.typing.NDArray[np.int64]`` spelled without importing ``numpy.typing`` (~0.4 ms at
#: every start: bench/README.md, Round 7).
EdgeArray = np.ndarray[tuple[Any, ...], np.dtype[np.int64]]
#: The end of an unknown stretch that lasts to the end of the capture (the largest int64).
NEVER = int(np.iinfo(np.int64).max)


@record
class Channel:
    """One 1-bit signal of a capture.

    Attributes:
        name: the name as written in the file (``"STEP (Y axis)"``, a VCD reference name).
        index: position in the file (``.sr`` probe number − 1, VCD declaration order), from 0.
        initial: level (0 or 1) at :attr:`known_from`.
        edges: tick of every level change, strictly increasing, each one toggling the level.
        known_from: first tick at which the level is known (later than the capture start when a
            VCD begins with ``x``).
        xz_times: ticks at which the value became ``x`` or ``z`` after :attr:`known_from`
            (empty for logic-analyzer captures).
        xz_ends: for each of :attr:`xz_times`, the tick at which a known value came back
            (:data:`NEVER` when it stays unknown to the end). An edge at that tick may be one
            hidden in the stretch, so :meth:`unknown_stretches` include it.
        never_known: the level is never known (``x`` all along); :attr:`initial` means nothing.
    """

    name: str
    index: int
    initial: int
    edges: EdgeArray
    known_from: int = 0
    xz_times: EdgeArray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    xz_ends: EdgeArray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    never_known: bool = False
    counted: int | None = None
    """The number of edges when :attr:`edges` is not kept (a streamed capture: the edges went
    by block by block: :mod:`wavecheck.capture.blocks`), else None."""

    @property
    def edge_count(self) -> int:
        """Number of edges (:attr:`counted` for a streamed capture)."""
        return int(len(self.edges)) if self.counted is None else self.counted

    def unknown_stretches(self, start: int) -> tuple[EdgeArray, EdgeArray]:
        """Where the level is not known, as closed tick ranges ``[starts[i], ends[i]]`` in time
        order, for a capture starting at tick ``start``: ``[start, known_from]`` when the
        level is known only later, then each ``x``/``z`` stretch up to the tick a known value
        came back (:data:`NEVER` for one that lasts to the end)."""
        starts, ends = self.xz_times, self.xz_ends
        if len(ends) != len(starts):  # a reader that lists only where x/z began
            ends = np.full(len(starts), NEVER, dtype=np.int64)
        if self.never_known:
            return np.array([start], np.int64), np.array([NEVER], np.int64)
        if self.known_from > start:
            starts = np.concatenate([[start], starts]).astype(np.int64)
            ends = np.concatenate([[self.known_from], ends]).astype(np.int64)
        return starts, ends

    @property
    def rising(self) -> int:
        """Number of 0→1 edges."""
        n = len(self.edges)
        return n // 2 if self.initial == 1 else (n + 1) // 2

    @property
    def falling(self) -> int:
        """Number of 1→0 edges."""
        return len(self.edges) - self.rising

    def level_after(self, i: int) -> int:
        """Level after edge ``i`` (``-1`` means before the first edge)."""
        return self.initial ^ ((i + 1) & 1)


@record(frozen=True)
class Vector:
    """A multi-bit signal of the file whose bits can be mapped as channels.

    Attributes:
        width: number of bits.
        msb: the declared index of the leftmost bit (``3`` for ``[3:0]``).
        lsb: the declared index of the rightmost bit.
        key: the name the file's reader knows it by (for reading its changes again).
    """

    width: int
    msb: int
    lsb: int
    key: str

    @property
    def range_text(self) -> str:
        """The declared range, ``"[3:0]"``."""
        return f"[{self.msb}:{self.lsb}]"

    def position(self, bit: int) -> int | None:
        """Position of declared index ``bit`` counted from the rightmost bit (0), or None when
        it is outside the range."""
        p = bit - self.lsb if self.msb >= self.lsb else self.lsb - bit
        return p if 0 <= p < self.width else None


@record
class Capture:
    """A whole capture: channels, exact time base, resolution and where it came from.

    Attributes:
        path: the file read.
        format: ``"sr"``, ``"vcd"``, or ``"sigrok:<input format>"`` for files converted by sigrok-cli.
        timebase: what one tick is.
        resolution_ticks: the sample period T in ticks (1 for a ``.sr``; 0 for an exact simulator
            VCD); a measured interval W is really in (W − T, W + T).
        samplerate_hz: the sample rate if the file states one (``None`` for a plain VCD).
        start: first tick of the captured window.
        end: last tick of the captured window (``end - start`` is the duration).
        channels: the 1-bit channels, in file order.
        notes: things the reader skipped or assumed (vectors, reals, comments), one line each.
        skipped: signals present in the file that are not 1-bit channels, name → what they are
            (``"an 8-bit vector"``, ``"a real"``), so mapping one gives a precise error.
        aliases: other names of a channel (a VCD id code declared more than once), name →
            channel name, so mapping any of them finds it.
        time_known: False when the file states no sample rate and none was given (read for
            ``wavecheck info`` only): ticks are samples of unknown length, the timebase is a
            placeholder, and only counts (edges, samples) mean anything.
        vectors: the file's bit vectors by full name (``tb.dut.stout``), whose bits
            :meth:`bit` turns into channels when they are mapped.
        bit_source: the file :meth:`bit` reads vector changes from (None: it cannot, e.g. a
            capture read from standard input).
    """

    path: str
    format: str
    timebase: Timebase
    resolution_ticks: int
    samplerate_hz: Fraction | None
    start: int
    end: int
    channels: list[Channel]
    notes: list[str] = field(default_factory=list)
    skipped: dict[str, str] = field(default_factory=dict)
    aliases: dict[str, str] = field(default_factory=dict)
    time_known: bool = True
    vectors: dict[str, Vector] = field(default_factory=dict)
    bit_source: str | None = None
    bit_reader: Callable[[str, Vector, int], Channel] | None = field(
        default=None, repr=False, compare=False
    )
    """How :meth:`bit` makes a vector's bit a channel (``(full name, vector, declared index)`` →
    the new channel, numbered after the others). A block reader sets its own, so the bit's edges
    come with its blocks; :mod:`wavecheck.capture.open` gives a capture read whole that names a
    :attr:`bit_source` one that reads that file again (pywellen); None: bits cannot be mapped."""

    def bit(self, ref: str, bit: int) -> Channel:
        """Bit ``bit`` (an index of the declared range, ``stout[3]``) of the vector ``ref`` as a
        channel, its edges extracted from the vector's value changes on first use and then kept
        in :attr:`channels`. ``ref`` is the vector's full name or any unique dotted tail of it
        (``stout``, ``dut.stout``; any case when no exact-case one).

        Raises:
            UsageError: no such vector, several match, the bit is outside the range, or the
                file cannot be read again (standard input).
        """
        name = f"{ref}[{bit}]"
        for ch in self.channels:
            if ch.name == name:
                return ch
        hits = [k for k in self.vectors if k == ref]
        if not hits:
            hits = [k for k in self.vectors if k.endswith("." + ref)]
        if not hits:
            low = "." + ref.lower()
            hits = [k for k in self.vectors if ("." + k.lower()).endswith(low)]
        if not hits:
            known = ", ".join(f"{k}{v.range_text}" for k, v in list(self.vectors.items())[:8])
            raise UsageError(
                f"{self.path}: no vector {ref!r} to take bit {bit} of (vectors: {known or 'none'})"
            )
        if len(hits) > 1:
            raise UsageError(
                f"{self.path}: {name!r} is ambiguous: vectors {', '.join(hits[:8])}; "
                "give more of the hierarchical name"
            )
        vec = self.vectors[hits[0]]
        full = f"{hits[0]}[{bit}]"
        for ch in self.channels:
            if ch.name == full:
                return ch
        if self.bit_reader is None:
            raise UsageError(
                f"{self.path}: a bit of a vector ({full}) can be mapped only from a file opened "
                "with wavecheck.capture.open (the vector's changes are read again)"
            )
        ch = self.bit_reader(hits[0], vec, bit)
        self.channels.append(ch)
        return ch

    @property
    def duration_s(self) -> Fraction:
        """Length of the captured window in exact seconds."""
        return self.timebase.seconds(self.end - self.start)

    @property
    def resolution_ns(self) -> Fraction:
        """The sample period T in exact nanoseconds (0 for an exact VCD)."""
        return self.timebase.ns(self.resolution_ticks)

    def _by_name(self) -> dict[str, list[Channel]]:
        """Channels by exact name (built once per list of channels: lookups stay O(1) on
        captures with hundreds of thousands of signals)."""
        cached = self.__dict__.get("_name_index")
        # the list itself is kept, not its id(): a freed list's address may be a new one's
        if cached is None or cached[0] is not self.channels or cached[1] != len(self.channels):
            index: dict[str, list[Channel]] = {}
            for ch in self.channels:
                index.setdefault(ch.name, []).append(ch)
            cached = (self.channels, len(self.channels), index)
            self.__dict__["_name_index"] = cached
        return cached[2]

    def channel(self, ref: str | int) -> Channel:
        """Find a channel by exact name, else by index (``"3"`` or ``3``).

        Raises:
            UsageError: no such channel; the message lists the channels there are.
        """
        if isinstance(ref, str):
            same = self._by_name().get(ref, [])
            if len(same) > 1:  # never the first of several silently (wavecheck.steps.interface)
                raise UsageError(
                    f"{self.path}: channel {ref!r} is ambiguous: indices "
                    f"{', '.join(str(c.index) for c in same)} share the name; map by index"
                )
            if same:
                return same[0]
            stripped = ref.strip()
            for ch in self.channels:
                if ch.name.strip() == stripped:
                    return ch
            if stripped.isdigit():
                ref = int(stripped)
        if isinstance(ref, int):
            for ch in self.channels:
                if ch.index == ref:
                    return ch
        if isinstance(ref, str):
            target = self.aliases.get(ref) or self.aliases.get(ref.strip())
            for ch in self.channels:
                if target is not None and ch.name == target:
                    return ch
        if isinstance(ref, str) and (ref in self.skipped or ref.strip() in self.skipped):
            what = self.skipped.get(ref) or self.skipped[ref.strip()]
            raise UsageError(
                f"{self.path}: channel {ref!r} is {what}, not a 1-bit signal "
                "(map a 1-bit wire; split vectors into single bits when dumping)"
            )
        available = ", ".join(f"{c.index}={c.name!r}" for c in self.channels) or "none"
        raise UsageError(
            f"{self.path}: no channel {ref!r} (channels: {available}; map by name or index, "
            f"e.g. --map step={self.channels[0].name if self.channels else 'STEP'!r})"
        )
