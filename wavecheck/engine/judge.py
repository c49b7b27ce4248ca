"""Verdicts: every measured interval of a rule judged against its limit, exactly.

With T the resolution (exact ns; 0 for an exact simulator VCD), a measured interval W is really in
(W − T, W + T), so each interval is

- **pass** if W − T ≥ limit (tested first: a pulse exactly at its minimum passes when T = 0),
- **fail** if W + T ≤ limit,
- **indeterminate** otherwise (this sample rate cannot decide it).

W is an integer number of ticks and the tick an exact rational, so both tests reduce to integer
thresholds computed once per rule with exact :class:`~fractions.Fraction` arithmetic:
pass ⟺ W ≥ ⌈(limit + T) / tick⌉, fail ⟺ W ≤ ⌊(limit − T) / tick⌋. No float is involved.
"""

from __future__ import annotations

import functools
import math
from fractions import Fraction
from typing import TYPE_CHECKING

import numpy as np

from wavecheck.capture.edges import EdgeArray
from wavecheck.record import field, record
from wavecheck.steps.primitives import Intervals
from wavecheck.timebase import Timebase

if TYPE_CHECKING:
    import numpy.typing as npt

__all__ = [
    "FAIL",
    "INDETERMINATE",
    "PASS",
    "Histogram",
    "Judged",
    "Violation",
    "decide_parts",
    "decide_rate",
    "evaluate",
    "sequence_result",
]

PASS, FAIL, INDETERMINATE = 0, 1, 2
_I64_MAX = int(np.iinfo(np.int64).max)
_I64_MIN = int(np.iinfo(np.int64).min)
#: Lengths spread over fewer ticks than this are counted one by one before binning.
_SPAN_COUNTED = 1 << 16


def _clamp(v: int) -> int:
    return max(_I64_MIN, min(_I64_MAX, v))


@record(frozen=True)
class Violation:
    """One failed interval (or one state-sequence error).

    Attributes:
        rule: the rule id.
        start_tick: where the interval starts (its reference event).
        end_tick: where it ends.
        time_s: ``start_tick`` in exact seconds (from the capture's tick 0).
        measured_ns: the measured length in exact ns (None for ``state_sequence``).
        limit_ns: the rule's minimum in exact ns (None for ``state_sequence``).
        margin_ns: measured − limit in exact ns (None for ``state_sequence``).
        detail: extra text (``"state 1 → 8"`` for ``state_sequence``).
    """

    rule: str
    start_tick: int
    end_tick: int
    time_s: Fraction
    measured_ns: Fraction | None
    limit_ns: Fraction | None
    margin_ns: Fraction | None
    detail: str = ""


@record
class Judged:
    """One window's intervals of one rule and their verdicts: what :func:`evaluate` gives and
    :class:`wavecheck.engine.results.RuleResult` merges (every interval of the window; nothing
    of it is kept once merged).

    Attributes:
        rule: the rule id (``step_high``, ``dir_hold``, …, ``state_sequence``).
        intervals: the measured intervals (start/end ticks).
        outcome: ``PASS``/``FAIL``/``INDETERMINATE`` per interval (int8).
        checked: how many intervals (or state changes) were examined.
        details: per-interval text, only for ``state_sequence``.
    """

    rule: str
    intervals: Intervals
    outcome: npt.NDArray[np.int8]
    checked: int
    details: list[str] = field(default_factory=list)

    @property
    def violations(self) -> int:
        """Number of failed intervals."""
        return int(np.count_nonzero(self.outcome == FAIL))

    @property
    def indeterminate(self) -> int:
        """Number of intervals this resolution cannot decide."""
        return int(np.count_nonzero(self.outcome == INDETERMINATE))


def decide_parts(
    limit_ns: Fraction, timebase: Timebase, w: EdgeArray
) -> tuple[int | None, int | None, int]:
    """Of the indeterminate lengths ``w`` (ticks): the longest below the limit, the shortest above
    it (None when there is none) and how many are neither (exactly the limit): the three
    mergeable figures :attr:`wavecheck.engine.results.RuleResult.decide_samplerate_hz` needs."""
    lim_ticks = limit_ns / timebase.tick_ns
    below = w[w <= _clamp(math.ceil(lim_ticks) - 1)]
    above = w[w >= _clamp(math.floor(lim_ticks) + 1)]
    return (
        int(below.max()) if len(below) else None,
        int(above.min()) if len(above) else None,
        int(len(w) - len(below) - len(above)),
    )


def decide_rate(
    limit_ns: Fraction, timebase: Timebase, below: int | None, above: int | None, exact: int
) -> Fraction | None:
    """The sample rate that decides the nearest-to-decided indeterminate interval (see
    :attr:`wavecheck.engine.results.RuleResult.decide_samplerate_hz`), from :func:`decide_parts`' figures."""
    tick = timebase.tick_ns
    gaps = []
    if below is not None:
        gaps.append(limit_ns - below * tick)
    if above is not None:
        gaps.append(above * tick - limit_ns)
    if not gaps or exact:
        return None
    return Fraction(2 * 10**9) / min(gaps)


@record(frozen=True)
class Histogram:
    """Measured lengths counted in fixed bins: mergeable by adding counts.

    Bin 0 holds lengths ≤ 0 ticks; a length w ≥ 1 tick goes to bin ``4·(e − 1) + q + 1`` where
    ``2^(e−1) ≤ w < 2^e`` and ``q`` (0–3) is the quarter of that octave it lies in — four bins
    per octave, exact integer arithmetic (lengths below 2^53 ticks)."""

    counts: tuple[tuple[int, int], ...]
    """(bin, count) pairs for the bins that hold anything, in bin order."""

    @staticmethod
    def bins(w: EdgeArray) -> npt.NDArray[np.int64]:
        """The bin of each length ``w`` (ticks)."""
        pos = np.maximum(w, 1)
        e = np.frexp(pos)[1].astype(np.int64)  # 2^(e−1) ≤ w < 2^e, exact below 2^53
        # 4·(e − 1) + q + 1 with q = ⌊4w / 2^(e−1)⌋ − 4: the top three bits of w, less 4
        out = np.left_shift(pos, 2, out=pos)
        np.right_shift(out, e - 1, out=out)
        out += 4 * e - 7
        out[w <= 0] = 0
        return out

    @classmethod
    def of(cls, w: EdgeArray, bounds: tuple[int, int] | None = None) -> Histogram:
        """The histogram of the lengths ``w`` (ticks); ``bounds``: their (min, max) if known."""
        if not len(w):
            return cls(())
        lo, hi = (int(w.min()), int(w.max())) if bounds is None else bounds
        if hi - lo < _SPAN_COUNTED:  # count each length, then bin the distinct lengths
            lo = 0 if 0 <= lo and hi < _SPAN_COUNTED else lo  # no shifted copy of w
            c = np.bincount(w - lo if lo else w)
            v = np.flatnonzero(c)
            b = cls.bins(v + lo)  # ascending with v: its last is the largest
            total = np.zeros(int(b[-1]) + 1, dtype=np.int64)
            np.add.at(total, b, c[v])
            b = np.flatnonzero(total)
            return cls(tuple(zip(b.tolist(), total[b].tolist(), strict=True)))
        c = np.bincount(cls.bins(w))  # a few hundred bins at most: counting beats sorting
        b = np.flatnonzero(c)
        return cls(tuple(zip(b.tolist(), c[b].tolist(), strict=True)))

    def __add__(self, other: Histogram) -> Histogram:
        total: dict[int, int] = dict(self.counts)
        for b, c in other.counts:
            total[b] = total.get(b, 0) + c
        return Histogram(tuple(sorted(total.items())))

    @staticmethod
    def lower_edge(bin_: int) -> Fraction:
        """The smallest length (ticks, exact) of bin ``bin_`` ≥ 1."""
        e, q = divmod(bin_ - 1, 4)
        return Fraction(2**e) * (1 + Fraction(q, 4))


@functools.lru_cache(maxsize=64)
def _thresholds(limit_ns: Fraction, tick_ns: Fraction, resolution_ns: Fraction) -> tuple[int, int]:
    """(pass_min, fail_max) in ticks: pass ⟺ W ≥ pass_min, fail ⟺ W ≤ fail_max (exact; once per
    rule, not once per window)."""
    pass_min = _clamp(math.ceil((limit_ns + resolution_ns) / tick_ns))
    fail_max = _clamp(math.floor((limit_ns - resolution_ns) / tick_ns))
    return pass_min, fail_max


def evaluate(
    rule: str,
    intervals: Intervals,
    limit_ns: Fraction,
    timebase: Timebase,
    resolution_ns: Fraction,
) -> Judged:
    """Judge every interval of ``rule`` against ``limit_ns`` (exact ns) at resolution T (exact
    ns)."""
    pass_min, fail_max = _thresholds(limit_ns, timebase.tick_ns, resolution_ns)
    w = intervals.measured
    lo, hi = intervals.bounds
    if len(w) and lo >= pass_min:  # every one passes (the usual case), or every one fails
        outcome = np.full(len(w), PASS, dtype=np.int8)
    elif len(w) and hi <= min(fail_max, pass_min - 1):
        outcome = np.full(len(w), FAIL, dtype=np.int8)
    else:
        outcome = np.full(len(w), INDETERMINATE, dtype=np.int8)
        outcome[w <= fail_max] = FAIL
        outcome[w >= pass_min] = PASS  # pass is tested first: it wins where both hold (T = 0)
    return Judged(rule, intervals, outcome, len(intervals))


def sequence_result(ticks: EdgeArray, details: list[str], transitions: int) -> Judged:
    """The ``state_sequence`` rule: every listed tick is a move to a non-neighbour state, of
    ``transitions`` state changes examined."""
    return Judged(
        "state_sequence",
        Intervals(ticks, ticks),
        np.full(len(ticks), FAIL, dtype=np.int8),
        transitions,
        details,
    )
