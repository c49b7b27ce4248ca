"""A step trace kept as the engine runs: position and step rate over time in bounded memory.

The motion panel (:func:`wavecheck.report.measured_plot.draw_motion`) draws position and step
rate from it, not from every step. The engine keeps, per axis, a :class:`StepTrace` (a step
sink, :mod:`wavecheck.engine.sinks`): at most :data:`MAX_BUCKETS` time buckets of equal width (ticks) from the first
step on. When a step falls past the last bucket, neighbouring buckets merge pairwise (the width
doubles, the origin stays) until it fits, so the memory does not depend on the capture's length.

Each bucket keeps, from the steps in it (ticks exact, positions exact):

- the first and the last step's tick and the position after each (forward − reverse, steps of
  unknown direction counting 0, as :attr:`wavecheck.steps.decode.StepEvents.position`): points on
  the position curve of every step; and the lowest and highest position reached in the bucket;
- the fastest and the slowest step (the shortest and the longest time since the step before,
  that step's tick, the earliest on ties): points on the step-rate curve of every step, each
  step's rate counted in the bucket of the step that ends the interval;
- the reversals (a known direction unlike the last known one), counted exactly.

The first :data:`REVERSALS_KEPT` reversal ticks are kept too (the plot marks that many). So the
thinned curves have at most ``2 · MAX_BUCKETS`` points each; the highest rate drawn is the highest
rate of every step over the same bucket, and the reversal count is exact. While no bucket holds
more than two steps, the curves hold every step (:attr:`StepTrace.thinned` is False).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from wavecheck.capture.edges import EdgeArray
from wavecheck.record import field_names, record

if TYPE_CHECKING:
    import numpy.typing as npt

__all__ = ["MAX_BUCKETS", "REVERSALS_KEPT", "StepTrace"]

#: Buckets kept at most (a power of two): each thinned curve has at most twice as many points.
MAX_BUCKETS = 2048
#: Reversal ticks kept (the first ones; the count is exact).
REVERSALS_KEPT = 200

_BIG = np.iinfo(np.int64).max
_SMALL = np.iinfo(np.int64).min
_I64 = EdgeArray  # int64 arrays (not only edges)


@record
class _Buckets:
    """Per-bucket figures (module docstring), one array element per bucket; an empty bucket has
    ``count`` 0, ``low`` = +max, ``high`` = −max, ``fast_gap`` = +max and ``slow_gap`` = −1."""

    count: _I64
    first_tick: _I64
    first_pos: _I64
    last_tick: _I64
    last_pos: _I64
    low: _I64
    high: _I64
    fast_gap: _I64  # shortest time since the step before (ticks), and the step's tick
    fast_tick: _I64
    slow_gap: _I64  # longest
    slow_tick: _I64
    reversals: _I64

    @classmethod
    def empty(cls, n: int) -> _Buckets:
        fill = {"low": _BIG, "high": _SMALL, "fast_gap": _BIG, "slow_gap": -1}
        return cls(*(np.full(n, fill.get(name, 0), np.int64) for name in field_names(cls)))

    def take(self, at: npt.NDArray[np.intp] | slice) -> _Buckets:
        return _Buckets(*(getattr(self, name)[at] for name in field_names(self)))

    def put(self, at: npt.NDArray[np.intp], other: _Buckets) -> None:
        for name in field_names(self):
            getattr(self, name)[at] = getattr(other, name)


def _combine(a: _Buckets, b: _Buckets) -> _Buckets:
    """Buckets ``a`` followed in time by ``b`` (element by element) as one bucket each."""
    has_a, has_b = a.count > 0, b.count > 0
    faster = b.fast_gap < a.fast_gap  # ties: the earlier (a's)
    slower = b.slow_gap > a.slow_gap
    return _Buckets(
        a.count + b.count,
        np.where(has_a, a.first_tick, b.first_tick),
        np.where(has_a, a.first_pos, b.first_pos),
        np.where(has_b, b.last_tick, a.last_tick),
        np.where(has_b, b.last_pos, a.last_pos),
        np.minimum(a.low, b.low),
        np.maximum(a.high, b.high),
        np.where(faster, b.fast_gap, a.fast_gap),
        np.where(faster, b.fast_tick, a.fast_tick),
        np.where(slower, b.slow_gap, a.slow_gap),
        np.where(slower, b.slow_tick, a.slow_tick),
        a.reversals + b.reversals,
    )


def _first_where(mask: npt.NDArray[np.bool_], group: _I64, starts: _I64) -> _I64:
    """Per group (``group``: each element's group, nondecreasing; ``starts``: each group's first
    element), the first element where ``mask`` holds (the group's first element when none)."""
    out = starts.copy()
    g, first = np.unique(group[mask], return_index=True)
    out[g] = np.flatnonzero(mask)[first]
    return out


class StepTrace:
    """One axis's thinned step trace (module docstring): :meth:`add` each window's new steps in
    time order; read :meth:`position_points`, :meth:`rate_points`, :meth:`envelope`."""

    def __init__(self, buckets: int = MAX_BUCKETS, reversals_kept: int = REVERSALS_KEPT) -> None:
        if buckets < 1 or buckets & (buckets - 1):
            raise ValueError(f"buckets must be a power of two, not {buckets}")
        self.size = buckets
        self.reversals_kept = reversals_kept
        self.width = 1
        """Ticks per bucket (a power of two)."""
        self.origin: int | None = None
        """Tick of bucket 0's start (the first step's tick)."""
        self.count = 0
        """Steps added."""
        self.position = 0
        """Position after the last step (forward − reverse)."""
        self.reversals = 0
        """Reversals seen (exact)."""
        self.reversal_ticks: EdgeArray = np.zeros(0, np.int64)
        """The first ``reversals_kept`` reversals' ticks."""
        self._b = _Buckets.empty(buckets)
        self._last_tick: int | None = None
        self._last_dir = 0  # last known direction (0: none yet)

    def add(self, ticks: EdgeArray, direction: npt.NDArray[np.int8]) -> None:
        """Add steps later than every step so far: their ticks (increasing) and directions."""
        n = len(ticks)
        if not n:
            return
        if self.origin is None:
            self.origin = int(ticks[0])
        pos = self.position + np.cumsum(direction, dtype=np.int64)
        gap = np.diff(ticks, prepend=ticks[0] if self._last_tick is None else self._last_tick)
        known = np.flatnonzero(direction != 0)
        d = direction[known]
        prev = np.concatenate([[self._last_dir], d[:-1]])
        flip = (d != prev) & (prev != 0)
        rev = np.zeros(n, np.int64)
        rev[known[flip]] = 1
        room = self.reversals_kept - len(self.reversal_ticks)
        if room > 0:
            self.reversal_ticks = np.concatenate([self.reversal_ticks, ticks[known[flip]][:room]])

        idx = (ticks - self.origin) // self.width
        over = int(idx[-1]) // self.size
        if over:
            self._coarsen(over.bit_length())
            idx = (ticks - self.origin) // self.width
        starts = np.concatenate([[0], np.flatnonzero(np.diff(idx)) + 1]).astype(np.int64)
        lengths = np.diff(np.append(starts, n))
        group = np.repeat(np.arange(len(starts), dtype=np.int64), lengths)
        ends = starts + lengths - 1
        fast = np.where(gap > 0, gap, _BIG)
        slow = np.where(gap > 0, gap, -1)
        fmin = np.minimum.reduceat(fast, starts)
        smax = np.maximum.reduceat(slow, starts)
        fi = _first_where(fast == fmin[group], group, starts)
        si = _first_where(slow == smax[group], group, starts)
        new = _Buckets(
            lengths,
            ticks[starts],
            pos[starts],
            ticks[ends],
            pos[ends],
            np.minimum.reduceat(pos, starts),
            np.maximum.reduceat(pos, starts),
            fmin,
            ticks[fi],
            smax,
            ticks[si],
            np.add.reduceat(rev, starts),
        )
        at = idx[starts]
        self._b.put(at, _combine(self._b.take(at), new))

        self.count += n
        self.position = int(pos[-1])
        self.reversals += int(np.count_nonzero(flip))
        self._last_tick = int(ticks[-1])
        if len(d):
            self._last_dir = int(d[-1])

    def _coarsen(self, shift: int) -> None:
        """Merge every ``2**shift`` neighbouring buckets into one (the width times ``2**shift``)."""
        b = self._b
        for _ in range(min(shift, self.size.bit_length() - 1)):  # one bucket left: done
            b = _combine(b.take(slice(0, None, 2)), b.take(slice(1, None, 2)))
        rest = _Buckets.empty(self.size - len(b.count))
        self._b = _Buckets(*(np.concatenate([getattr(b, name), getattr(rest, name)])
                             for name in field_names(b)))  # fmt: skip
        self.width <<= shift

    # -- reading -----------------------------------------------------------------------------
    @property
    def buckets(self) -> int:
        """Buckets holding a step."""
        return int(np.count_nonzero(self._b.count))

    @property
    def thinned(self) -> bool:
        """Whether a bucket holds more than two steps (its first and last are drawn): the curves
        then leave steps out; otherwise they hold every step."""
        return bool((self._b.count > 2).any())

    def _used(self) -> _Buckets:
        return self._b.take(np.flatnonzero(self._b.count))

    def position_points(self) -> tuple[EdgeArray, EdgeArray]:
        """(ticks, position after the step): each used bucket's first and last step, in time
        order (points of the position curve; a tick twice when steps share it)."""
        u = self._used()
        t = np.stack([u.first_tick, u.last_tick], axis=1).ravel()
        p = np.stack([u.first_pos, u.last_pos], axis=1).ravel()
        keep = np.ones(len(t), bool)
        keep[1::2] = u.count > 1
        return t[keep], p[keep]

    def rate_points(self) -> tuple[EdgeArray, EdgeArray]:
        """(ticks, time since the step before, ticks): each used bucket's fastest and slowest
        step, in time order (points of the step-rate curve: rate = samplerate / gap).
        """
        u = self._used()
        t = np.concatenate([u.fast_tick, u.slow_tick])
        g = np.concatenate([u.fast_gap, u.slow_gap])
        ok = (g > 0) & (g < _BIG)
        t, g = t[ok], g[ok]
        order = np.lexsort((g, t))
        t, g = t[order], g[order]
        keep = np.ones(len(t), bool)
        keep[1:] = (t[1:] != t[:-1]) | (g[1:] != g[:-1])
        return t[keep], g[keep]

    def envelope(self) -> tuple[EdgeArray, EdgeArray, EdgeArray]:
        """(start tick, lowest position, highest position) of each used bucket (``width`` ticks
        wide)."""
        at = np.flatnonzero(self._b.count)
        assert self.origin is not None or not len(at)
        start = (self.origin or 0) + at.astype(np.int64) * self.width
        return start, self._b.low[at], self._b.high[at]
