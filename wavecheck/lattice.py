"""Base-thread latency read from the wire: the invocation lattice of a periodic thread.

Software step generation (LinuxCNC's ``stepgen.make-pulses`` in the base thread) changes its
pins only when the thread runs: invocation k is due at k·P and runs l_k ≥ 0 late (never early),
and every pin it changes changes at that one moment, ``phase + k·P + l_k``. From the edge times
of the mapped channels this module infers P, where lateness 0 lies, and each edge's lateness.

The limit (``stepgen-linuxcnc.md`` §2.3 and the Stepper Tuning chapter's n·P − J): an interval
stepgen makes n periods long lasts n·P − J when its first edge is J late and its last on time,
so the shortest, a STEP pulse of one period (steplen ≥ 1 period), lasts P − J. The thread still
makes a pulse while J < P: the largest lateness it can show and still produce steps is just
under one period, P − G, G being how long one invocation runs (the next cannot start before it
ends). From J = P on, an invocation runs after the next was due and the thread catches up G
apart (stepgen/latency.py). Lateness 0 … P − G is read; lateness of a period or more only where
the wire shows it (two write times in one period: a catch-up run), as a lower bound.

How (all times integer ticks, P exact):

1. Comb search (:func:`_coarse`): the densest stretch of edges is binned and Fourier-transformed;
   a lattice puts power at every harmonic h/P whatever the lateness (its spread only lowers the
   higher ones), so each fundamental is scored by its harmonics' summed power, refined on exact
   harmonic sums.
2. The family (:func:`_down`, :func:`_up`): the thread may be the comb's period, a fraction of it
   (a stepgen at its maximum rate uses every second invocation: a lattice at 2P fits, its other
   edges a period late) or a multiple (a lattice at P/m fits P's edges with the same lateness
   while that is below P/m). Taken: the period that reads the edges with the fewest double
   writes and the least lateness, the longest among those reading them alike; a worst-case
   pattern (below) the longest that shows it; a multiple m·P when the edges keep to residues of
   k mod m as their spacing varies, which a thread at P would not.
3. P refined (:func:`_grow`) over windows growing ×4, on the floor of each phase cluster's
   lateness (never negative, many invocations nearly on time), then the simplest rational within
   its uncertainty (a whole number of ticks when it is one; 25 µs sampled at 3.3 MHz is 165/2).
4. Where lateness 0 lies (:class:`_Fold`, :func:`_evaluate`), decided by the model's facts: one
   invocation writes once, so two distinct edge times in one period are impossible (counted for
   every anchor at once); latency does not depend on which pin an invocation changes, so a
   reading in which it does (Kuiper test per channel and direction) is no thread's latency,
   except LinuxCNC's worst case ``worst:J:RULE``: two exact lateness values, the on-time edges
   exactly RULE's end events (:mod:`wavecheck.linuxcnc.worstcase`). Natural latency: the feasible
   anchor with the least mean lateness. When the capture cannot tell two readings apart (J or
   P − J; a few edges a sample before the bulk), both are kept, the larger first: plan from it.

"Not a lattice" is a statistical statement: for n edges of which m lie within an arc of a fraction
f of P (or within K arcs of total fraction f), the chance that edges timed by anything else
(a hardware timer, grbl's and Smoothieware's step interrupts) fit as well is bounded
(:func:`_significance`); the capture is lattice-timed only if that is below 10⁻⁶, P lies in
5 µs (latency-histogram's shortest --base) … 1 ms and is at least 8 samples, and there are at
least :data:`MIN_EDGES` edges; the worst lateness is established from :data:`ESTABLISH_EDGES`.

Every edge is seen up to one sample late and lateness 0 is itself an edge, so each lateness is
exact to ± one sample; the maximum also comes as an upper bound (measured + one sample) that is
never below the true one.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from fractions import Fraction

import numpy as np
import numpy.typing as npt

from wavecheck.capture.model import Capture
from wavecheck.errors import UsageError
from wavecheck.linuxcnc.steptypes import StepKind
from wavecheck.linuxcnc.worstcase import WORST_RULES, end_events, union
from wavecheck.progress import ProgressCallback, no_progress
from wavecheck.units import format_ns

__all__ = [
    "MAX_PERIOD_NS",
    "ESTABLISH_EDGES",
    "MIN_EDGES",
    "MIN_PERIOD_NS",
    "WINDOW_EDGES",
    "EdgeKinds",
    "LatencyReport",
    "LatticeFit",
    "Candidate",
    "CatchUp",
    "Reading",
    "Spike",
    "analyse",
    "analyse_times",
    "common_period",
    "simplest_between",
]

#: Fewest distinct edge times from which a period is inferred.
MIN_EDGES = 8
#: Fewest distinct edge times from which the worst lateness counts as established (fewer show
#: a lattice, but lattices at multiples or fractions of P may fit them as well, and a handful
#: of invocations says little of a machine's worst latency).
ESTABLISH_EDGES = 64
#: Largest chance (log10) that edges not made by a periodic thread fit as well.
MAX_LOG10_CHANCE = -6.0
#: Shortest base period considered (ns; latency-histogram refuses a --base below 5 us), and in
#: samples; longest (a single 1 ms thread running make-pulses).
MIN_PERIOD_NS = 5000
MIN_PERIOD_SAMPLES = 8
MAX_PERIOD_NS = 1_000_000
#: Edges the comb search looks at (the densest stretch of the capture).
WINDOW_EDGES = 1 << 14
#: Edges the comb search looks at, and refines its periods on (exact harmonic sums).
COMB_EDGES = 2048
#: Edges of the first window P is refined on: enough that the widest empty arc of their phases
#: is the lattice's even when lateness spans 95 % of the period.
GROW_EDGES = 512
#: Kuiper test: a channel/direction's lateness differs from the others' when V·√n_e exceeds
#: this (chance about 4·10⁻⁴) and V is at least :data:`KIND_EFFECT`.
KIND_CRITICAL = 2.4
KIND_EFFECT = 0.3

Ints = npt.NDArray[np.int64]
Floats = npt.NDArray[np.float64]


def simplest_between(lo: Fraction, hi: Fraction) -> Fraction:
    """The rational with the smallest denominator in ``[lo, hi]`` (0 < lo ≤ hi)."""
    if lo > hi or lo <= 0:
        raise ValueError(f"need 0 < lo <= hi, got {lo}, {hi}")
    whole = lo.numerator // lo.denominator
    if whole == lo:
        return Fraction(whole)
    if whole + 1 <= hi:
        return Fraction(whole + 1)
    return whole + 1 / simplest_between(1 / (hi - whole), 1 / (lo - whole))


# ----------------------------------------------------------------------------------------------
# Edge kinds: which channel changed, in which direction (and the worst-case rules' end events)


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


# ----------------------------------------------------------------------------------------------
# Step 1: the comb search


def _densest(times: Ints, span: int) -> tuple[int, int]:
    """[i, j) of the stretch of at most ``span`` ticks holding the most edges."""
    ends = np.searchsorted(times, times + span, side="left")
    i = int(np.argmax(ends - np.arange(len(times))))
    return i, int(ends[i])


def _coarse(
    times: Ints,
    pmin: float,
    pmax: float,
    harmonics: int = 16,
    keep: int = 3,
    edges: int = COMB_EDGES,
    bins: int = 1 << 20,
) -> list[float]:
    """Up to ``keep`` candidate periods (ticks, floats), best first, from the comb of the
    densest stretch (at most ``edges`` edges and ``bins`` FFT bins of 1/(2·``harmonics``) of
    the shortest period), each scored by its first ``harmonics`` harmonics."""
    bw = max(1, int(pmin // (2 * harmonics)))  # bins fine enough for the shortest period's
    i, j = _densest(times, bw * bins)
    j = min(j, i + edges)
    w = times[i:j] - times[i]
    if len(w) < MIN_EDGES or w[-1] < 2 * pmin:
        return []
    m = 1 << max(10, int(w[-1] // bw + 1).bit_length())
    hist = np.bincount(w // bw, minlength=m).astype(np.float64)
    power = np.abs(np.fft.rfft(hist)) ** 2 / len(w)  # the noise: exponential, mean 1
    length = m * bw  # frequency index f ↔ period length / f
    h_top = harmonics
    flo = max(2, math.ceil(length / pmax))
    fhi = int(min(length / pmin, (len(power) - h_top - 1) / h_top))
    if fhi <= flo:
        return []
    # summed power of the harmonics h of each fundamental f..f+1: harmonic h lies in bins
    # h·f .. h·f + h − 1, of which the largest counts (less the noise's expected largest)
    f = np.arange(flo, fhi + 1)
    z = np.zeros(len(f))
    for h in range(1, h_top + 1):
        top = power[h * f[:, None] + np.arange(h)[None, :]].max(axis=1)
        z += top - sum(1 / i for i in range(1, h + 1))
    peaks = np.flatnonzero((z[1:-1] >= z[:-2]) & (z[1:-1] >= z[2:])) + 1
    order = peaks[np.argsort(-z[peaks], kind="stable")]
    if not len(order):
        return []
    # a punctual lattice at P puts full power on every harmonic, so P/m scores as well as P:
    # the longest period whose comb scores nearly as well as the best's is first
    best = int(order[0])
    picked: list[float] = []
    for k in range(16, 1, -1):
        g = int(round((f[best] + 0.5) / k)) - flo
        if 1 <= g < len(z) - 1 and z[g - 1 : g + 2].max() >= 0.85 * z[best]:
            picked.append(float(f[g - 1 + int(np.argmax(z[g - 1 : g + 2]))]) + 0.5)
            break
    for k in order:  # then the best few, each at least two bins from the others
        if all(abs(f[k] + 0.5 - g) > 2 for g in picked):
            picked.append(float(f[k]) + 0.5)
        if len(picked) >= keep:
            break
    return [_refine_comb(w, length / g, 0.6 / g) for g in picked[:keep]]


def _refine_comb(t: Ints, p: float, width: float) -> float:
    """``p`` refined to where the summed power of the first 12 harmonics of edge times ``t``
    peaks, within ±``width`` (relative), in two passes of 25 periods (the second 8× finer)."""
    rel = (t - t[len(t) // 2]).astype(np.float64)
    for w in (width, width / 8):
        grid = p * (1 + np.linspace(-w, w, 25))
        z = np.exp(2j * np.pi * rel[None, :] / grid[:, None])
        zh = np.ones_like(z)
        total = np.zeros(len(grid))
        for _ in range(12):  # harmonics 1..12
            zh *= z
            total += np.abs(zh.sum(axis=1)) ** 2
        p = float(grid[int(np.argmax(total))])
    return p


# ----------------------------------------------------------------------------------------------
# Step 2: growing windows, least squares with the phase clusters' offsets removed


def _cut(x: Floats, p: float, q: float) -> float:
    """Where to cut phases ``x`` (in [0, p)) into invocations: the middle of the widest empty
    arc (its emptiest bin when none is empty), in bins of a quarter sample or finer."""
    nb = int(max(16, min(1 << 16, 4 * p // max(q, 1e-9))))
    hist = np.bincount(np.minimum((x / p * nb).astype(np.int64), nb - 1), minlength=nb)
    empty = np.concatenate([hist, hist]) == 0
    if not empty.any():
        return (int(np.argmin(hist)) + 0.5) * p / nb
    # longest run of empty bins on the doubled circle
    edges = np.diff(np.concatenate([[0], empty.astype(np.int8), [0]]))
    starts, stops = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
    k = int(np.argmax(stops - starts))
    return ((starts[k] + stops[k]) / 2 % nb) * p / nb


def _lower_hull(x: Floats, y: Floats) -> list[int]:
    """Indices of the lower convex hull of points (x, y), x increasing (a few hundred points:
    the lowest edge of each stretch)."""
    hull: list[int] = []
    for i in range(len(x)):
        while len(hull) >= 2:
            o, a = hull[-2], hull[-1]
            if (x[a] - x[o]) * (y[i] - y[o]) - (y[a] - y[o]) * (x[i] - x[o]) > 0:
                break
            hull.pop()
        hull.append(i)
    return hull


def _floor_line(k: Ints, r: Floats, labels: Ints, q: float) -> tuple[float, float]:
    """Slope of the floor of residuals ``r`` against invocation ``k``, and how far P could be
    off (ticks): each phase cluster's own floor (:func:`_cluster_floor`; a worst-case pattern
    has two), the most certain ones weighted most."""
    num = den = 0.0
    for c in range(int(labels.max()) + 1):  # a few clusters: gaps of 2 % of the period
        sel = labels == c
        if np.count_nonzero(sel) < 2:
            continue
        slope, err = _cluster_floor(k[sel], r[sel], q)
        if math.isfinite(err) and err > 0:
            num, den = num + slope / err**2, den + 1 / err**2
    if not den:
        return 0.0, math.inf
    return num / den, 1 / math.sqrt(den)


def _cluster_floor(k: Ints, r: Floats, q: float) -> tuple[float, float]:
    """The floor of one phase cluster: the line under every edge with the least mean lateness
    (lateness is never negative, so the true line is under them too), i.e. the edge of the
    lower convex hull over the mean invocation. The hull is taken over the lowest edge of each
    of up to 64 stretches of ``k``; P could be off by twice (a sample + how far the stretches'
    lowest edges stay above the line) over the span."""
    span = int(k[-1] - k[0])
    if span < 2:
        return 0.0, math.inf
    nblocks = int(max(2, min(64, len(k) // 4, span)))
    block = ((k - k[0]) * nblocks // (span + 1)).astype(np.int64)
    first = np.flatnonzero(np.diff(np.concatenate([[-1], block])))
    mins = np.minimum.reduceat(r, first)
    low_at = np.flatnonzero(r == np.repeat(mins, np.diff(np.append(first, len(r)))))
    at = low_at[np.searchsorted(low_at, first)]  # each stretch's lowest edge
    kb, rb = k[at].astype(np.float64), r[at]
    hull = _lower_hull(kb, rb)
    if len(hull) < 2:
        return 0.0, math.inf
    kbar = float(k.mean())
    hx = kb[hull]
    e = int(np.clip(np.searchsorted(hx, kbar) - 1, 0, len(hull) - 2))
    a, b = hull[e], hull[e + 1]
    slope = float((rb[b] - rb[a]) / (kb[b] - kb[a]))
    above = rb - (rb[a] + slope * (kb - kb[a]))
    part = np.array_split(np.arange(len(kb)), min(8, len(kb)))
    spread = max(float(above[p].min()) for p in part if len(p))
    return slope, 2 * (q + spread) / span


def _grow(
    times: Ints, p: float, centre: int, q: float, progress: ProgressCallback, half: float
) -> tuple[float, float]:
    """Refine the period ``p`` over windows growing ×4 from ±``half`` ticks (at least 32
    periods and :data:`GROW_EDGES` edges) about ``times[centre]``; returns (P, its standard
    error), both in ticks."""
    t0 = int(times[centre])
    n = len(times)
    lo, hi = max(0, centre - GROW_EDGES // 2), min(n - 1, centre + GROW_EDGES // 2)
    half = max(half, 32.0 * p, float(times[hi] - t0), float(t0 - times[lo]))
    err = math.inf
    while True:
        i = int(np.searchsorted(times, t0 - half, side="left"))
        j = int(np.searchsorted(times, t0 + half, side="right"))
        rel = (times[i:j] - t0).astype(np.float64)
        cut = _cut(np.mod(rel, p), p, q)
        k = np.floor((rel - cut) / p).astype(np.int64)
        r = rel - cut - k * p
        slope, err_k = _floor_line(k, r, _cluster_labels(r, p, q), q)
        if math.isfinite(err_k) and abs(slope) < 0.01 * p:
            if abs(slope) > err_k:  # a correction beyond what the floor's noise allows
                p += slope
            err = err_k
        progress(j - i, n)
        if i == 0 and j == n:
            return p, err
        half *= 4


def _cluster_labels(r: Floats, p: float, q: float) -> Ints:
    """Label each residual (in [0, p)) with its phase cluster (runs separated by empty arcs of
    at least two samples and a fiftieth of the period)."""
    nb = int(max(16, min(1 << 16, 4 * p // max(q, 1e-9))))
    b = np.minimum((r / p * nb).astype(np.int64), nb - 1)
    occ = np.bincount(b, minlength=nb) > 0
    gap = max(2, int(math.ceil(2 * q / p * nb)), nb // 50)
    idx = np.flatnonzero(occ)
    breaks = np.flatnonzero(np.diff(idx) > gap)
    label = np.zeros(nb, np.int64)
    for_start = idx[breaks + 1] if len(breaks) else np.zeros(0, np.int64)
    label[for_start] = 1
    label = np.cumsum(label)
    if len(breaks) and (idx[0] + nb - idx[-1] - 1) < gap:  # the first run wraps to the last
        label[label == label[idx[-1]]] = 0
    return label[b]


# ----------------------------------------------------------------------------------------------
# Step 3: readings of an exact lattice


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


class _Fold:
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
        self.bins = self.x // self.w
        self.hist = np.bincount(self.bins, minlength=self.nb)
        self.n = len(times)

    def collisions(self) -> Ints:
        """For each anchor bin: pairs of successive edge times in one period."""
        d = np.diff(self.units)
        close = np.flatnonzero(d < self.a)
        cover = np.zeros(2 * self.nb + 2, np.int64)
        if len(close):
            first = self.x[close] // self.w + 1
            last = (self.x[close] + d[close]) // self.w
            np.add.at(cover, first, 1)
            np.add.at(cover, last + 1, -1)
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
        """(invocation, lateness in units) of every edge."""
        k = np.floor_divide(self.units - anchor, self.a)
        return k, self.units - anchor - k * self.a

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


def _kind_dependence(fold: _Fold, kinds: EdgeKinds) -> tuple[int, float] | None:
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
    for offset in (0, fold.a // (2 * nbk)):
        bins = np.mod((fold.x + offset) * nbk // fold.a, nbk)
        hists = {c: np.bincount(bins[((kinds.bits >> c) & 1) == 1], minlength=nbk) for c in present}
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
class _Eval:
    """What a lattice at one exact period says: its fold, the readings kept (one: decided;
    several: the capture cannot tell them apart), or why none is a thread's latency."""

    fold: _Fold
    readings: list[Reading]
    refused: str = ""
    note: str = ""
    slots: Ints = field(default_factory=lambda: np.zeros(0, np.int64))

    @property
    def collisions(self) -> int:
        return min((r.collisions for r in self.readings), default=self.fold.n)


def _evaluate(
    times: Ints,
    period: Fraction,
    res: int,
    kinds: EdgeKinds | None,
    bins: int = 1 << 20,
    judge: bool = True,
) -> _Eval:
    """Read the lattice at ``period`` (exact ticks), its phases in at most ``bins`` bins: see
    step 3 of the module docstring. ``judge`` False skips the test of latency depending on the
    pin (a quick look at a candidate: the chosen period is judged)."""
    fold = _Fold(times, period, res, bins)
    coll = fold.collisions()
    worst = _worst(times, fold, coll, kinds) if kinds is not None else []
    if worst:
        ev = _Eval(fold, worst)
    else:
        dep = _kind_dependence(fold, kinds) if kinds is not None and judge else None
        if dep is None or kinds is None:
            ev = _Eval(fold, _natural(fold, coll))
        else:
            ev = _dependent(fold, kinds, dep)
    if ev.readings:
        ev.slots = fold.lateness(ev.readings[0].anchor)[0]
    return ev


def _allowance(n: int) -> int:
    """Double writes a reading may have beyond the fewest and still count as feasible: a few
    catch-up runs (invocations a period or more late) make them under any reading."""
    return max(2, n // 100)


def _natural(fold: _Fold, coll: Ints) -> list[Reading]:
    """Readings of latency that does not depend on the pin: the feasible anchor (fewest
    collisions) among the cluster starts after wide gaps with the least mean lateness (most
    invocations run almost on time).

    When half the edges or more sit within one sample (a punctual bulk) and the two samples
    before it hold less than a third as many, the start of that bulk is a reading too: if it
    is feasible and its maximum is larger, it comes second (a few edges a sample or two before
    the bulk: late by nearly P, or is the bulk late by a sample or two? The capture cannot
    tell; the larger is the one to plan from)."""
    cands = fold.candidate_bins()
    cands = cands[coll[cands] <= coll[cands].min() + _allowance(fold.n)]
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


def _two_point(fold: _Fold) -> tuple[Ints, Ints]:
    """The starts and widths (units) of the two phase clusters when every edge is within two
    samples of one of two phases (LinuxCNC's worst case: lateness 0 or J), else none."""
    starts, widths = fold.clusters()
    if len(starts) == 2 and bool(np.all(widths <= 2 * fold.q + fold.w)):
        return starts, widths
    return np.zeros(0, np.int64), np.zeros(0, np.int64)


def _worst(times: Ints, fold: _Fold, coll: Ints, kinds: EdgeKinds | None) -> list[Reading]:
    """The readings of a two-point lattice whose on-time edges (its first cluster) are exactly
    a worst-case rule's end events (both when both are: the capture cannot tell J from
    P − J)."""
    kept = []
    starts, widths = _two_point(fold)
    readings = [fold.reading(int(s), coll) for s in starts]
    least = min((r.collisions for r in readings), default=0)
    for r, width in zip(readings, widths, strict=True):
        if r.collisions > least + _allowance(fold.n):
            continue
        _, lat = fold.lateness(r.anchor)
        rule = _rule_of(times, lat < width, kinds)
        if rule:
            kept.append(Reading(r.anchor, r.collisions, r.max_lateness, rule))
    return kept


def _dependent(fold: _Fold, kinds: EdgeKinds, dep: tuple[int, float]) -> _Eval:
    """Lateness that depends on the pin and is no worst case: no thread's latency."""
    if len(_two_point(fold)[0]):
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
    return _Eval(fold, [], refused=why)


def _locked(ev: _Eval, m: int, sample: slice) -> bool:
    """Whether P's edges keep to residues of k mod m as their spacing varies, which a thread
    at P would not (its step rate changes move them), so the thread may be at m·P: 99 % of
    them on one residue, nine in ten with the others single edges between them
    (:func:`_spiked`), or 99 % on two residues each within two samples of one lateness. Judged
    on the edges ``sample`` (a bounded stretch)."""
    slots = ev.slots[sample]
    res = np.mod(slots, m)
    counts = np.bincount(res, minlength=m)
    order = np.argsort(-counts, kind="stable")
    n = len(res)
    main = res == order[0]
    d = np.diff(slots[main])
    if not len(d) or bool(np.all(d == d[0])):
        return False  # a fixed pattern: no evidence either way
    if counts[order[0]] >= 0.99 * n or _spiked(ev, m, sample):
        return True
    if counts[order[:2]].sum() >= 0.99 * n:
        fold = ev.fold
        lat = fold.units[sample] - ev.readings[0].anchor - slots * fold.a
        for r in order[:2]:
            lo, hi = np.percentile(lat[res == r], [0.5, 99.5])
            if hi - lo > 2 * fold.q:
                return False
        return True
    return False


def _spiked(ev: _Eval, m: int, sample: slice) -> bool:
    """Nine edges in ten of ``sample`` on one residue of k mod m, and the others single edges
    between two of them (late invocations of a thread at m·P, not a change of step rate,
    which moves a run of steps)."""
    res = np.mod(ev.slots[sample], m)
    counts = np.bincount(res, minlength=m)
    top = int(np.argmax(counts))
    n = len(res)
    if counts[top] < 0.9 * n or counts[top] == n:
        return False
    main = res == top
    off = np.flatnonzero(~main)
    alone = (off > 0) & (off < n - 1)
    alone[alone] &= main[off[alone] - 1] & main[off[alone] + 1]
    return bool(np.count_nonzero(alone) >= 0.9 * len(off))


def _window_kinds(kinds: EdgeKinds | None, times: Ints, i: int, j: int) -> EdgeKinds | None:
    """``kinds`` of the edges ``times[i:j]`` (the end events within their span)."""
    if kinds is None:
        return None
    lo, hi = times[i], times[j - 1]
    whole = kinds

    def source() -> Signatures:
        return tuple((rule, e[(e >= lo) & (e <= hi)]) for rule, e in whole.signatures)

    return EdgeKinds(kinds.names, kinds.bits[i:j], source)


def _spread(ev: _Eval) -> tuple[float, float] | None:
    """The mean and the largest lateness (ticks) of ``ev``'s first reading, catch-up runs at its
    period left out (three write times within a period: lateness of a period or more, seen
    modulo P); None when it has none or its lattice is no better than chance."""
    if not ev.readings:
        return None
    fold = ev.fold
    lat = fold.lateness(ev.readings[0].anchor)[1]
    span = int(ev.slots.max() - ev.slots.min()) if len(ev.slots) else 1
    _, _, _, chance = _significance(lat, fold.b, fold.q // fold.b, fold.period, span)
    if chance > MAX_LOG10_CHANCE:
        return None
    calm = lat[~_bursts(fold.units, fold.a)]
    if not len(calm):
        return None
    return float(calm.mean()) / fold.b, float(calm.max()) / fold.b


def _alike(a: tuple[float, float], b: tuple[float, float], q: float) -> bool:
    """Two lattices read with the same lateness: mean and maximum within half a sample."""
    return abs(a[0] - b[0]) <= q / 2 and abs(a[1] - b[1]) <= q / 2


def _down(
    times: Ints, coarse: list[float], res: int, kinds: EdgeKinds | None, pmin: float, pmax: float
) -> float | None:
    """The thread among the ``coarse`` periods, their submultiples p/m and the multiples of the
    best of those (m ≤ 8), on a stretch of edges. Among those with no more double writes than
    the fewest: when some read as a worst-case pattern (whose exact structure chance does not
    make), the longest of those (at P/m the pattern repeats with J wrapped); otherwise the one
    with the least mean lateness, the longest among equals (within half a sample): a stepgen
    at its maximum rate uses every second invocation, which a lattice at 2P fits with its other
    edges a period late, and a lattice at P/2 fits P's edges with the same lateness. None: no
    lattice better than chance.
    """
    q = float(max(res, 1))

    def tries(periods: list[float]) -> list[tuple[int, tuple[float, float], float, bool]]:
        out = []
        for p in periods:
            e = _evaluate(times, Fraction(p).limit_denominator(1 << 20), res, kinds, 1 << 14, False)
            spread = _spread(e)
            if spread is not None:
                out.append((e.collisions, spread, p, bool(e.readings[0].rule)))
        return out

    def best(tried: list[tuple[int, tuple[float, float], float, bool]]) -> float:
        fewest = min(t[0] for t in tried)
        ok = [t for t in tried if t[0] <= fewest + _allowance(len(times))]
        if any(t[3] for t in ok):
            return max(t[2] for t in ok if t[3])
        least = min(ok, key=lambda t: t[1][0])[1]
        return max(t[2] for t in ok if _alike(t[1], least, q))

    # each submultiple refined on its own: a lattice at a multiple of the thread's period
    # (its step pattern) does not fit well enough to refine P there
    starts = [p0 / m for p0 in coarse for m in range(1, 9) if m == 1 or p0 / m >= pmin]
    subs: list[float] = []
    for p0 in sorted(starts, reverse=True):
        if all(abs(p0 - s) > 1e-3 * s for s in subs):
            p, err = _grow(times, p0, len(times) // 2, q, no_progress, 0.0)
            subs.append(float(_exact(p, err, times)))
    tried = tries(subs)
    if not tried:
        return None
    p1 = best(tried)
    return best(tried + tries([p1 * m for m in range(2, 9) if p1 * m <= pmax]))


def _reads_as_well(ev: _Eval, big: _Eval, m: int, sample: slice) -> bool:
    """Whether the lattice at m·P (``big``) explains the edges as well as P's (``ev``): no
    more double writes, and the same lateness (:func:`_alike`), or P's off-residue edges single
    spikes, or a worst-case pattern at m·P (the on-time edges a rule's end events) where P's is
    one too or punctual."""
    if not big.readings or big.collisions > ev.collisions:
        return False
    q = max(ev.fold.q // ev.fold.b, 1)
    mine, theirs = _spread(ev), _spread(big)
    if mine is not None and theirs is not None and _alike(theirs, mine, q):
        return True
    if _spiked(ev, m, sample):
        return True
    punctual = ev.readings[0].max_lateness <= 2 * q
    return bool(big.readings[0].rule) and (bool(ev.readings[0].rule) or punctual)


def _up(
    times: Ints, period: Fraction, res: int, kinds: EdgeKinds | None, pmax: float, sample: slice
) -> tuple[_Eval, list[tuple[Fraction, Reading]]]:
    """The thread at ``period`` or a multiple: while one (the least m ≤ 16 first) is
    :func:`_locked` and reads as well (:func:`_reads_as_well`), move up to it."""
    ev = _evaluate(times, period, res, kinds)
    moved = True
    while moved and ev.readings:
        moved = False
        for m in range(2, 17):
            if float(period) * m > pmax:
                break
            if not _locked(ev, m, sample):
                continue
            big = _evaluate(times, period * m, res, kinds)
            if _reads_as_well(ev, big, m, sample):
                ev, period, moved = big, period * m, True
                break
    return ev, []


# ----------------------------------------------------------------------------------------------
# The report


@dataclass(frozen=True)
class LatticeFit:
    """The invocation lattice: ``phase + k·period`` (exact ticks) and how well edges fit it.

    Attributes:
        period: P in exact ticks (a Fraction when not a whole number of ticks).
        phase: lattice point of invocation 0 in exact ticks (the earliest edge has lateness 0).
        given: P was given (``--base-period``/``--ini``), not inferred.
        half_width: how far P could move and still fit (ticks): the exactness of P.
        span_periods: invocations between the first and the last edge.
        arc_fraction: (99th percentile lateness + one sample) / P.
        in_arc: edges within that 99th percentile.
        log10_chance: log10 of the chance that edges not made by a periodic thread fit as well.
        envelope_period: the edges' own least-squares period (ticks; equals ``period`` unless
            given).
        p99: the 99th percentile lateness (ticks).
    """

    period: Fraction
    phase: Fraction
    given: bool
    half_width: Fraction
    span_periods: int
    arc_fraction: float
    in_arc: int
    log10_chance: float
    envelope_period: Fraction
    p99: Fraction = Fraction(0)


@dataclass(frozen=True)
class Spike:
    """A latency spike: edges far later than the rest, close together in time."""

    time_ns: Fraction
    lateness_ns: Fraction
    channels: tuple[str, ...]
    edges: int


@dataclass(frozen=True)
class Candidate:
    """Another reading the capture cannot rule out: its period and worst lateness (ns)."""

    period_ns: Fraction
    max_lateness_ns: Fraction
    how: str


@dataclass(frozen=True)
class CatchUp:
    """Edges of invocations a whole period or more late (two distinct write times in one period,
    which a thread on time or less than a period late cannot make)."""

    edges: int
    first_ns: Fraction
    at_least_ns: Fraction


@dataclass
class LatencyReport:
    """What ``wavecheck latency`` reports. Times in exact ns unless said; arrays in ticks.

    ``lattice`` False means the edges are not on a periodic lattice (``reason`` says why) and the
    lateness figures are absent. ``established`` says whether the worst lateness is known: False
    when a catch-up run shows lateness of a period or more, of which only a lower bound is seen.
    ``candidates`` are other readings that fit as well; the figures are the reading with the
    largest lateness (the one to plan from).
    """

    path: str
    tick_ns: Fraction
    resolution_ns: Fraction
    channels: tuple[str, ...]
    edges_per_channel: dict[str, int]
    n_edges: int
    lattice: bool
    reason: str
    fit: LatticeFit | None = None
    period_ns: Fraction | None = None
    phase_ns: Fraction | None = None
    times: Ints = field(default_factory=lambda: np.zeros(0, np.int64))
    invocation: Ints = field(default_factory=lambda: np.zeros(0, np.int64))
    lateness_num: Ints = field(default_factory=lambda: np.zeros(0, np.int64))
    lateness_den: int = 1
    channel_mask: Ints = field(default_factory=lambda: np.zeros(0, np.int64))
    notes: list[str] = field(default_factory=list)
    candidates: list[Candidate] = field(default_factory=list)
    catch_up: CatchUp | None = None
    rule: str = ""

    @property
    def established(self) -> bool:
        """The worst lateness is known: a lattice, no lateness of a period or more, and at least
        :data:`ESTABLISH_EDGES` edge times."""
        return self.lattice and self.catch_up is None and len(self.lateness_num) >= ESTABLISH_EDGES

    # -- exact figures ----------------------------------------------------------------------
    def lateness_ns_at(self, i: int) -> Fraction:
        """Exact lateness of edge ``i`` (ns)."""
        return Fraction(int(self.lateness_num[i]), self.lateness_den) * self.tick_ns

    @property
    def lateness_ns(self) -> Floats:
        """Lateness of every edge in ns (floats, for plots and histograms)."""
        return self.lateness_num.astype(np.float64) / self.lateness_den * float(self.tick_ns)

    @property
    def max_lateness_ns(self) -> Fraction | None:
        """The worst lateness measured (ns), exact to ± one sample."""
        if not len(self.lateness_num):
            return None
        return self.lateness_ns_at(int(np.argmax(self.lateness_num)))

    @property
    def max_lateness_bound_ns(self) -> Fraction | None:
        """An upper bound of the worst lateness (ns): measured plus one sample (each edge and
        lateness 0 itself are seen up to one sample late), never below the true figure."""
        top = self.max_lateness_ns
        return None if top is None else top + self.resolution_ns

    def percentile_ns(self, q: float) -> Fraction | None:
        """The ``q``-th percentile of lateness (nearest rank, an observed value, exact)."""
        n = len(self.lateness_num)
        if not n:
            return None
        rank = max(1, math.ceil(q / 100 * n))
        value = int(np.partition(self.lateness_num, rank - 1)[rank - 1])
        return Fraction(value, self.lateness_den) * self.tick_ns

    def worst(self) -> tuple[Fraction, tuple[str, ...]] | None:
        """(time in ns, channels with an edge there) of the worst lateness."""
        if not len(self.lateness_num):
            return None
        i = int(np.argmax(self.lateness_num))
        return Fraction(int(self.times[i])) * self.tick_ns, self.channels_at(i)

    def channels_at(self, i: int) -> tuple[str, ...]:
        """Channels with an edge at edge time ``i``."""
        m = int(self.channel_mask[i])
        return tuple(c for j, c in enumerate(self.channels) if m >> j & 1)

    def jitter(self) -> tuple[Fraction | None, int, Fraction | None]:
        """latency-test's Max Jitter (``timedelta``: max(max − P, P − min) of the intervals
        between successive invocations), as far as the edges show it: (the largest |l_{k+1} −
        l_k| over edges in adjacent invocations, how many such pairs, the lateness range, which
        bounds it from above for the invocations that made edges)."""
        if len(self.lateness_num) < 2:
            return None, 0, self.max_lateness_ns
        adj = np.flatnonzero(np.diff(self.invocation) == 1)
        if not len(adj):
            return None, 0, self.max_lateness_ns
        dl = np.abs(self.lateness_num[adj + 1] - self.lateness_num[adj])
        return (
            Fraction(int(dl.max()), self.lateness_den) * self.tick_ns,
            len(adj),
            self.max_lateness_ns,
        )

    def histogram(self, max_bins: int = 60) -> tuple[Fraction, Ints]:
        """Lateness histogram like ``latency-histogram``'s: (bin width ns, counts from 0)."""
        lat = self.lateness_ns
        top = float(lat.max()) if len(lat) else 0.0
        width = _nice_bin(max(top / max_bins, float(self.resolution_ns), 1.0))
        idx = np.floor(lat / float(width)).astype(np.int64)
        return width, np.bincount(idx, minlength=int(idx.max()) + 1 if len(idx) else 1).astype(
            np.int64
        )

    def over_time(self, bins: int = 100) -> tuple[Floats, Floats]:
        """(bin start in s, max lateness in ns) over the capture, for 'every 64 s' spikes."""
        if not len(self.times):
            return np.zeros(0), np.zeros(0)
        t = self.times.astype(np.float64) * float(self.tick_ns) * 1e-9
        lo, hi = float(t[0]), float(t[-1])
        nb = max(1, min(bins, len(t)))
        width = (hi - lo) / nb or 1.0
        idx = np.minimum(((t - lo) / width).astype(np.int64), nb - 1)
        mx = np.full(nb, -np.inf)
        np.maximum.at(mx, idx, self.lateness_ns)
        mx[np.isinf(mx)] = np.nan
        return (lo + np.arange(nb) * width).astype(np.float64), mx

    def spikes(self) -> list[Spike]:
        """Edges far later than the bulk (above the middle between the 99th percentile and the
        maximum, when that is well above both the bulk and the resolution), grouped by time."""
        if len(self.lateness_num) < MIN_EDGES or self.fit is None:
            return []
        p99 = self.percentile_ns(99)
        top = self.max_lateness_ns
        assert p99 is not None and top is not None
        if top <= 2 * p99 or top - p99 <= 4 * max(self.resolution_ns, self.tick_ns):
            return []
        thr_num = (p99 + top) / 2 / self.tick_ns * self.lateness_den
        hits = np.flatnonzero(self.lateness_num >= math.ceil(thr_num))
        # groups: hits more than 16 periods apart start a new spike
        new = np.concatenate([[True], np.diff(self.times[hits]) > 16 * self.fit.period])
        starts = np.flatnonzero(new)
        bounds = np.append(starts, len(hits))
        out: list[Spike] = []
        for lo, hi in zip(bounds[:-1], bounds[1:], strict=True):  # one per spike (few)
            group = hits[lo:hi]
            best = group[int(np.argmax(self.lateness_num[group]))]
            mask = int(np.bitwise_or.reduce(self.channel_mask[group]))
            chans = tuple(c for j, c in enumerate(self.channels) if mask >> j & 1)
            out.append(
                Spike(
                    Fraction(int(self.times[best])) * self.tick_ns,
                    self.lateness_ns_at(int(best)),
                    chans,
                    len(group),
                )
            )
        return out


def _nice_bin(x: float) -> Fraction:
    """The smallest 1-2-5 × 10^n ns width ≥ x."""
    e = math.floor(math.log10(x))
    for m in (1, 2, 5, 10):
        if m * 10**e >= x:
            return Fraction(m) * Fraction(10) ** e
    return Fraction(10) ** (e + 1)  # pragma: no cover


# ----------------------------------------------------------------------------------------------
# The analysis


def _exact(p: float, err: float, times: Ints) -> Fraction:
    """The rational with the smallest denominator within ``err`` ticks of ``p`` (at least a
    millionth of a tick; the nearest of them), its denominator small enough for exact int64
    arithmetic over the capture."""
    half = Fraction(max(err, 1e-6)).limit_denominator(10**9)
    centre = Fraction(p).limit_denominator(10**12)
    lo, hi = max(centre - half, Fraction(1, 10**9)), centre + half
    b = simplest_between(lo, hi).denominator
    exact = Fraction(round(centre * b), b)  # the nearest with that denominator
    if not lo <= exact <= hi:
        exact = simplest_between(lo, hi)
    bmax = max(1, (1 << 60) // max(int(times[-1] - times[0]), 1) // 4)
    return exact if exact.denominator <= bmax else centre.limit_denominator(bmax)


def _significance(
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
    values = union(lat)
    a_units = float(period) * b
    gaps = np.sort(np.diff(np.append(values, values[0] + a_units)))[::-1][:8]
    for k in range(1, len(gaps) + 1):
        f = min(1.0, 1.0 - float(gaps[:k].sum()) / a_units + k * q * b / a_units)
        if 0 < f < 1 and n > k:
            best = min(best, trials + k * math.log10(n) + (n - k) * math.log10(f))
    return p99, in_arc, f99, best


def _catch_up(fold: _Fold, reading: Reading) -> tuple[Ints, Ints, int]:
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


def _limits(tick_ns: Fraction, res_ticks: int) -> tuple[float, float]:
    pmin = max(MIN_PERIOD_NS / float(tick_ns), MIN_PERIOD_SAMPLES * max(res_ticks, 1))
    return pmin, MAX_PERIOD_NS / float(tick_ns)


def _not_lattice(why: str) -> str:
    return f"edges do not lie on a periodic lattice: not a base thread's timing ({why})"


def _infer(
    times: Ints, res: int, kinds: EdgeKinds | None, pmin: float, pmax: float,
    progress: ProgressCallback,
) -> tuple[_Eval | None, list[tuple[Fraction, Reading]], float, str, Fraction]:  # fmt: skip
    """Search, refine and read the lattice: (evaluation, other readings, standard error of P,
    why not when none fits (``{period}``: the period tried), that period in ticks). Catch-up runs (:func:`_bursts`) are left out of the search and read
    with the rest."""
    burst = _bursts(times, pmin)
    if burst.any():
        every, times = times, times[~burst]
        whole, kinds = (
            kinds,
            None if kinds is None else EdgeKinds(kinds.names, kinds.bits[~burst], kinds.source),
        )
    if len(times) < MIN_EDGES:
        return None, [], 0.0, "too few edges outside catch-up runs", Fraction(0)
    coarse = _coarse(times, pmin, pmax)
    if not coarse:
        return None, [], 0.0, "no periodic comb in the edges' timing", Fraction(0)
    i, j = _densest(times, int(64 * WINDOW_EDGES * max(coarse)))
    j = min(j, i + WINDOW_EDGES)
    p1 = _down(times[i:j], coarse, res, _window_kinds(kinds, times, i, j), pmin, pmax)
    if p1 is None:
        return (
            None, [], 0.0, "no lattice near the edges' strongest combs is better than chance",
            Fraction(0),
        )  # fmt: skip
    p, err = _grow(
        times, p1, (i + j) // 2, float(max(res, 1)), progress, float(times[j - 1] - times[i])
    )
    if not pmin <= p <= pmax:
        return (
            None, [], 0.0, "the best period, {period}, is outside the base thread's range",
            Fraction(p).limit_denominator(10**6),
        )  # fmt: skip
    ev, others = _up(times, _exact(p, err, times), res, kinds, pmax, slice(i, j))
    if ev.readings and burst.any():
        ev = _evaluate(every, ev.fold.period, res, whole)
    if ev.readings:
        return ev, others, err, "", ev.fold.period
    return None, [], 0.0, ev.refused, ev.fold.period


def _bursts(times: Ints, pmin: float) -> npt.NDArray[np.bool_]:
    """Edges of catch-up runs: three distinct edge times within the shortest period, which a
    thread less than a period late cannot make (invocations k and k + 2 are more than P apart
    when each is less than P late), but one catching up after a longer delay does."""
    out = np.zeros(len(times), bool)
    if len(times) >= 3:
        at = np.flatnonzero(times[2:] - times[:-2] < pmin)
        out[at] = out[at + 1] = out[at + 2] = True
    return out


def analyse_times(
    times: Ints,
    *,
    tick_ns: Fraction,
    resolution_ns: Fraction,
    channels: tuple[str, ...] = ("edges",),
    channel_mask: Ints | None = None,
    edges_per_channel: dict[str, int] | None = None,
    period_ns: Fraction | None = None,
    path: str = "",
    kinds: EdgeKinds | None = None,
    progress: ProgressCallback = no_progress,
) -> LatencyReport:
    """Infer (or use ``period_ns``) the lattice of edge ``times`` (ticks, sorted, unique).

    ``kinds`` (what changed at each time) lets the readings be decided by the model's facts
    (module docstring, step 3); without it latency is taken not to depend on the pin.
    """
    times = np.asarray(times, dtype=np.int64)
    mask = np.ones(len(times), np.int64) if channel_mask is None else channel_mask
    res_ticks = int(math.ceil(resolution_ns / tick_ns)) if resolution_ns else 0
    report = LatencyReport(
        path=path,
        tick_ns=tick_ns,
        resolution_ns=resolution_ns,
        channels=channels,
        edges_per_channel=edges_per_channel or {channels[0]: len(times)},
        n_edges=len(times),
        lattice=False,
        reason="",
    )
    given = period_ns is not None
    if len(times) < (2 if given else MIN_EDGES):
        report.reason = (
            f"too few edges ({len(times)} distinct edge times; at least "
            f"{2 if given else MIN_EDGES} are needed{'' if given else ' to infer a period'})"
        )
        return report
    pmin, pmax = _limits(tick_ns, res_ticks)
    others: list[tuple[Fraction, Reading]] = []
    if period_ns is not None:
        period = Fraction(period_ns) / tick_ns
        ev = _evaluate(times, period, res_ticks, kinds)
        if not ev.readings:  # the given period decides: read it as natural latency
            ev = _evaluate(times, period, res_ticks, None)
        i, j = _densest(times, int(64 * WINDOW_EDGES * period))
        j = min(j, i + WINDOW_EDGES)
        env, err = _grow(
            times, float(period), (i + j) // 2, float(max(res_ticks, 1)), progress,
            float(times[j - 1] - times[i]) / 8,
        )  # fmt: skip
    else:
        found, others, err, why, p_ticks = _infer(times, res_ticks, kinds, pmin, pmax, progress)
        if found is None:
            report.reason = _not_lattice(why.format(period=format_ns(p_ticks * tick_ns)))
            return report
        ev, env = found, float(found.fold.period)
    return _fill(report, times, mask, ev, others, given, env, err, res_ticks, pmin)


def _fill(
    report: LatencyReport, times: Ints, mask: Ints, ev: _Eval,
    others: list[tuple[Fraction, Reading]], given: bool, env: float, err: float, res: int,
    pmin: float,
) -> LatencyReport:  # fmt: skip
    """The report's figures from the reading with the largest lateness (the one to plan from);
    the others become candidates."""
    fold = ev.fold
    readings = sorted(ev.readings, key=lambda r: -r.max_lateness)
    reading = readings[0]
    tick = report.tick_ns
    k, lat, moved = _catch_up(fold, reading)
    span_p = max(int(k.max() - k.min()), 1)
    q = max(res, 1)
    p99, in_arc, f, _ = _significance(lat, fold.b, q, fold.period, span_p)
    # the evidence for the lattice: the most plausible reading's (the first)
    _, _, _, chance = _significance(
        fold.lateness(ev.readings[0].anchor)[1], fold.b, q, fold.period, span_p
    )
    fit = LatticeFit(
        period=fold.period,
        phase=Fraction(int(times[0])) + Fraction(reading.anchor, fold.b),
        given=given,
        half_width=Fraction(0) if given else Fraction(err).limit_denominator(10**9),
        span_periods=span_p,
        arc_fraction=f,
        in_arc=in_arc,
        log10_chance=chance,
        envelope_period=Fraction(env).limit_denominator(10**9) if given else fold.period,
        p99=Fraction(p99, fold.b),
    )
    report.fit = fit
    report.period_ns = fold.period * tick
    report.phase_ns = fit.phase * tick
    bad = []
    if not given and float(fold.period) < pmin:
        bad.append(
            f"its period would be {float(report.period_ns):.4g} ns, shorter than a base thread runs"
        )
    if chance > MAX_LOG10_CHANCE:
        bad.append(
            f"the fit could be chance (10^{chance:.1f}: {in_arc} edges within {f:.0%} of "
            f"{float(report.period_ns):.6g} ns; more edges are needed when lateness is this "
            "close to a period)"
        )
    collisions = reading.collisions
    if collisions > _allowance(len(times)) + int(np.count_nonzero(_bursts(times, pmin))):
        bad.append(
            f"{collisions} times two distinct edge times fall into one period "
            f"({float(report.period_ns):.6g} ns), which a thread's one write per run cannot make"
        )
    if bad and not given:
        report.reason = _not_lattice("; ".join(bad))
        return report
    if bad:
        report.notes.append(
            "the edges do not fit the given period well: " + "; ".join(bad) + " (lateness below "
            "is measured against it anyway)"
        )
    report.invocation, report.lateness_num, report.lateness_den = k, lat, fold.b
    report.times, report.channel_mask = times, mask
    report.lattice = not bad
    report.rule = reading.rule
    report.reason = "edges lie on a periodic lattice: a software base thread" if not bad else bad[0]
    if moved:
        first = int(times[int(np.argmax(k != fold.lateness(reading.anchor)[0]))])
        report.catch_up = CatchUp(
            moved, Fraction(first) * tick, Fraction(int(lat.max()), fold.b) * tick
        )
        report.notes.append(
            f"{collisions} times two distinct edge times fall into one period (first at "
            f"{first * float(tick) * 1e-9:.9g} s): invocations a whole period or more late, the "
            "thread catching up; lateness that long is seen only as a lower bound "
            f"(at least {float(report.catch_up.at_least_ns):.6g} ns)"
        )
    if reading.rule:
        report.notes.append(
            f"two exact lateness values, the on-time edges being exactly the end events of "
            f"{reading.rule}: LinuxCNC's worst case worst:J:{reading.rule} (or a hardware step "
            "timer with a fixed pulse length, which the wire cannot tell apart)"
        )
    for r in readings[1:]:
        report.candidates.append(
            Candidate(fold.period * tick, r.max_lateness * tick, _how(r, "the same lattice"))
        )
    for period, r in others:
        report.candidates.append(
            Candidate(period * tick, r.max_lateness * tick, _how(r, "another period"))
        )
    if report.candidates:
        report.notes.append(
            "the capture cannot tell these readings apart; the figures are those of the one "
            "with the largest lateness, the one to plan from"
        )
    if given and abs(env - float(fold.period)) * span_p > q + float(fit.p99):
        drift = (env / float(fold.period) - 1) * 1e6
        report.notes.append(
            f"the edges' own period is {env * float(tick):.9g} ns ({drift:+.3g} ppm from the "
            "given one): a different period or the analyzer's clock"
        )
    if len(times) < ESTABLISH_EDGES:
        report.notes.append(
            f"only {len(times)} edge times: lattices at multiples or fractions of P may fit them "
            "as well, and so few invocations say little of the machine's worst latency (not "
            f"established: {ESTABLISH_EDGES} or more are needed)"
        )
    if fold.period.denominator != 1:
        report.notes.append(f"P is not a whole number of samples: {fold.period} samples")
    return report


def _how(r: Reading, where: str) -> str:
    return f"{where}, lateness 0 elsewhere" + (f" (worst case of {r.rule})" if r.rule else "")


def _merge(capture: Capture, names: list[str]) -> tuple[Ints, Ints, Ints, dict[str, int]]:
    """Unique edge times of the named channels, a bitmask of channels at each and of kinds
    (bit 2c: channel c fell, 2c + 1: it rose)."""
    chans = [capture.channel(n) for n in names]
    counts = {n: int(len(c.edges)) for n, c in zip(names, chans, strict=True)}
    if not any(len(c.edges) for c in chans):
        z = np.zeros(0, np.int64)
        return z, z, z, counts
    allt = np.concatenate([c.edges for c in chans])
    bits = np.concatenate([np.full(len(c.edges), 1 << j, np.int64) for j, c in enumerate(chans)])
    kind = np.concatenate(
        [
            np.left_shift(1, 2 * j + (np.arange(len(c.edges)) + 1 + c.initial) % 2)
            for j, c in enumerate(chans)
        ]
    ).astype(np.int64)
    times, inv = np.unique(allt, return_inverse=True)
    mask = np.zeros(len(times), np.int64)
    kinds = np.zeros(len(times), np.int64)
    np.bitwise_or.at(mask, inv, bits)
    np.bitwise_or.at(kinds, inv, kind)
    return times.astype(np.int64), mask, kinds, counts


def common_period(
    times: Ints, tick_ns: Fraction, resolution_ns: Fraction
) -> tuple[Fraction | None, str]:
    """Whether edge ``times`` (ticks, sorted, unique: the steps of several axes) lie on one
    periodic lattice, one timer's or thread's, as cheaply as that can be told: the comb's best
    period (8 harmonics), refined, and the chance of its fit. (P in ns or None, why not.)
    The edges of one timer interrupt may be written one after another, so two write times in a
    period do not refuse it; the period may be the thread's or a multiple or submultiple."""
    res = int(math.ceil(resolution_ns / tick_ns)) if resolution_ns else 0
    if len(times) < MIN_EDGES:
        return None, f"too few steps ({len(times)})"
    pmin, pmax = _limits(tick_ns, res)
    coarse = _coarse(times, pmin, pmax, harmonics=8, keep=1, edges=1024, bins=1 << 16)
    if not coarse:
        return None, "no periodic comb in the steps' timing"
    i, j = _densest(times, int(64 * WINDOW_EDGES * coarse[0]))
    p, err = _grow(times, coarse[0], (i + j) // 2, float(max(res, 1)), no_progress, 0.0)
    if not pmin <= p <= pmax:
        return None, "no base-thread period fits"
    ev = _evaluate(times, _exact(p, err, times), res, None, 1 << 14, False)
    fold = ev.fold
    lat = fold.lateness(ev.readings[0].anchor)[1]
    span = int(ev.slots.max() - ev.slots.min()) if len(ev.slots) else 1
    _, _, f, chance = _significance(lat, fold.b, max(res, 1), fold.period, span)
    if chance > MAX_LOG10_CHANCE:
        return None, f"the best lattice could be chance (10^{chance:.1f})"
    return fold.period * tick_ns, ""


def _signatures(capture: Capture, roles: dict[str, str]) -> Signatures:
    """The end events of every worst-case rule that applies to the mapped roles (both active
    edges, both parities of the every-second rules)."""

    def rise_fall(role: str) -> tuple[Ints, Ints]:
        if role not in roles:
            return np.zeros(0, np.int64), np.zeros(0, np.int64)
        ch = capture.channel(roles[role])
        return ch.edges[ch.initial :: 2], ch.edges[1 - ch.initial :: 2]

    phases = sorted(r for r in roles if r.lower().startswith("phase-"))
    kind: StepKind
    if "step" in roles:
        kind, lines = "step-dir", [rise_fall("step")]
    elif "up" in roles or "down" in roles:
        kind, lines = "up-down", [rise_fall("up"), rise_fall("down")]
    elif phases:
        kind, lines = "phases", [rise_fall(p) for p in phases]
    else:
        return ()
    dirs = capture.channel(roles["dir"]).edges if "dir" in roles else np.zeros(0, np.int64)
    out: list[tuple[str, Ints]] = []
    for rule in WORST_RULES:
        for active in (True, False):
            for parity in (0, 1):
                ends = end_events(rule, kind, lines, dirs, active, parity)
                if (
                    ends is not None
                    and len(ends)
                    and not any(r == rule and np.array_equal(e, ends) for r, e in out)
                ):
                    out.append((rule, ends))
    return tuple(out)


def analyse(
    capture: Capture,
    channels: list[str],
    period_ns: Fraction | None = None,
    roles: dict[str, str] | None = None,
    progress: ProgressCallback = no_progress,
) -> LatencyReport:
    """Lattice and lateness of ``capture``'s named channels (see the module docstring).

    ``roles`` (role → channel, as ``check`` maps them) lets LinuxCNC's worst-case patterns be
    recognised.

    Raises:
        UsageError: no channel named, or a channel that is not in the capture.
    """
    if not channels:
        raise UsageError(
            f"{capture.path}: no channel to read (map the step pins, e.g. --map step=STEP)"
        )
    names = list(dict.fromkeys(capture.channel(c).name for c in channels))
    if len(names) > 30:
        raise UsageError(f"{capture.path}: {len(names)} channels to read; at most 30")
    times, mask, bits, counts = _merge(capture, names)
    named = {r: capture.channel(c).name for r, c in (roles or {}).items()}
    kinds = EdgeKinds(tuple(names), bits, lambda: _signatures(capture, named))
    return analyse_times(
        times,
        tick_ns=capture.timebase.tick_ns,
        resolution_ns=capture.resolution_ns,
        channels=tuple(names),
        channel_mask=mask,
        edges_per_channel=counts,
        period_ns=period_ns,
        path=capture.path,
        kinds=kinds,
        progress=progress,
    )
