"""Generic timing measurements over whole edge arrays, in the spirit of Verilog's timing checks.

Each function returns :class:`Intervals`: the start and end tick of every *complete* interval of
its kind. Intervals that would start before the first edge or end after the last one (partial
intervals at the capture's start and end) are never produced, so they are never measured.

- :func:`widths` — ``$width``: each stretch at a level, from the edge entering it to the next edge.
- :func:`periods` — ``$period``: successive reference events.
- :func:`setups` — ``$setup``: each data event to the first reference event at or after it.
- :func:`holds` — ``$hold``: the last reference event at or before each data event, to it.

All inputs are increasing ``int64`` tick arrays; nothing loops per edge in Python.
"""

from __future__ import annotations

from functools import cached_property
from typing import TYPE_CHECKING, Literal

import numpy as np

from wavecheck.capture.edges import EdgeArray
from wavecheck.record import record

if TYPE_CHECKING:
    import numpy.typing as npt

__all__ = ["Intervals", "holds", "periods", "setups", "sorted_search", "widths"]

#: :func:`sorted_search` counts over the ticks spanned when they are at most this many per event.
DENSE_SPAN = 8


@record(frozen=True)
class Intervals:
    """Measured intervals: ``end[i] - start[i]`` ticks, starting at ``start[i]``.

    ``start`` is the reference event of the interval (e.g. the active edge for ``dir_hold``, the
    DIR change for ``dir_setup``), ``end`` the event that closes it.
    """

    start: EdgeArray
    end: EdgeArray

    def __post_init__(self) -> None:
        if len(self.start) != len(self.end):
            raise ValueError("interval start and end arrays differ in length")

    def __len__(self) -> int:
        return int(len(self.start))

    @cached_property
    def measured(self) -> EdgeArray:
        """Lengths in ticks (``end - start``), computed once."""
        return self.end - self.start

    @cached_property
    def bounds(self) -> tuple[int, int]:
        """The shortest and the longest length in ticks, computed once ((0, 0) when empty)."""
        w = self.measured
        return (int(w.min()), int(w.max())) if len(w) else (0, 0)

    @classmethod
    def empty(cls) -> Intervals:
        """No interval."""
        z = np.zeros(0, dtype=np.int64)
        return cls(z, z)

    @staticmethod
    def concat(parts: list[Intervals]) -> Intervals:
        """Several interval sets as one, ordered by start tick."""
        parts = [p for p in parts if len(p)]
        if not parts:
            return Intervals.empty()
        if len(parts) == 1:
            return parts[0]
        start = np.concatenate([p.start for p in parts])
        end = np.concatenate([p.end for p in parts])
        order = np.argsort(start, kind="stable")
        return Intervals(start[order], end[order])


def widths(initial: int, edges: EdgeArray, level: int) -> Intervals:
    """Every complete stretch of a signal at ``level``: from the edge entering it to the next edge.

    Args:
        initial: the level before ``edges[0]``.
        edges: tick of every level change (each toggles).
        level: 0 or 1.
    """
    first = 0 if initial != level else 1
    starts = edges[first::2]
    ends = edges[first + 1 :: 2]
    return Intervals(starts[: len(ends)], ends)


def periods(events: EdgeArray) -> Intervals:
    """Every interval between successive events."""
    return Intervals(events[:-1], events[1:]) if len(events) > 1 else Intervals.empty()


def setups(data: EdgeArray, ref: EdgeArray) -> Intervals:
    """From each data event to the first reference event at or after it (``$setup``).

    A data event with no reference event after it (the capture ends first) is not measured.
    A reference event at the same tick as the data event gives an interval of 0.
    """
    k = sorted_search(ref, data, "left")
    n = int(np.searchsorted(k, len(ref)))  # k ascends: the measured ones are a prefix
    return Intervals(data[:n], ref[k[:n]])


def holds(ref: EdgeArray, data: EdgeArray) -> Intervals:
    """From the last reference event at or before each data event, to that data event (``$hold``).

    Only the last reference before a data event bounds it (earlier ones are further away). A data
    event with no reference before it (the capture starts after it) is not measured.
    """
    k = sorted_search(ref, data, "right") - 1
    n = int(np.searchsorted(k, 0))  # k ascends: the measured ones are a suffix
    return Intervals(ref[k[n:]], data[n:])


def sorted_search(
    ref: EdgeArray, keys: EdgeArray, side: Literal["left", "right"]
) -> npt.NDArray[np.intp]:
    """``np.searchsorted(ref, keys, side)`` for increasing ``ref`` (ticks).

    Where the events are dense (the ticks they span at most :data:`DENSE_SPAN` per event, and
    ``ref`` strictly increasing), a running count over the span instead of a binary search per
    key: ~5× faster on a capture where nearly every sample is an edge."""
    if len(ref) and len(keys):
        lo = min(int(ref[0]), int(keys.min()))
        span = max(int(ref[-1]), int(keys.max())) - lo
        if span <= DENSE_SPAN * (len(ref) + len(keys)) and bool(np.all(ref[1:] > ref[:-1])):
            below = np.zeros(span + 2, dtype=np.intp)  # below[j]: events of ref before lo + j
            below[ref - (lo - 1)] = 1
            np.cumsum(below, out=below)
            return below[keys - (lo if side == "left" else lo - 1)]
    return np.searchsorted(ref, keys, side=side)
