"""The one result type per rule and the step counts, merged window by window, in bounded memory:
the same figures whatever the windows (tests/wavecheck/engine hold one window against many).

:class:`RuleResult` is what every renderer reads: counts (checked, violations, indeterminate,
unknown), the shortest and longest interval and where the shortest is, the worst ``keep``
violations (ties in the intervals' order), the figures that decide ``decide_samplerate_hz``, and,
when pictures are asked for (``binned``), a fixed-bin
:class:`~wavecheck.engine.judge.Histogram`. What it does not keep: every interval
(each window's :class:`~wavecheck.engine.judge.Judged` is merged and dropped); the pictures
draw from these results and the signal windows kept around the worst places
(:mod:`wavecheck.engine.windows`); whatever needs every step or interval is a sink
(:mod:`wavecheck.engine.sinks`).
"""

from __future__ import annotations

import heapq
from fractions import Fraction

import numpy as np

from wavecheck.capture.edges import EdgeArray
from wavecheck.drives.datasheet import Figure
from wavecheck.engine.judge import (
    FAIL,
    INDETERMINATE,
    Histogram,
    Judged,
    Violation,
    decide_parts,
    decide_rate,
)
from wavecheck.record import field, record
from wavecheck.timebase import Timebase
from wavecheck.verdict import Verdict

__all__ = ["FRESH_KEPT", "UNKNOWN_KEPT", "RuleResult", "StepCounts"]

#: Unknown places and ambiguous steps listed (the first ones; the counts are exact).
UNKNOWN_KEPT = 100
#: Violations of one window handed to :attr:`RuleResult.fresh`.
FRESH_KEPT = 64
#: Distinct measured lengths (or ``state_sequence`` details) whose violations are counted with
#: their first and last time over the whole capture (:meth:`RuleResult.tally`): the shortest.
TALLY_KEPT = 4096

_Key = tuple[int, int, int]  # (measured ticks, order tick, other tick): the intervals' order


@record
class RuleResult:
    """One rule's results merged window by window (see the module docstring).

    ``order_by_end``: this rule's intervals are listed by their end event (``dir_hold``: by DIR
    change; ``dir_delay``: by the pulse after the switch; :attr:`wavecheck.rules.Rule.listed_by_end`),
    not by start; ties (same length) are broken in that order. ``binned``: keep the measured
    lengths' :meth:`histogram` (only a picture draws it).
    """

    rule: str
    limit_ns: Fraction | None
    figure: Figure | None
    timebase: Timebase
    resolution_ns: Fraction
    keep: int = 1000
    order_by_end: bool = False
    binned: bool = True
    checked: int = 0
    fails: int = 0
    indet: int = 0
    left_out: int = 0
    uncovered: int = 0
    _unknown_first: list[int] = field(default_factory=list)  # max-heap (negated), bounded
    _best: _Key | None = None
    _longest: int | None = None
    _below: int | None = None
    _above: int | None = None
    _exact: int = 0
    _worst: list[tuple[_Key, int, int, str]] = field(default_factory=list)  # sorted, bounded
    _hist: Histogram = field(default_factory=lambda: Histogram(()))
    _tally: dict[int | str, list[int]] = field(default_factory=dict)  # key → [n, first, last]
    _tally_floor: int | None = None  # lengths from this one on are no longer tallied
    covered: set[int] = field(default_factory=set)
    """Start ticks of the unknown stretches an interval left out has touched (so far)."""
    fresh: list[tuple[int, int]] | None = None
    """When a list: (start, end) ticks of violations found since the caller last emptied it, in
    time order, at most :data:`FRESH_KEPT` per window (a live watch saves snippets around them)."""

    # -- merging -----------------------------------------------------------------------------
    def _key(self, start: EdgeArray, end: EdgeArray) -> tuple[EdgeArray, EdgeArray]:
        return (end, start) if self.order_by_end else (start, end)

    def add(self, part: Judged, left_out: EdgeArray) -> None:
        """Merge one window's judged intervals (``part``) and the starts of the intervals it left
        out as unknown (touching an x/z stretch)."""
        fails, indet = part.violations, part.indeterminate
        self.checked += part.checked
        self.fails += fails
        self.indet += indet
        self._add_unknown(left_out)
        self.left_out += len(left_out)
        iv = part.intervals
        if self.fresh is not None and fails:
            f = np.flatnonzero(part.outcome == FAIL)[:FRESH_KEPT]
            self.fresh.extend(zip(iv.start[f].tolist(), iv.end[f].tolist(), strict=True))
        if self.limit_ns is None:  # state_sequence: errors in time order, no length
            if len(iv):
                self._tally_keys(np.asarray(part.details[: len(iv)], dtype=str), iv.start)
            if len(self._worst) < self.keep:
                for i in range(min(len(iv), self.keep - len(self._worst))):
                    t = int(iv.start[i])
                    self._worst.append(((0, t, t), t, t, part.details[i]))
            return
        if not len(iv):
            return
        w = iv.measured
        a, b = self._key(iv.start, iv.end)
        lo, hi = iv.bounds
        self._shortest(w, a, b, lo)
        self._longest = hi if self._longest is None else max(self._longest, hi)
        if self.binned:
            self._hist = self._hist + Histogram.of(w, (lo, hi))
        if indet:
            ind = part.outcome == INDETERMINATE
            below, above, exact = decide_parts(self.limit_ns, self.timebase, w[ind])
            if below is not None:
                self._below = below if self._below is None else max(self._below, below)
            if above is not None:
                self._above = above if self._above is None else min(self._above, above)
            self._exact += exact
        if fails:
            self._add_worst(part, w, a, b, lo)
            self._tally_fails(part, w)

    def _tally_fails(self, part: Judged, w: EdgeArray) -> None:
        """Count the failed intervals by measured length, with the first and last start tick
        of each length (numpy per window; a Python step per distinct length, the shortest
        :data:`TALLY_KEPT` only)."""
        f = np.flatnonzero(part.outcome == FAIL)
        self._tally_keys(w[f], part.intervals.start[f])

    def _tally_keys(self, keys: np.ndarray, starts: EdgeArray) -> None:
        """Tally ``keys`` (lengths, or details) with the start ticks ``starts``."""
        uniq, inverse, counts = np.unique(keys, return_inverse=True, return_counts=True)
        first = np.full(len(uniq), np.iinfo(np.int64).max, dtype=np.int64)
        last = np.full(len(uniq), np.iinfo(np.int64).min, dtype=np.int64)
        np.minimum.at(first, inverse, starts)
        np.maximum.at(last, inverse, starts)
        for k, key in enumerate(uniq[:TALLY_KEPT].tolist()):
            self._count(key, int(first[k]), int(last[k]), int(counts[k]))
        if len(uniq) > TALLY_KEPT and uniq.dtype.kind == "i":
            self._evict(int(uniq[TALLY_KEPT]))

    def _count(self, key: int | str, first: int, last: int, n: int) -> None:
        if isinstance(key, int) and self._tally_floor is not None and key >= self._tally_floor:
            return
        if key not in self._tally and len(self._tally) >= TALLY_KEPT:
            if isinstance(key, str):
                return
            longest = max(k for k in self._tally if isinstance(k, int))
            if key > longest:
                self._evict(key)
                return
            self._evict(longest)
        got = self._tally.get(key)
        if got is None:
            self._tally[key] = [n, first, last]
        else:
            got[0] += n
            got[1] = min(got[1], first)
            got[2] = max(got[2], last)

    def _evict(self, floor: int) -> None:
        """Stop tallying lengths from ``floor`` on (they are the least short)."""
        self._tally_floor = floor if self._tally_floor is None else min(self._tally_floor, floor)
        for k in [k for k in self._tally if isinstance(k, int) and k >= self._tally_floor]:
            del self._tally[k]

    def tally(self, key: int | str) -> tuple[int, int, int] | None:
        """Every violation of measured length ``key`` ticks (``state_sequence``: of detail
        ``key``) over the whole capture: (count, first start tick, last start tick); None when
        that length was not tallied (beyond the :data:`TALLY_KEPT` shortest)."""
        got = self._tally.get(key)
        return None if got is None else (got[0], got[1], got[2])

    def _shortest(self, w: EdgeArray, a: EdgeArray, b: EdgeArray, lo: int) -> None:
        """Keep the shortest interval (``lo`` ticks), ties broken in the intervals' order."""
        if self._best is not None and (
            lo > self._best[0] or lo == self._best[0] and a.min() > self._best[1]
        ):
            return  # cannot beat the one kept
        least = np.flatnonzero(w == lo)
        la = a[least]
        first = int(la.min())
        best = (lo, first, int(b[least[la == first]].min()))
        if self._best is None or best < self._best:
            self._best = best

    def _add_worst(self, part: Judged, w: EdgeArray, a: EdgeArray, b: EdgeArray, lo: int) -> None:
        """Merge the failed intervals that beat the last of the kept worst ones."""
        if len(self._worst) >= self.keep:
            (kw, ka, kb), _, _, _ = self._worst[-1]
            if lo > kw or lo == kw and a.min() > ka:
                return  # a cheap reject: none is shorter, none as short and earlier
            f = np.flatnonzero((part.outcome == FAIL) & (w <= kw))
            fw, fa, fb = w[f], a[f], b[f]
            f = f[(fw < kw) | ((fw == kw) & ((fa < ka) | ((fa == ka) & (fb < kb))))]
        else:
            f = np.flatnonzero(part.outcome == FAIL)
            if len(f) > self.keep:  # only the shortest ``keep`` lengths can be kept
                fw = w[f]
                f = f[fw <= np.partition(fw, self.keep - 1)[self.keep - 1]]
        if len(f):
            iv = part.intervals
            fw, fa, fb = w[f], a[f], b[f]
            order = np.lexsort((fb, fa, fw))[: self.keep]
            new = [
                ((int(fw[j]), int(fa[j]), int(fb[j])), int(iv.start[f[j]]), int(iv.end[f[j]]), "")
                for j in order.tolist()
            ]
            self._worst = heapq.nsmallest(self.keep, [*self._worst, *new])

    def places_signature(self, n: int) -> tuple[object, ...]:
        """What the places of the worst ``n`` violations and of the smallest margin depend on:
        equal signatures, equal places (cheap: no :class:`Violation` built)."""
        return (self._best, tuple((w[1], w[2]) for w in self._worst[:n]))

    def _add_unknown(self, ticks: EdgeArray) -> None:
        heap = self._unknown_first
        for t in ticks.tolist():
            if len(heap) < UNKNOWN_KEPT:
                heapq.heappush(heap, -t)
            elif -t > heap[0]:
                heapq.heapreplace(heap, -t)

    def add_sequence(self, transitions: int) -> None:
        """Count ``transitions`` state changes examined (``state_sequence``)."""
        self.checked += transitions

    def close_stretches(self, starts: EdgeArray) -> None:
        """At the end: ``starts`` are every unknown stretch of the rule's signals; those no left-out
        interval touched count as unknown places of their own."""
        lone = np.array([s for s in starts.tolist() if s not in self.covered], dtype=np.int64)
        self.uncovered += len(lone)
        self._add_unknown(lone)

    # -- RuleOutcome ---------------------------------------------------------------------------
    @property
    def violations(self) -> int:
        """Number of failed intervals."""
        return self.fails

    @property
    def indeterminate(self) -> int:
        """Number of intervals this resolution cannot decide."""
        return self.indet

    @property
    def unknown(self) -> int:
        """Intervals left out as unknown plus stretches that no interval touched."""
        return self.left_out + self.uncovered

    @property
    def unknown_ticks(self) -> EdgeArray:
        """The first :data:`UNKNOWN_KEPT` unknown places, in time order (the count is
        :attr:`unknown`)."""
        return np.array(sorted(-t for t in self._unknown_first), dtype=np.int64)

    @property
    def verdict(self) -> Verdict:
        """As :attr:`RuleResult.verdict`."""
        if self.checked == 0:
            return "unchecked"
        if self.fails:
            return "fail"
        if self.indet:
            return "indeterminate"
        return "pass"

    @property
    def min_measured_ns(self) -> Fraction | None:
        """The shortest measured interval, exact ns."""
        if self._best is None or self.limit_ns is None:
            return None
        return self.timebase.ns(self._best[0])

    @property
    def max_measured_ns(self) -> Fraction | None:
        """The longest measured interval, exact ns."""
        if self._longest is None or self.limit_ns is None:
            return None
        return self.timebase.ns(self._longest)

    @property
    def min_margin_ns(self) -> Fraction | None:
        """min(measured − limit), exact ns."""
        m = self.min_measured_ns
        return None if m is None or self.limit_ns is None else m - self.limit_ns

    @property
    def min_margin_at_tick(self) -> int | None:
        """Start tick of the (first) interval with the smallest margin."""
        if self._best is None or self.limit_ns is None:
            return None
        _, a, b = self._best
        return b if self.order_by_end else a

    @property
    def min_margin_at_s(self) -> Fraction | None:
        """:attr:`min_margin_at_tick` in exact seconds."""
        t = self.min_margin_at_tick
        return None if t is None else self.timebase.seconds(t)

    @property
    def decide_samplerate_hz(self) -> Fraction | None:
        """As :attr:`RuleResult.decide_samplerate_hz`, from the merged figures."""
        if self.limit_ns is None or not self.indet:
            return None
        return decide_rate(self.limit_ns, self.timebase, self._below, self._above, self._exact)

    def worst_violations(self, n: int) -> list[Violation]:
        """Up to ``n`` (at most :attr:`keep`) failed intervals, shortest first, ties in the whole
        path's order."""
        out = []
        for _, start, end, detail in self._worst[: max(n, 0)]:
            if self.limit_ns is None:
                measured = margin = None
            else:
                measured = self.timebase.ns(end - start)
                margin = measured - self.limit_ns
            out.append(
                Violation(
                    self.rule,
                    start,
                    end,
                    self.timebase.seconds(start),
                    measured,
                    self.limit_ns,
                    margin,
                    detail,
                )
            )
        return out

    def histogram(self) -> Histogram | None:
        """The measured intervals in fixed bins (None: not ``binned``, no picture was asked for)."""
        return self._hist if self.binned else None


@record
class StepCounts:
    """Step counts merged window by window: what the reports read of
    :class:`wavecheck.steps.decode.StepEvents` (which keeps every step)."""

    count: int = 0
    forward: int = 0
    reverse: int = 0
    ambiguous_count: int = 0
    ambiguous: EdgeArray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    """The first :data:`UNKNOWN_KEPT` steps of ambiguous direction (ticks)."""
    lost_from: int | None = None
    """The tick where a step line first went unknown (``x``/``z``) after its level was known:
    steps inside are not seen, so the position is unknown from there (None: never)."""

    @property
    def unknown(self) -> int:
        """Steps of unknown or ambiguous direction."""
        return self.count - self.forward - self.reverse

    @property
    def final_position(self) -> int | None:
        """forward − reverse, or None when any step's direction is unknown or steps may have
        been lost in an unknown stretch (:attr:`lost_from`)."""
        return None if self.unknown or self.lost_from is not None else self.forward - self.reverse

    def lose_from(self, tick: int) -> None:
        """A step line went unknown at ``tick``: the position is unknown from the earliest."""
        self.lost_from = tick if self.lost_from is None else min(self.lost_from, tick)

    def add(self, direction: np.ndarray, ambiguous: EdgeArray) -> None:
        """Merge one window's steps (their directions) and its ambiguous steps' ticks."""
        self.count += len(direction)
        self.forward += int(np.count_nonzero(direction > 0))
        self.reverse += int(np.count_nonzero(direction < 0))
        self.ambiguous_count += len(ambiguous)
        room = UNKNOWN_KEPT - len(self.ambiguous)
        if room > 0 and len(ambiguous):
            self.ambiguous = np.concatenate([self.ambiguous, ambiguous[:room]])
