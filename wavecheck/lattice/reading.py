"""Readings of one exact lattice: where lateness 0 lies, decided by the model's facts.

A lattice of period P (exact ticks) can be read with lateness 0 at any phase; the readings
differ in what they imply. One invocation writes once, so a reading that puts two distinct edge
times into one period is infeasible (:meth:`Fold.collisions` counts them for every anchor at
once); latency does not depend on which pin an invocation changes, so a reading in which it
does is no thread's latency (:func:`_kind_dependence`, a Kuiper test per channel and direction),
except LinuxCNC's worst case ``worst:J:RULE``: two exact lateness values, the on-time edges
exactly RULE's end events (:func:`_worst`, :mod:`wavecheck.linuxcnc.worstcase`). Otherwise the
feasible anchor with the least mean lateness (:func:`_natural`), and both readings when the
capture cannot tell them apart. Used by :mod:`wavecheck.lattice` (see its docstring).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from fractions import Fraction

import numpy as np
import numpy.typing as npt

from wavecheck.linuxcnc.worstcase import union

__all__ = [
    "MAX_LOG10_CHANCE",
    "MIN_GAP_FRACTION",
    "MIN_EDGES",
    "EdgeKinds",
    "Evaluation",
    "Fold",
    "Reading",
    "Signatures",
    "allowance",
    "ascending",
    "bursts",
    "catch_up",
    "evaluate",
    "significance",
    "two_point",
    "widest_gap",
]

#: Fewest distinct edge times from which a period is inferred.
MIN_EDGES = 8


#: Largest chance (log10) that edges not made by a periodic thread fit as well.
MAX_LOG10_CHANCE = -6.0


#: Kuiper test: a channel/direction's lateness differs from the others' when V·√n_e exceeds
#: this (chance about 4·10⁻⁴) and V is at least :data:`KIND_EFFECT`.
KIND_CRITICAL = 2.4


KIND_EFFECT = 0.3


Ints = npt.NDArray[np.int64]


Floats = npt.NDArray[np.float64]


Signatures = tuple[tuple[str, Ints], ...]


@dataclass
class EdgeKinds:
    """What changed at each edge time: ``bits`` has bit 2c (channel c fell) and 2c + 1 (rose).

    ``signatures`` (computed by ``source`` when first needed): for each of LinuxCNC's
    worst-case rules that could apply, the edge times at which ``worst:J:RULE`` runs the thread
    on time (its intervals' end events), by rule name.
    """

    names: tuple[str, ...]
    bits: Ints
    source: Callable[[], Signatures] | None = None
    _signatures: Signatures | None = field(default=None, repr=False)

    @property
    def signatures(self) -> Signatures:
        """The rules' end events (see the class docstring)."""
        if self._signatures is None:
            self._signatures = self.source() if self.source is not None else ()
        return self._signatures

    def label(self, kind: int) -> str:
        """``"step rising"`` for kind 2c + 1."""
        return f"{self.names[kind // 2]} {'rising' if kind % 2 else 'falling'}"


@dataclass(frozen=True)
class Reading:
    """One way to read a lattice: where lateness 0 is and what follows from it.

    Attributes:
        anchor: lattice point of invocation 0 in units (1/b tick) after the first edge.
        collisions: how often two distinct edge times fall into one period under this reading.
        max_lateness: the largest lateness (ticks, exact).
        rule: the worst-case rule whose end events are exactly the on-time edges (or "").
    """

    anchor: int
    collisions: int
    max_lateness: Fraction
    rule: str = ""


class Fold:
    """The edges folded at an exact period ``a/b`` ticks: phases, and for every anchor (in bins
    of ``w`` units) the collisions and mean lateness of the reading it makes."""

    def __init__(self, times: Ints, period: Fraction, res: int, bins: int = 1 << 20) -> None:
        self.period = period
        self.a, self.b = period.numerator, period.denominator
        self.units = (times - times[0]) * self.b
        self.x = np.mod(self.units, self.a)
        self.w = max(1, -(-self.a // bins))
        self.nb = -(-self.a // self.w)
        self.q = max(res, 1) * self.b  # one sample in units
        self.bins = self.x // self.w if self.w > 1 else self.x
        self.hist = np.bincount(self.bins, minlength=self.nb)
        self.n = len(times)
        self._last: tuple[int, tuple[Ints, Ints]] | None = None

    def collisions(self) -> Ints:
        """For each anchor bin: pairs of successive edge times in one period."""
        d = np.diff(self.units)
        close = np.flatnonzero(d < self.a)
        size = 2 * self.nb + 2
        cover = np.zeros(size, np.int64)
        if len(close):
            first = self.x[close] // self.w + 1
            end = self.x[close] + d[close]  # past the period: the next period's bins (the
            # last bin is shorter than w when w does not divide the period)
            last = np.where(end >= self.a, self.nb + (end - self.a) // self.w, end // self.w)
            cover = np.bincount(first, minlength=size) - np.bincount(last + 1, minlength=size)
        c = np.cumsum(cover)
        covered = c[: self.nb] + c[self.nb : 2 * self.nb]
        return len(close) - covered

    def mean_bins(self) -> Ints:
        """For each anchor bin: the summed lateness in bins (its argmin: least mean lateness)."""
        y = np.arange(self.nb, dtype=np.int64)
        s0 = int(self.bins.sum())
        before = np.concatenate([[0], np.cumsum(self.hist)[:-1]])
        return s0 - y * self.n + self.nb * before

    def anchor_at(self, bin_: int) -> int:
        """The exact anchor of bin ``bin_``: the earliest phase at or after its start."""
        start = bin_ * self.w
        return start + int(np.min(np.mod(self.x - start, self.a)))

    def lateness(self, anchor: int) -> tuple[Ints, Ints]:
        """(invocation, lateness in units) of every edge (the last anchor's kept: the same
        reading is asked for several times)."""
        if self._last is None or self._last[0] != anchor:
            k = np.floor_divide(self.units - anchor, self.a)
            self._last = anchor, (k, self.units - anchor - k * self.a)
        return self._last[1]

    def reading(self, bin_: int, collisions: Ints) -> Reading:
        anchor = self.anchor_at(bin_)
        _, lat = self.lateness(anchor)
        return Reading(anchor, int(collisions[bin_]), Fraction(int(lat.max()), self.b))

    def candidate_bins(self, limit: int = 6) -> Ints:
        """Anchor bins worth reading: the starts of phase clusters after the widest gaps that
        are at least a sample and a 64th of the period wide (the start after the widest gap
        when none is)."""
        min_gap = max(1, -(-max(self.q, self.a // 64) // self.w))
        starts, _ = _runs(self.hist > 0, min_gap)
        if len(starts) <= limit:
            return starts
        occ = np.flatnonzero(self.hist > 0)
        prev = occ[np.searchsorted(occ, starts) - 1]  # the occupied bin before each start
        gap = np.mod(starts - prev, self.nb)
        return starts[np.argsort(-gap, kind="stable")[:limit]]

    def clusters(self) -> tuple[Ints, Ints]:
        """Phase clusters (first bin, width in units): occupied phases less than a sample apart
        belong together, so one lattice point seen at sub-sample offsets is one cluster."""
        starts, lasts = _runs(self.hist > 0, max(0, -(-self.q // self.w) - 1))
        return starts, (np.mod(lasts - starts, self.nb) + 1) * self.w


def _runs(occupied: npt.NDArray[np.bool_], min_gap: int) -> tuple[Ints, Ints]:
    """Circular runs of occupied bins separated by at least ``min_gap`` empty bins:
    (first bin, last bin) of each."""
    nb = len(occupied)
    occ = np.flatnonzero(occupied)
    if not len(occ):
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    gaps = np.diff(np.concatenate([occ, [occ[0] + nb]])) - 1  # empty bins after each
    ends = np.flatnonzero(gaps >= min_gap)
    if not len(ends):
        k = int(np.argmax(gaps))
        return occ[[(k + 1) % len(occ)]], occ[[k]]
    return occ[(ends + 1) % len(occ)], occ[np.roll(ends, -1)]


def _kind_dependence(fold: Fold, kinds: EdgeKinds) -> tuple[int, float] | None:
    """The channel/direction whose phases differ most from the other edges' (kind, Kuiper V),
    when one differs significantly; None when lateness does not depend on what changed.

    Phases are compared in bins of two samples at two offsets (the smaller V counts), so the
    sub-sample offsets of a lattice that is not a whole number of samples are not a difference.
    """
    nbk = int(max(8, min(4096, fold.a // (2 * fold.q))))
    seen = int(np.bitwise_or.reduce(kinds.bits)) if len(kinds.bits) else 0
    present = [c for c in range(64) if seen >> c & 1]
    if len(present) < 2:
        return None
    best: tuple[int, float] | None = None
    worst_v: dict[int, float] = {}
    # the edges grouped by what changed at them (a few combinations): one count per offset
    combos, group = _groups(kinds.bits)
    for offset in (0, fold.a // (2 * nbk)):
        bins = np.mod((fold.x + offset) * nbk // fold.a, nbk)
        per = np.bincount(group * nbk + bins, minlength=len(combos) * nbk).reshape(-1, nbk)
        hists = {c: per[((combos >> c) & 1) == 1].sum(axis=0) for c in present}
        total = np.sum(list(hists.values()), axis=0)
        n_all = int(total.sum())
        for c, h in hists.items():
            n1 = int(h.sum())
            n2 = n_all - n1
            if n1 < MIN_EDGES or n2 < MIN_EDGES:
                worst_v[c] = 0.0
                continue
            diff = np.cumsum(h) / n1 - np.cumsum(total - h) / n2
            v = float(max(diff.max(), 0.0) + max(-diff.min(), 0.0))
            ne = n1 * n2 / (n1 + n2)
            v = v if v >= KIND_EFFECT and v * math.sqrt(ne) >= KIND_CRITICAL else 0.0
            worst_v[c] = min(worst_v.get(c, v), v)
    for c, v in worst_v.items():
        if v > 0 and (best is None or v > best[1]):
            best = (c, v)
    return best


def _groups(bits: Ints) -> tuple[Ints, Ints]:
    """(the distinct values of ``bits``, each element's index among them): counted when the
    values are small (a few channels), else sorted."""
    if int(bits.max()) < 1 << 16:
        seen = np.bincount(bits)
        combos = np.flatnonzero(seen)
        index = np.zeros(len(seen), np.int64)
        index[combos] = np.arange(len(combos))
        return combos, index[bits]
    combos, group = np.unique(bits, return_inverse=True)
    return combos, group.reshape(-1)


def _rule_of(times: Ints, on_time: npt.NDArray[np.bool_], kinds: EdgeKinds | None) -> str:
    """The worst-case rule whose end events are exactly the ``on_time`` edge times ("" none);
    only the first two and last two edge times may differ (a capture cut mid-pulse)."""
    if kinds is None:
        return ""
    got = times[on_time]
    ends = np.concatenate([times[:2], times[-2:]])
    for rule, events in kinds.signatures:
        if not len(events):
            continue
        diff = np.setxor1d(got, events, assume_unique=True)
        if not len(np.setdiff1d(diff, ends, assume_unique=False)):
            return rule
    return ""


@dataclass
class Evaluation:
    """What a lattice at one exact period says: its fold, the readings kept (one: decided;
    several: the capture cannot tell them apart), or why none is a thread's latency."""

    fold: Fold
    readings: list[Reading]
    refused: str = ""
    slots: Ints = field(default_factory=lambda: np.zeros(0, np.int64))

    @property
    def collisions(self) -> int:
        return min((r.collisions for r in self.readings), default=self.fold.n)


def evaluate(
    times: Ints,
    period: Fraction,
    res: int,
    kinds: EdgeKinds | None,
    bins: int = 1 << 20,
    judge: bool = True,
) -> Evaluation:
    """Read the lattice at ``period`` (exact ticks), its phases in at most ``bins`` bins: see
    step 3 of the module docstring. ``judge`` False skips the test of latency depending on the
    pin (a quick look at a candidate: the chosen period is judged)."""
    fold = Fold(times, period, res, bins)
    coll = fold.collisions()
    worst = _worst(times, fold, coll, kinds) if kinds is not None else []
    if worst:
        ev = Evaluation(fold, worst)
    else:
        dep = _kind_dependence(fold, kinds) if kinds is not None and judge else None
        if dep is None or kinds is None:
            ev = Evaluation(fold, _natural(fold, coll))
        else:
            ev = _dependent(fold, kinds, dep)
    if ev.readings:
        ev.slots = fold.lateness(ev.readings[0].anchor)[0]
    return ev


def allowance(n: int) -> int:
    """Double writes a reading may have beyond the fewest and still count as feasible: a few
    catch-up runs (invocations a period or more late) make them under any reading."""
    return max(2, n // 100)


def _natural(fold: Fold, coll: Ints) -> list[Reading]:
    """Readings of latency that does not depend on the pin: the feasible anchor (fewest
    collisions) among the cluster starts after wide gaps with the least mean lateness (most
    invocations run almost on time).

    When half the edges or more sit within one sample (a punctual bulk) and the two samples
    before it hold less than a third as many, the start of that bulk is a reading too: if it
    is feasible and its maximum is larger, it comes second (a few edges a sample or two before
    the bulk: late by nearly P, or is the bulk late by a sample or two? The capture cannot
    tell; the larger is the one to plan from)."""
    cands = fold.candidate_bins()
    cands = cands[coll[cands] <= coll[cands].min() + allowance(fold.n)]
    mean = fold.mean_bins()[cands]
    chosen = fold.reading(int(cands[int(np.argmin(mean))]), coll)
    out = [chosen]
    width = max(1, fold.q // fold.w)  # bins per sample
    dense = np.convolve(
        np.concatenate([fold.hist, fold.hist[: width - 1]]), np.ones(width), "valid"
    )
    top = int(np.argmax(dense))
    before = np.arange(top - 2 * width, top) % fold.nb
    if dense[top] >= fold.n / 2 and 3 * fold.hist[before].sum() < dense[top]:
        bulk = int(np.flatnonzero(fold.hist[np.arange(top, top + width) % fold.nb])[0] + top)
        r = fold.reading(bulk % fold.nb, coll)
        if r.collisions <= chosen.collisions and r.max_lateness > chosen.max_lateness:
            out.append(r)
    return out


def two_point(fold: Fold) -> tuple[Ints, Ints]:
    """The starts and widths (units) of the two phase clusters when every edge is within two
    samples of one of two phases (LinuxCNC's worst case: lateness 0 or J), else none."""
    starts, widths = fold.clusters()
    if len(starts) == 2 and bool(np.all(widths <= 2 * fold.q + fold.w)):
        return starts, widths
    return np.zeros(0, np.int64), np.zeros(0, np.int64)


def _worst(times: Ints, fold: Fold, coll: Ints, kinds: EdgeKinds | None) -> list[Reading]:
    """The readings of a two-point lattice whose on-time edges (its first cluster) are exactly
    a worst-case rule's end events (both when both are: the capture cannot tell J from
    P − J)."""
    kept = []
    starts, widths = two_point(fold)
    readings = [fold.reading(int(s), coll) for s in starts]
    least = min((r.collisions for r in readings), default=0)
    for r, width in zip(readings, widths, strict=True):
        if r.collisions > least + allowance(fold.n):
            continue
        _, lat = fold.lateness(r.anchor)
        rule = _rule_of(times, lat < width, kinds)
        if rule:
            kept.append(Reading(r.anchor, r.collisions, r.max_lateness, rule))
    return kept


def _dependent(fold: Fold, kinds: EdgeKinds, dep: tuple[int, float]) -> Evaluation:
    """Lateness that depends on the pin and is no worst case: no thread's latency."""
    if len(two_point(fold)[0]):
        why = (
            "every edge is on one of two exact offsets from a {period} lattice, set "
            "by which pin changed, and the on-time edges are no rule's end events: a hardware "
            "step timer, not a thread's latency"
        )
    else:
        kind, v = dep
        why = (
            f"the phase of the {kinds.label(kind)} edges differs from the other edges' "
            f"(Kuiper V = {v:.2f}) on the best lattice ({{period}}): a thread's "
            "latency does not depend on which pin it changes (a step timer with its own pulse "
            "timer, or pins written at different times)"
        )
    return Evaluation(fold, [], refused=why)


def significance(
    lat: Ints, b: int, q: int, period: Fraction, span_p: int
) -> tuple[int, int, float, float]:
    """(99th percentile lateness in units, edges within it, its arc fraction, log10 chance).

    The chance that n edges not made by a thread put m of them within an arc of fraction f: at
    most trials · n · P(Binomial(n, f) ≥ m), bounded by Chernoff, exp(−n·KL(m/n ‖ f)); taken
    for the arc of every edge and for that of 99 % of them (spikes). A worst-case pattern puts
    the edges on a few points: for K arcs (cut at the K widest gaps, each arc a sample longer)
    covering a fraction f, the first edge of each arc falls anywhere and the others within
    theirs: at most trials · n^K · f^(n − K). The smallest of these counts.
    """
    n = len(lat)
    rank = max(1, math.ceil(0.99 * n))
    p99 = int(np.partition(lat, rank - 1)[rank - 1])
    in_arc = int(np.count_nonzero(lat <= p99))
    f99 = min(1.0, (p99 / b + q) / float(period))
    f_all = min(1.0, (int(lat.max()) / b + q) / float(period))
    trials = math.log10(max(span_p, 1) * 10.0 * n)
    best = 0.0
    for m, f in ((in_arc, f99), (n, f_all)):
        a = m / n
        if a <= f or f >= 1.0:
            continue
        kl = a * math.log(a / f) + ((1 - a) * math.log((1 - a) / (1 - f)) if a < 1 else 0.0)
        best = min(best, trials - n * kl / math.log(10))
    counts = _counts(lat)
    values = np.flatnonzero(counts) if len(counts) else union(lat)  # sorted, distinct
    a_units = float(period) * b
    gaps = np.sort(np.diff(np.append(values, values[0] + a_units)))[::-1][:8]
    for k in range(1, len(gaps) + 1):
        f = min(1.0, 1.0 - float(gaps[:k].sum()) / a_units + k * q * b / a_units)
        if 0 < f < 1 and n > k:
            best = min(best, trials + k * math.log10(n) + (n - k) * math.log10(f))
    return p99, in_arc, f99, best


#: The empty arc a lattice must show (fraction of P; and at least two samples): invocations
#: that are never more than a bounded time late leave the rest of each period without edges.
#: Non-uniform phases alone (a step rate folded at a period it beats with) are no lattice.
MIN_GAP_FRACTION = 0.03


def _counts(values: Ints) -> Ints:
    """How often each value 0 … max occurs in ``values`` (non-negative): the sorted values in
    linear time, when that range is at most a few times their number (else empty)."""
    top = int(values.max()) + 1 if len(values) else 0
    if not len(values) or top > 4 * len(values) + (1 << 16):
        return np.zeros(0, np.int64)
    return np.bincount(values, minlength=top)


def ascending(values: Ints) -> Ints:
    """``values`` (non-negative integers) sorted: counted when their range allows (linear)."""
    counts = _counts(values)
    return np.repeat(np.arange(len(counts)), counts) if len(counts) else np.sort(values)


def widest_gap(lat: Ints, a: int) -> int:
    """The widest arc (units) between two edges' phases (``lat`` modulo ``a`` units) with at
    most ``max(2, n // 500)`` edges inside it (late spikes), measured edge to edge."""
    x = ascending(np.mod(lat, a))
    n = len(x)
    if not n:
        return a
    c = min(max(2, n // 500), n - 1)
    circle = np.concatenate([x, x + a])
    return int((circle[c + 1 : c + 1 + n] - x).max())


def catch_up(fold: Fold, reading: Reading) -> tuple[Ints, Ints, int]:
    """(invocation, lateness in units, edges moved) with every distinct edge time in its own
    invocation: where two fall into one period, the earlier belongs to an earlier invocation
    (a catch-up run); each is given the latest invocation it can have, so the lateness is the
    least the edges allow."""
    k, lat = fold.lateness(reading.anchor)
    if not reading.collisions:
        return k, lat, 0
    i = np.arange(len(k), dtype=np.int64)
    lowest = np.minimum.accumulate((k - i)[::-1])[::-1] + i  # k_i ≤ slot_i, strictly rising
    moved = int(np.count_nonzero(lowest != k))
    return lowest, fold.units - reading.anchor - lowest * fold.a, moved


def bursts(times: Ints, pmin: float) -> npt.NDArray[np.bool_]:
    """Edges of catch-up runs: three distinct edge times within the shortest period, which a
    thread less than a period late cannot make (invocations k and k + 2 are more than P apart
    when each is less than P late), but one catching up after a longer delay does."""
    out = np.zeros(len(times), bool)
    if len(times) >= 3:
        at = np.flatnonzero(times[2:] - times[:-2] < pmin)
        out[at] = out[at + 1] = out[at + 2] = True
    return out
