"""Base-thread latency read from the wire: the invocation lattice of a periodic thread.

Software step generation (LinuxCNC's ``stepgen.make-pulses`` in the base thread) changes its
pins only when the thread runs: invocation k is due at k·P and runs l_k ≥ 0 late, so every STEP,
DIR or phase edge it makes lies at ``phase + k·P + l_k``. From the edge times of every mapped
channel this module infers P and the phase, then each edge's lateness.

How P is found (all times integer ticks of the capture):

1. Candidates: the commonest short differences between successive edges (any channel; edges of
   one invocation coincide) and their submultiples. A difference is n·P + (l_j − l_i); each
   candidate is scored by the 99th percentile of |difference − round(difference/P)·P| / P, and
   the best (the largest among equal scores: P/2 fits whatever P fits) is refined by least
   squares on the short differences.
2. Absolute fit over growing windows (×4 each time, so the phase never drifts by more than a
   fraction of P): edges are assigned to invocations by their phase (the start of the dense arc
   of ``t mod P``), and the line k ↦ phase + k·P is the *lower envelope* of the points
   (k, t) that minimises the mean lateness with every lateness ≥ 0 (a linear programme whose
   optimum is the lower convex hull's edge over the mean k: its slope is an exact Fraction).
3. Exact P: the simplest rational within (resolution + lowest-lateness spread) / span of that
   slope, so a period of a whole number of ticks comes out as that integer, and one that is not
   (25 µs sampled at 3.3 MHz = 165/2 samples) as the exact Fraction. The phase is then the
   earliest edge's lattice point: lateness 0 is the earliest edge, all others are later.
4. The thread, not its pattern: a stepgen at its maximum rate uses every second (third…)
   invocation, and those edges fit a lattice at 2P (3P…) more tightly than one at P. A thread
   writes a pin once per run, so a lattice on which a pin changes twice in one invocation is
   replaced by its submultiple with the fewest such double writes (:func:`_finer`).

"Not a lattice" is a statistical statement: under the hypothesis that edges are timed by
something else (a hardware timer, grbl's and Smoothieware's step interrupts, a step generator
chip), the phase of each edge modulo any P is spread over the whole period. With n edges of
which m lie within an arc of a fraction f of P, the chance of that is about
``trials · n · f^(m − 1)`` (trials: the periods one could have tried, span × 10). The capture is
lattice-timed only if that chance is below 10⁻⁶, f ≤ 3/4 (the 99th percentile lateness plus one
sample within three quarters of a period: beyond that lateness cannot be told from the next
invocation), P ≥ 5 µs (latency-histogram's shortest --base) and ≥ 8 samples, and there are at least :data:`MIN_EDGES` edges.

Limits stated in every report: every edge is seen up to one sample period late (T), and the
phase comes from an edge too, so every lateness is exact to ± T. Lateness of P or more (a
latency spike longer than the period, after which LinuxCNC's thread catches up) is seen modulo P.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from fractions import Fraction

import numpy as np
import numpy.typing as npt

from wavecheck.capture.edges import Capture
from wavecheck.errors import UsageError

__all__ = [
    "MAX_ARC_FRACTION",
    "MIN_EDGES",
    "LatencyReport",
    "LatticeFit",
    "Spike",
    "analyse",
    "analyse_times",
    "fit_lattice",
    "infer_period",
    "simplest_between",
]

#: Fewest distinct edge times from which a period is inferred.
MIN_EDGES = 8
#: Largest (99th percentile lateness + one sample) / P a lattice may have.
MAX_ARC_FRACTION = 0.75
#: Largest chance (log10) that hardware-timed edges fit the lattice as well.
MAX_LOG10_CHANCE = -6.0
#: Shortest base period considered (ns), and in samples.
MIN_PERIOD_NS = 5000  # latency-histogram refuses a --base below 5 us
MIN_PERIOD_SAMPLES = 8

Ints = npt.NDArray[np.int64]


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
# Step 1: a coarse period from successive differences


def _candidates(d: Ints, min_p: float) -> list[float]:
    """Commonest short differences (log-binned) and their submultiples ≥ ``min_p``."""
    d = d[d > 0]
    if len(d) == 0:
        return []
    logs = np.log(d.astype(np.float64))
    bins = np.floor(logs / 0.01).astype(np.int64)
    uniq, counts = np.unique(bins, return_counts=True)
    top = uniq[np.argsort(-counts, kind="stable")[:8]]
    values = [float(np.median(d[bins == b])) for b in top]
    # differences of the common differences cancel a repeating lateness pattern: under a
    # worst-case latency the intervals are n·P − J and n·P + J, and their steps are P
    values += [abs(u - v) for i, u in enumerate(values) for v in values[i + 1 :]]
    out: set[float] = set()
    for value in values:
        for m in range(1, 9):
            if value / m >= min_p:
                out.add(value / m)
    return sorted(out)


def _score(d: npt.NDArray[np.float64], p: float) -> float:
    n = np.rint(d / p)
    r = np.abs(d - n * p)
    return float(np.quantile(r, 0.99)) / p


def infer_period(times: Ints, min_period_ticks: float, keep: int = 8) -> list[float]:
    """Coarse base periods (ticks, floats) from successive differences, best first (at most
    ``keep``; each least-squares refined on the short differences)."""
    if len(times) < MIN_EDGES:
        return []
    d = np.diff(times)
    df = d.astype(np.float64)
    scored = []
    for p in _candidates(d, min_period_ticks):
        short = df[df <= 64 * p]
        if len(short) < max(4, len(df) // 20):
            continue
        scored.append((_score(short, p), p))
    if not scored:
        return []
    # P/2 fits whatever P fits: among equal scores the largest period first
    scored.sort(key=lambda sp: (round(sp[0] / 0.02), -sp[1]))
    out: list[float] = []
    for s, p in scored:
        short = df[df <= 64 * p]
        n = np.rint(short / p)
        ok = (n >= 1) & (np.abs(short - n * p) <= max(s, 1e-12) * p + 1e-9)
        if np.count_nonzero(ok) >= 2:  # least squares, unless a lateness pattern biases it
            ls = float(np.sum(n[ok] * short[ok]) / np.sum(n[ok] * n[ok]))
            if _score(df[df <= 64 * ls], ls) <= s:
                p = ls
        if all(abs(p - q) > 1e-3 * q for q in out):
            out.append(p)
        if len(out) >= keep:
            break
    return out


# ----------------------------------------------------------------------------------------------
# Step 2: invocations by phase, lower envelope


def _arc_start(x: npt.NDArray[np.float64], p: float, res: int) -> float:
    """Where lateness 0 most likely is among phases ``x`` in [0, p): the start of the bin from
    which the phases' mean lateness (distance forward, modulo p) is least. A few outliers move
    the mean little, so they never become the start."""
    nb = int(max(4, min(128, p // max(res, 1))))  # bins no finer than a sample
    hist = np.bincount(np.minimum((x / p * nb).astype(np.int64), nb - 1), minlength=nb)
    shifts = (np.arange(nb)[:, None] - np.arange(nb)[None, :]) % nb  # [bin, start]
    cost = (hist[:, None] * shifts).sum(axis=0)
    start = int(np.argmin(cost))
    # the least mean may cut a sparse first bin off the cluster: step back over occupied bins
    # (at most an eighth of the period) so that no on-time edge wraps to a lateness near P
    for _ in range(nb // 8):
        if hist[(start - 1) % nb] == 0:
            break
        start = (start - 1) % nb
    return start * p / nb


def _assign(times: Ints, p: float, anchor: int, res: int) -> tuple[Ints, float]:
    """Invocation index of every edge (floor from the dense arc's start), and that start."""
    rel = (times - anchor).astype(np.float64)
    x = np.mod(rel, p)
    start = _arc_start(x, p, res)
    k = np.floor((rel - start) / p).astype(np.int64)
    return k, anchor + start


def _lower_hull(k: list[int], e: list[int]) -> list[int]:
    """Indices of the lower convex hull of points (k, e), k strictly increasing."""
    hull: list[int] = []
    for i in range(len(k)):
        while len(hull) >= 2:
            o, a = hull[-2], hull[-1]
            cross = (k[a] - k[o]) * (e[i] - e[o]) - (e[a] - e[o]) * (k[i] - k[o])
            if cross > 0:
                break
            hull.pop()
        hull.append(i)
    return hull


def _envelope(k: Ints, e: Ints) -> tuple[Fraction, Fraction, Fraction]:
    """Slope range [lo, hi] of lines below every (k, e) that minimise the mean of e − line(k),
    and the slope chosen (their middle). Needs at least two distinct k."""
    order = np.lexsort((e, k))
    ks, es = k[order], e[order]
    first = np.concatenate([[True], ks[1:] != ks[:-1]])
    ks, es = ks[first], es[first]  # the lowest point of each invocation
    kbar = Fraction(int(k.sum()), len(k))
    # candidate points for the hull: low against a rough line (checked below, grown if needed)
    slope0 = (es[-1] - es[0]) / max(int(ks[-1] - ks[0]), 1)
    resid = es - ks * slope0
    keep = resid <= np.quantile(resid, 0.1) + (np.max(resid) - np.min(resid)) * 0.05
    keep[0] = keep[-1] = True
    for _ in range(8):
        idx = np.flatnonzero(keep)
        kl, el = ks[idx].tolist(), es[idx].tolist()
        hull = [idx[h] for h in _lower_hull(kl, el)]
        hk = [int(ks[h]) for h in hull]
        he = [int(es[h]) for h in hull]
        # the hull edge over kbar (or the vertex at it)
        j = 0
        while j + 1 < len(hk) - 1 and hk[j + 1] < kbar:
            j += 1
        if len(hk) == 1:
            raise UsageError("a lattice needs edges from at least two invocations")
        if hk[j + 1] == kbar and j + 2 < len(hk):
            lo = Fraction(he[j + 1] - he[j], hk[j + 1] - hk[j])
            hi = Fraction(he[j + 2] - he[j + 1], hk[j + 2] - hk[j + 1])
        elif hk[j] == kbar and j > 0:
            lo = Fraction(he[j] - he[j - 1], hk[j] - hk[j - 1])
            hi = Fraction(he[j + 1] - he[j], hk[j + 1] - hk[j])
        else:
            lo = hi = Fraction(he[j + 1] - he[j], hk[j + 1] - hk[j])
        mid = (lo + hi) / 2
        # every point on or above the line through the support point?
        sk, se = (
            hk[j + 1] if hk[j + 1] == kbar else hk[j],
            he[j + 1] if hk[j + 1] == kbar else he[j],
        )
        below = (es - se) * mid.denominator < (ks - sk) * mid.numerator
        if not below.any():
            return lo, hi, mid
        keep |= below
    return lo, hi, mid  # pragma: no cover - converges in one or two rounds


def _refine(times: Ints, p: float) -> float | None:
    """Refine a coarse period: successive differences give whole periods n = round(d / P)
    (right while |l_j − l_i| + n·error < P/2), their running sum the invocation of every edge,
    and the lower envelope of (invocation, time) the period to (lowest-lateness spread) / span.
    Long gaps (n > 16, then 256, 4096, 65536) split the run until the period is good enough to
    count them; each round fits the stretch spanning the most periods."""
    d = np.diff(times).astype(np.float64)
    for n_max in (16, 256, 4096, 65536, 0):
        n = np.rint(d / p).astype(np.int64)
        cut = np.flatnonzero(n > n_max) if n_max else np.zeros(0, np.int64)
        bounds = np.concatenate([[0], cut + 1, [len(times)]])
        best, best_span = (0, 0), -1
        for lo, hi in zip(bounds[:-1], bounds[1:], strict=True):
            span = int(n[lo : hi - 1].sum()) if hi - lo >= 2 else 0
            if span > best_span:
                best, best_span = (int(lo), int(hi)), span
        lo, hi = best
        if best_span < 2:
            continue
        k = np.concatenate([[0], np.cumsum(n[lo : hi - 1])]).astype(np.int64)
        _, _, mid = _envelope(k, times[lo:hi])
        if mid <= 0:
            return None
        p = float(mid)
    return p


# ----------------------------------------------------------------------------------------------
# The fit


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
        envelope_period: the lower envelope's own slope (ticks; equals ``period`` unless given).
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


@dataclass
class LatencyReport:
    """What ``wavecheck latency`` reports. Times in exact ns unless said; ``*_t`` arrays in ticks.

    ``lattice`` False means the edges are not on a periodic lattice (``reason`` says why) and the
    lateness figures are absent.
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

    # -- exact figures ----------------------------------------------------------------------
    def lateness_ns_at(self, i: int) -> Fraction:
        """Exact lateness of edge ``i`` (ns)."""
        return Fraction(int(self.lateness_num[i]), self.lateness_den) * self.tick_ns

    @property
    def lateness_ns(self) -> npt.NDArray[np.float64]:
        """Lateness of every edge in ns (floats, for plots and histograms)."""
        return self.lateness_num.astype(np.float64) / self.lateness_den * float(self.tick_ns)

    @property
    def max_lateness_ns(self) -> Fraction | None:
        """The worst lateness (ns), exact."""
        if not len(self.lateness_num):
            return None
        return self.lateness_ns_at(int(np.argmax(self.lateness_num)))

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

    def over_time(self, bins: int = 100) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
        """(bin start in s, max lateness in ns) over the capture, for 'every 64 s' spikes."""
        if not len(self.times):
            return np.zeros(0), np.zeros(0)
        t = self.times.astype(np.float64) * float(self.tick_ns) * 1e-9
        lo, hi = float(t[0]), float(t[-1])
        nb = max(1, min(bins, len(t)))
        width = (hi - lo) / nb or 1.0
        idx = np.minimum(((t - lo) / width).astype(np.int64), nb - 1)
        mx = np.full(nb, np.nan)
        np.fmax.at(mx, idx, self.lateness_ns)
        return (lo + np.arange(nb) * width).astype(np.float64), mx

    def spikes(self) -> list[Spike]:
        """Edges far later than the bulk (above the middle between the 99th percentile and the
        maximum, when that is well above both the bulk and the resolution), grouped by time."""
        if len(self.lateness_num) < MIN_EDGES or self.fit is None:
            return []
        p99 = self.percentile_ns(99)
        top = self.max_lateness_ns
        assert p99 is not None and top is not None
        res = self.resolution_ns
        if top <= 2 * p99 or top - p99 <= 4 * max(res, self.tick_ns):
            return []
        threshold = (p99 + top) / 2
        thr_num = threshold / self.tick_ns * self.lateness_den
        hits = np.flatnonzero(self.lateness_num >= math.ceil(thr_num))
        gap = 16 * self.fit.period
        out: list[Spike] = []
        start = 0
        for j in range(1, len(hits) + 1):
            if j == len(hits) or self.times[hits[j]] - self.times[hits[j - 1]] > gap:
                group = hits[start:j]
                best = group[int(np.argmax(self.lateness_num[group]))]
                chans = sorted({c for g in group for c in self.channels_at(int(g))})
                out.append(
                    Spike(
                        Fraction(int(self.times[best])) * self.tick_ns,
                        self.lateness_ns_at(int(best)),
                        tuple(chans),
                        len(group),
                    )
                )
                start = j
        return out


def _nice_bin(x: float) -> Fraction:
    """The smallest 1-2-5 × 10^n ns width ≥ x."""
    e = math.floor(math.log10(x))
    for m in (1, 2, 5, 10):
        if m * 10**e >= x:
            return Fraction(m) * Fraction(10) ** e
    return Fraction(10) ** (e + 1)  # pragma: no cover


def fit_lattice(times: Ints, period: float | Fraction, res_ticks: int, given: bool) -> LatticeFit:
    """The exact lattice for edge ``times`` (ticks, sorted, unique) near ``period`` (ticks)."""
    p_float = float(period)
    k, _ = _assign(times, p_float, int(times[0]), res_ticks)
    if given:
        p_exact = Fraction(period)
        env: Fraction = p_exact
        half = Fraction(0)
        if len(np.unique(k)) >= 2:
            _, _, env = _envelope(k, times)
    else:
        lo, hi, env = _envelope(k, times)
        for _ in range(8):  # reassign with the envelope's period until it no longer moves
            k, _ = _assign(times, float(env), int(times[0]), res_ticks)
            lo, hi, moved = _envelope(k, times)
            if moved == env:
                break
            env = moved
        span = max(int(k[-1] - k[0]), 1)
        # how far the lowest edges of eight stretches lie above the envelope: their spread.
        # The true line lies below every edge too, but its own lowest lateness per stretch is
        # unknown (of the same order): it may tilt by that spread about either end, hence 2×
        line = (times - k * env.numerator / env.denominator).astype(np.float64)
        low = 0.0
        for part in np.array_split(np.arange(len(times)), 8):
            if len(part):
                low = max(low, float(line[part].min() - line.min()))
        half = 2 * (Fraction(res_ticks) + Fraction(low).limit_denominator(10**6)) / span
        half = max(half, (hi - lo) / 2)
        bmax = max(1, (1 << 60) // max(int(np.abs(times).max()), 1) // 4)
        p_exact = simplest_between(max(env - half, Fraction(1, 10**9)), env + half)
        if p_exact.denominator > bmax:
            p_exact = env.limit_denominator(bmax)
    a, b = p_exact.numerator, p_exact.denominator
    if b * int(np.abs(times).max()) >= (1 << 62):
        raise UsageError("the capture is too long for an exact lattice at this period")
    # invocation of each edge with the exact period, lateness numerators in 1/b ticks
    k, start = _assign(times, float(p_exact), int(times[0]), res_ticks)
    c0 = int(math.floor(start * b))
    bt = times * b
    k = np.floor_divide(bt - c0, a)
    num = bt - k * a
    c = int(num.min())
    lat = num - c
    n = len(times)
    rank = max(1, math.ceil(0.99 * n))
    p99 = int(np.partition(lat, rank - 1)[rank - 1])
    in_arc = int(np.count_nonzero(lat <= p99))
    f = min(1.0, (p99 / b + res_ticks) / float(p_exact))
    span_p = max(int(k.max() - k.min()), 1)
    trials = math.log10(span_p * 10.0)
    chance = trials + math.log10(n) + (in_arc - 1) * (math.log10(f) if f > 0 else -300.0)
    return LatticeFit(
        period=p_exact,
        phase=Fraction(c, b),
        given=given,
        half_width=half,
        span_periods=span_p,
        arc_fraction=f,
        in_arc=in_arc,
        log10_chance=min(chance, 0.0),
        envelope_period=env,
        p99=Fraction(p99, b),
    )


def _lateness(times: Ints, fit: LatticeFit) -> tuple[Ints, Ints]:
    """(invocation, lateness numerator in 1/b ticks) of every edge under ``fit``."""
    b = fit.period.denominator
    bt = times * b
    c = fit.phase.numerator * (b // fit.phase.denominator)
    k = np.floor_divide(bt - c, fit.period.numerator)
    return k, bt - c - k * fit.period.numerator


def _twice(invocation: Ints, mask: Ints, n_channels: int) -> int:
    """How often one channel has two edges in the same invocation."""
    total = 0
    for j in range(n_channels):
        k = invocation[(mask >> j) & 1 == 1]
        total += int(np.count_nonzero(np.diff(k) == 0))
    return total


def _choose(times: Ints, fits: list[LatticeFit], res_ticks: int) -> LatticeFit:
    """The lattice among ``fits``: the most concentrated one (smallest arc fraction; the largest
    period among equals), unless a multiple m·P (m ≤ 8) also fits and P's lateness clusters sit
    off the multiples of P by more than m·P's on-time edges spread: then the edges are a thread
    at m·P with a lateness pattern (LinuxCNC's worst case: l ∈ {0, J}), not one at P with
    unused invocations. Edges on a thread at P give clusters exactly at multiples of P."""
    # (the multiples are compared at one sample: finer, quantisation alone could explain it)
    best_arc = min(f.arc_fraction for f in fits)
    best = max((f for f in fits if f.arc_fraction <= best_arc + 0.01), key=lambda f: f.period)
    multiples = []
    for m in range(2, 9):
        try:
            multiples.append(fit_lattice(times, best.period * m, res_ticks, False))
        except UsageError:
            continue
    fits = fits + multiples
    best = max((f for f in fits if f.arc_fraction <= best_arc + 0.01), key=lambda f: f.period)
    chosen = best
    for big in sorted(fits, key=lambda f: f.period):
        ratio = big.period / best.period
        m = round(ratio)
        if m < 2 or m > 8 or abs(ratio - m) > Fraction(1, 10**6) * m or big.arc_fraction > 0.5:
            continue
        _, lat = _lateness(times, big)
        b = big.period.denominator
        on_time = lat[lat * 2 < math.ceil(best.period * b)]
        rank = max(1, math.ceil(0.99 * len(on_time)))
        spread0 = Fraction(int(np.partition(on_time, rank - 1)[rank - 1]), b)
        if best.p99 > spread0 + res_ticks:
            chosen = big
    return chosen


def _finer(
    times: Ints, mask: Ints, n_channels: int, fit: LatticeFit, res_ticks: int, min_p: float
) -> LatticeFit:
    """``fit``, or the lattice at one of its submultiples P/m (m ≤ 8) when ``fit`` is only the
    pattern of the invocations a thread at P/m used.

    A thread writes a pin once per run, so a lattice on which a pin changes twice within one
    invocation cannot be the thread's. Concentration alone cannot tell: a stepgen at its
    maximum rate makes edges on every other invocation, and those edges sit on a lattice at
    2P with the same lateness spread over twice the period (so a smaller arc fraction); only
    the few edges off that pattern (while the rate ramps, or a pulse that ends on the next
    invocation) show the thread at P, and on the 2P lattice they make a pin change twice in
    one invocation. So: while ``fit`` has such double writes, take the submultiple that fits
    (arc within :data:`MAX_ARC_FRACTION`) with the fewest of them, the largest among equals
    (a lattice at 3P is not split into halves that cut P's invocations). A true thread at P has none
    unless a run is a whole period late, which P/m then explains as well."""
    for _ in range(8):  # each step divides the period by at least 2
        twice = _twice(_lateness(times, fit)[0], mask, n_channels)
        best: tuple[int, LatticeFit] | None = None
        for m in range(2, 9):
            if not twice or float(fit.period) / m < min_p:
                break
            try:
                sub = fit_lattice(times, fit.period / m, res_ticks, False)
            except UsageError:
                continue
            if sub.arc_fraction > MAX_ARC_FRACTION or abs(sub.period * m / fit.period - 1) > 1e-3:
                continue
            n = _twice(_lateness(times, sub)[0], mask, n_channels)
            if n < twice and (best is None or n < best[0]):
                best = (n, sub)
        if best is None:
            return fit
        fit = best[1]
    return fit


def _merge(capture: Capture, names: list[str]) -> tuple[Ints, Ints, dict[str, int]]:
    """Unique edge times of the named channels and a bitmask of channels at each."""
    arrays = [capture.channel(n).edges for n in names]
    counts = {n: int(len(a)) for n, a in zip(names, arrays, strict=True)}
    if not any(len(a) for a in arrays):
        return np.zeros(0, np.int64), np.zeros(0, np.int64), counts
    allt = np.concatenate(arrays)
    bits = np.concatenate([np.full(len(a), 1 << j, np.int64) for j, a in enumerate(arrays)])
    times, inv = np.unique(allt, return_inverse=True)
    mask = np.zeros(len(times), np.int64)
    np.bitwise_or.at(mask, inv, bits)
    return times.astype(np.int64), mask, counts


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
) -> LatencyReport:
    """Infer (or use ``period_ns``) the lattice of edge ``times`` (ticks, sorted, unique)."""
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
    min_p = max(MIN_PERIOD_NS / float(tick_ns), MIN_PERIOD_SAMPLES * max(res_ticks, 1))
    given = period_ns is not None
    if len(times) < (2 if given else MIN_EDGES):
        report.reason = (
            f"too few edges ({len(times)} distinct edge times; at least "
            f"{2 if given else MIN_EDGES} are needed{'' if given else ' to infer a period'})"
        )
        return report
    period = Fraction(period_ns) / tick_ns if period_ns is not None else Fraction(0)
    if not given:
        fits = []
        for coarse in infer_period(times, min_p):
            refined = _refine(times, coarse)
            if refined is not None:
                try:
                    fits.append(fit_lattice(times, refined, res_ticks, given))
                except UsageError:
                    continue
        if not fits:
            report.reason = _not_lattice("no period fits the edges' spacing")
            return report
        fit = _finer(times, mask, len(channels), _choose(times, fits, res_ticks), res_ticks, min_p)
    if given:
        try:
            fit = fit_lattice(times, period, res_ticks, given)
        except UsageError as err:
            report.reason = str(err)
            return report
    report.fit = fit
    report.period_ns = fit.period * tick_ns
    report.phase_ns = fit.phase * tick_ns
    bad = []
    if not given and float(fit.period) < min_p:
        bad.append(
            f"its period would be {float(fit.period * tick_ns):.4g} ns, shorter than a base thread runs"
        )
    if fit.arc_fraction > MAX_ARC_FRACTION:
        bad.append(
            f"99 % of the edges spread over {fit.arc_fraction:.0%} of the best period "
            f"({float(fit.period * tick_ns):.6g} ns)"
        )
    if fit.log10_chance > MAX_LOG10_CHANCE:
        bad.append(f"the fit could be chance (10^{fit.log10_chance:.1f})")
    invocation, lateness = _lateness(times, fit)
    twice = _twice(invocation, mask, len(channels))
    if twice > max(1, len(times) // 100):
        bad.append(
            f"{twice} times a pin would change twice within one period "
            f"({float(fit.period * tick_ns):.6g} ns), which a thread's one write per run cannot do"
        )
    if bad and not given:
        report.reason = _not_lattice("; ".join(bad))
        return report
    if bad:
        report.notes.append(
            "the edges do not fit the given period well: " + "; ".join(bad) + " (lateness below "
            "is measured against it anyway)"
        )
    report.invocation, report.lateness_num = invocation, lateness
    report.lateness_den = fit.period.denominator
    report.times = times
    report.channel_mask = mask
    report.lattice = not bad
    report.reason = "edges lie on a periodic lattice: a software base thread" if not bad else bad[0]
    drift_ticks = abs(fit.envelope_period - fit.period) * fit.span_periods
    if given and drift_ticks > max(res_ticks, 1) + fit.p99:  # a drift beyond the lateness spread
        drift = float((fit.envelope_period - fit.period) / fit.period) * 1e6
        report.notes.append(
            f"the edges' own lower envelope has a period of {float(fit.envelope_period * tick_ns):.9g} ns "
            f"({drift:+.3g} ppm from the given one): a different period or the analyzer's clock"
        )
    if fit.period.denominator != 1:
        report.notes.append(f"P is not a whole number of samples: {fit.period} samples")
    return report


def _not_lattice(why: str) -> str:
    return (
        "edges do not lie on a periodic lattice: hardware-timed stepping; base-thread latency "
        f"does not apply ({why})"
    )


def analyse(
    capture: Capture, channels: list[str], period_ns: Fraction | None = None
) -> LatencyReport:
    """Lattice and lateness of ``capture``'s named channels (see the module docstring).

    Raises:
        UsageError: no channel named, or a channel that is not in the capture.
    """
    if not channels:
        raise UsageError(
            f"{capture.path}: no channel to read (map the step pins, e.g. --map step=STEP)"
        )
    names = list(dict.fromkeys(capture.channel(c).name for c in channels))
    times, mask, counts = _merge(capture, names)
    return analyse_times(
        times,
        tick_ns=capture.timebase.tick_ns,
        resolution_ns=capture.resolution_ns,
        channels=tuple(names),
        channel_mask=mask,
        edges_per_channel=counts,
        period_ns=period_ns,
        path=capture.path,
    )
