"""The thread's period: comb search, refinement and the choice among multiples and fractions.

:func:`infer` finds P for :mod:`wavecheck.lattice` (see its docstring, steps 1–3): the comb of
the densest stretch (:func:`coarse`), the family of periods it belongs to (:func:`_down`,
:func:`_up`), the exact period refined over growing windows on the floor of the lateness
(:func:`grow`, :func:`exact`). The readings of each candidate come from
:mod:`wavecheck.lattice.reading`.
"""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np

from wavecheck.lattice.reading import (
    MAX_LOG10_CHANCE,
    MIN_EDGES,
    EdgeKinds,
    Evaluation,
    Floats,
    Ints,
    Signatures,
    allowance,
    bursts,
    evaluate,
    significance,
)
from wavecheck.progress import ProgressCallback, no_progress

__all__ = [
    "COMB_EDGES",
    "GROW_EDGES",
    "MAX_PERIOD_NS",
    "MIN_PERIOD_NS",
    "WINDOW_EDGES",
    "coarse",
    "densest",
    "dither",
    "exact",
    "grow",
    "infer",
    "limits",
    "simplest_between",
]

#: Shortest base period considered (ns; latency-histogram refuses a --base below 5 us), and in
#: samples; longest (a single 1 ms thread running make-pulses).
MIN_PERIOD_NS = 5000


MIN_PERIOD_SAMPLES = 8


MAX_PERIOD_NS = 1_000_000


#: Edges the comb search looks at (the densest stretch of the capture).
WINDOW_EDGES = 1 << 14


#: Edges the comb search looks at, and refines its periods on (exact harmonic sums).
COMB_EDGES = 2048


#: Submultiples p/m of a comb's period tried as the thread's: a constant step rate a/b of the
#: thread's repeats every b periods (a cruise at 0.3 of the top rate: 3 steps in 10 periods), and
#: the comb may find that pattern's period.
SUBMULTIPLES = 8


#: Edges each candidate period is read on when choosing among them (the middle of the stretch).
TRY_EDGES = 4096


#: Strongest single spectral lines tried as the thread's period (beside the combs).
LINES = 8


#: Edges of the first window P is refined on: enough that the widest empty arc of their phases
#: is the lattice's even when lateness spans 95 % of the period.
GROW_EDGES = 512


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


def densest(times: Ints, span: int) -> tuple[int, int]:
    """[i, j) of the stretch of at most ``span`` ticks holding the most edges (starting at one
    of 2^16 edges spread evenly over a longer capture)."""
    step = max(1, len(times) >> 16)
    starts = np.arange(0, len(times), step)
    ends = np.searchsorted(times, times[starts] + span, side="left")
    at = int(np.argmax(ends - starts))
    return int(starts[at]), int(ends[at])


def coarse(
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
    return combs_and_lines(times, pmin, pmax, harmonics, keep, edges, bins)[0]


def combs_and_lines(
    times: Ints,
    pmin: float,
    pmax: float,
    harmonics: int = 16,
    keep: int = 3,
    edges: int = COMB_EDGES,
    bins: int = 1 << 20,
    lines: int = 0,
) -> tuple[list[float], list[float]]:
    """:func:`coarse`'s combs, and the periods of up to ``lines`` of the strongest single
    spectral lines (local maxima of the power itself) within the period range, refined: at a
    constant step rate a/b of the thread's the comb finds the step pattern (b periods, or its
    fractions), and the thread's own period is a strong line of it, seldom one of the comb's
    fractions (3/20 of the pattern at 0.3 of the top rate of step/dir)."""
    bw = max(1, int(pmin // (2 * harmonics)))  # bins fine enough for the shortest period's
    i, j = densest(times, bw * bins)
    j = min(j, i + edges)
    w = times[i:j] - times[i]
    if len(w) < MIN_EDGES or w[-1] < 2 * pmin:
        return [], []
    m = 1 << max(10, int(w[-1] // bw + 1).bit_length())
    hist = np.bincount(w // bw, minlength=m).astype(np.float64)
    power = np.abs(np.fft.rfft(hist)) ** 2 / len(w)  # the noise: exponential, mean 1
    length = m * bw  # frequency index f ↔ period length / f
    h_top = harmonics
    flo = max(2, math.ceil(length / pmax))
    fhi = int(min(length / pmin, (len(power) - h_top - 1) / h_top))
    if fhi <= flo:
        return [], []
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
        return [], []
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
    found = [_refine_comb(w, length / g, 0.6 / g) for g in picked[:keep]]
    seg = power[flo : int(min(length / pmin, len(power) - 2)) + 1]  # lines up to pmin
    tops = np.flatnonzero((seg[1:-1] >= seg[:-2]) & (seg[1:-1] >= seg[2:])) + 1
    strong: list[int] = []
    for g in tops[np.argsort(-seg[tops], kind="stable")]:  # a neighbour is the same line
        if len(strong) >= lines:
            break
        if all(abs(int(g) - h) > 2 for h in strong):
            strong.append(int(g))
    return found, [_refine_comb(w, length / (flo + g), 0.6 / (flo + g)) for g in strong]


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


def _cut(x: Floats, p: float, q: float) -> tuple[float, float]:
    """Where to cut phases ``x`` (in [0, p)) into invocations: the middle of the widest empty
    arc (its emptiest bin when none is empty), in bins of a quarter sample or finer; and that
    arc's width (ticks; 0 when none is empty)."""
    nb = int(max(16, min(1 << 16, 4 * p // max(q, 1e-9))))
    hist = np.bincount(np.minimum((x / p * nb).astype(np.int64), nb - 1), minlength=nb)
    empty = np.concatenate([hist, hist]) == 0
    if not empty.any():
        return (int(np.argmin(hist)) + 0.5) * p / nb, 0.0
    # longest run of empty bins on the doubled circle
    edges = np.diff(np.concatenate([[0], empty.astype(np.int8), [0]]))
    starts, stops = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
    k = int(np.argmax(stops - starts))
    width = min(int(stops[k] - starts[k]), nb) * p / nb
    return ((starts[k] + stops[k]) / 2 % nb) * p / nb, width


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


def grow(
    times: Ints, p: float, centre: int, q: float, progress: ProgressCallback, half: float
) -> tuple[float, float]:
    """Refine the period ``p`` over windows growing ×4 from ±``half`` ticks (at least 32
    periods and :data:`GROW_EDGES` edges) about ``times[centre]``, or at once to the whole
    capture when P is known well enough that its error moves the edges of the whole by less
    than an eighth of the empty arc the cut lies in; returns (P, its standard error), both in
    ticks."""
    t0 = int(times[centre])
    n = len(times)
    lo, hi = max(0, centre - GROW_EDGES // 2), min(n - 1, centre + GROW_EDGES // 2)
    half = max(half, 32.0 * p, float(times[hi] - t0), float(t0 - times[lo]))
    err = math.inf
    while True:
        i = int(np.searchsorted(times, t0 - half, side="left"))
        j = int(np.searchsorted(times, t0 + half, side="right"))
        rel = (times[i:j] - t0).astype(np.float64)
        cut, room = _cut(np.mod(rel, p), p, q)
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
        reach = float(max(t0 - times[0], times[-1] - t0))
        half = reach if err * reach / p < room / 8 else half * 4


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


def _locked(ev: Evaluation, m: int, sample: slice) -> bool:
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


def _spiked(ev: Evaluation, m: int, sample: slice) -> bool:
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


def _spread(ev: Evaluation) -> tuple[float, float] | None:
    """The mean and the largest lateness (ticks) of ``ev``'s first reading, catch-up runs at its
    period left out (three write times within a period: lateness of a period or more, seen
    modulo P); None when it has none or its lattice is no better than chance."""
    if not ev.readings:
        return None
    fold = ev.fold
    lat = fold.lateness(ev.readings[0].anchor)[1]
    span = int(ev.slots.max() - ev.slots.min()) if len(ev.slots) else 1
    _, _, _, chance = significance(lat, fold.b, fold.q // fold.b, fold.period, span)
    if chance > MAX_LOG10_CHANCE:
        return None
    calm = lat[~bursts(fold.units, fold.a)]
    if not len(calm):
        return None
    return float(calm.mean()) / fold.b, float(calm.max()) / fold.b


def _alike(a: tuple[float, float], b: tuple[float, float], q: float) -> bool:
    """Two lattices read with the same lateness: mean and maximum within half a sample."""
    return abs(a[0] - b[0]) <= q / 2 and abs(a[1] - b[1]) <= q / 2


#: A candidate period as tried: (double writes, (mean, max) lateness, period in ticks, read as a
#: worst-case pattern).
Tried = tuple[int, tuple[float, float], Fraction, bool]


def _middle(times: Ints, kinds: EdgeKinds | None) -> tuple[Ints, EdgeKinds | None]:
    """The middle :data:`TRY_EDGES` edges of ``times`` (all when fewer) and their ``kinds``."""
    if len(times) <= TRY_EDGES:
        return times, kinds
    i = (len(times) - TRY_EDGES) // 2
    return times[i : i + TRY_EDGES], _window_kinds(kinds, times, i, i + TRY_EDGES)


def _tries(times: Ints, periods: list[Fraction], res: int, kinds: EdgeKinds | None) -> list[Tried]:
    """Each exact period read quickly (:func:`evaluate` of the middle :data:`TRY_EDGES` edges
    on at most 2^14 phase bins, the pin not judged), those better than chance kept."""
    times, kinds = _middle(times, kinds)
    out = []
    bmax = max(1, min(1 << 20, (1 << 60) // max(int(times[-1] - times[0]), 1) // 4))
    for p in periods:
        e = evaluate(times, p.limit_denominator(bmax), res, kinds, 1 << 14, False)
        spread = _spread(e)
        if spread is not None:
            out.append((e.collisions, spread, p, bool(e.readings[0].rule)))
    return out


def _best(tried: list[Tried], n: int, q: float) -> Fraction:
    """Among the tried periods with no more double writes than the fewest (and the allowance):
    when some read as a worst-case pattern (whose exact structure chance does not make), the
    longest of those; otherwise the longest among those with the least mean lateness (within
    half a sample, :func:`_alike`)."""
    fewest = min(t[0] for t in tried)
    ok = [t for t in tried if t[0] <= fewest + allowance(n)]
    if any(t[3] for t in ok):
        return max(t[2] for t in ok if t[3])
    least = min(ok, key=lambda t: t[1][0])[1]
    return max(t[2] for t in ok if _alike(t[1], least, q))


def _down(
    times: Ints, combs: list[float], lines: list[float], res: int, kinds: EdgeKinds | None,
    pmin: float, pmax: float,
) -> Fraction | None:  # fmt: skip
    """The thread among the ``combs``' periods, their submultiples p/m (m ≤
    :data:`SUBMULTIPLES`), the strongest spectral ``lines`` and the multiples of the best of
    those, on a stretch of edges, chosen by :func:`_best`: a stepgen at its maximum rate uses
    every second invocation, which a lattice at 2P fits with its other edges a period late, and
    a lattice at P/2 fits P's edges with the same lateness. None: no lattice better than chance.
    """
    q = float(max(res, 1))
    times, kinds = _middle(times, kinds)  # the edges the candidates are read on
    # each start refined on its own: a lattice at a multiple of the thread's period (its step
    # pattern) does not fit well enough to refine P there
    starts = sorted(
        (p0 / m for p0 in combs for m in range(1, SUBMULTIPLES + 1) if m == 1 or p0 / m >= pmin),
        reverse=True,
    ) + [p0 for p0 in lines if pmin <= p0 <= pmax]  # a line after the combs: it may be a sidelobe
    subs: list[Fraction] = []
    for p0 in starts:
        if all(abs(p0 - float(s)) > 1e-3 * float(s) for s in subs):
            p, err = grow(times, p0, len(times) // 2, q, no_progress, 0.0)
            subs.append(exact(p, err, times, res))
    tried = _tries(times, subs, res, kinds)
    if not tried:
        return None
    p1 = _best(tried, len(times), q)
    more = [p1 * m for m in range(2, 9) if float(p1) * m <= pmax]
    return _best(tried + _tries(times, more, res, kinds), len(times), q)


def _reads_as_well(ev: Evaluation, big: Evaluation, m: int, sample: slice) -> bool:
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
) -> Evaluation:
    """The thread at ``period`` or a multiple: while one (the least m ≤ 16 first) is
    :func:`_locked` and reads as well (:func:`_reads_as_well`), move up to it."""
    ev = evaluate(times, period, res, kinds)
    moved = True
    while moved and ev.readings:
        moved = False
        for m in range(2, 17):
            if float(period) * m > pmax:
                break
            if not _locked(ev, m, sample):
                continue
            big = evaluate(times, period * m, res, kinds)
            if _reads_as_well(ev, big, m, sample):
                ev, period, moved = big, period * m, True
                break
    return ev


def exact(p: float, err: float, times: Ints, sample: int = 1) -> Fraction:
    """The rational number of samples (``sample`` ticks each) with the smallest denominator
    within ``err`` ticks of ``p`` (at least a millionth of a tick; the nearest of them), in
    ticks, its denominator small enough for exact int64 arithmetic over the capture. Simplest
    in samples, not ticks: on a 2 µs sample grid exported with 1 ns ticks, 34 µs is 17 samples,
    where every whole tick within the uncertainty would be as simple. An ``err`` that is not
    finite (the floor of the lateness gave no line to refine on) leaves ``p`` as it is, to that
    denominator."""
    if not math.isfinite(p) or p <= 0:
        raise ValueError(f"a period must be finite and positive, got {p} ticks")
    unit = max(sample, 1)
    bmax = max(1, (1 << 60) // max(int(times[-1] - times[0]), 1) // 4)
    centre = Fraction(p).limit_denominator(10**12)
    if not math.isfinite(err):
        return centre.limit_denominator(bmax)
    centre /= unit
    half = Fraction(max(err, 1e-6)).limit_denominator(10**9) / unit
    lo, hi = max(centre - half, Fraction(1, 10**9)), centre + half
    b = simplest_between(lo, hi).denominator
    exact = Fraction(round(centre * b), b)  # the nearest with that denominator
    if not lo <= exact <= hi:
        exact = simplest_between(lo, hi)
    exact *= unit
    return exact if exact.denominator <= bmax else (centre * unit).limit_denominator(bmax)


def limits(tick_ns: Fraction, res_ticks: int) -> tuple[float, float]:
    pmin = max(MIN_PERIOD_NS / float(tick_ns), MIN_PERIOD_SAMPLES * max(res_ticks, 1))
    return pmin, MAX_PERIOD_NS / float(tick_ns)


def dither(times: Ints, res: int) -> Ints:
    """``times`` each moved later by a fixed pseudo-random part of a sample (``res`` ticks; none
    when a sample is a tick): the comb of a sample grid coarser than the tick is gone, a thread's
    lattice stays (an edge is seen up to a sample late anyway), the order too."""
    if res <= 1:
        return times
    return times + np.random.default_rng(0).integers(0, res, len(times))


def _fractions(times: Ints, period: Fraction, res: int, pmin: float) -> Fraction | None:
    """A fraction k/m (m ≤ 16) of ``period`` that :func:`_best` prefers on the edges ``times``
    (a bounded stretch), else None: a constant step rate a/b of the thread's repeats every b
    periods, and a lattice at a fraction of that pattern fits it too, with more lateness than
    the thread's own period."""
    q = float(max(res, 1))
    family = {period * Fraction(k, m) for m in range(2, 17) for k in range(1, m)}
    periods = [period] + sorted(p for p in family if p >= pmin)
    tried = _tries(times, periods, res, None)
    if not tried or tried[0][2] != period:
        return None
    chosen = _best(tried, min(len(times), TRY_EDGES), q)
    return None if chosen == period else chosen


def infer(
    times: Ints, res: int, kinds: EdgeKinds | None, pmin: float, pmax: float,
    progress: ProgressCallback,
) -> tuple[Evaluation | None, float, str, Fraction]:  # fmt: skip
    """Search, refine and read the lattice: (evaluation, uncertainty of P in ticks,
    why not when none fits (``{period}``: the period tried), that period in ticks). Catch-up
    runs (:func:`~wavecheck.lattice.reading.bursts`) are left out of the search and read
    with the rest."""
    burst = bursts(times, pmin)
    if np.count_nonzero(burst) * 2 > len(times):
        return (
            None, 0.0,
            "most edges come three within the shortest base period ({period}): faster than a "
            "base thread writes", Fraction(pmin).limit_denominator(10**6),
        )  # fmt: skip
    if burst.any():
        every, times = times, times[~burst]
        whole, kinds = (
            kinds,
            None if kinds is None else EdgeKinds(kinds.names, kinds.bits[~burst], kinds.source),
        )
    if len(times) < MIN_EDGES:
        return None, 0.0, "too few edges outside catch-up runs", Fraction(0)
    combs, lines = combs_and_lines(dither(times, res), pmin, pmax, lines=LINES)
    if not combs:
        return None, 0.0, "no periodic comb in the edges' timing", Fraction(0)
    i, j = densest(times, int(64 * WINDOW_EDGES * max(combs)))
    j = min(j, i + WINDOW_EDGES)
    p1 = _down(times[i:j], combs, lines, res, _window_kinds(kinds, times, i, j), pmin, pmax)
    if p1 is None:
        return (
            None, 0.0, "no lattice near the edges' strongest combs is better than chance",
            Fraction(0),
        )  # fmt: skip
    p, err = grow(
        times, float(p1), (i + j) // 2, float(max(res, 1)), progress,
        float(times[j - 1] - times[i]),
    )  # fmt: skip
    if not pmin <= p <= pmax:
        return (
            None, 0.0, "the best period, {period}, is outside the base thread's range",
            Fraction(p).limit_denominator(10**6),
        )  # fmt: skip
    ev = _up(times, exact(p, err, times, res), res, kinds, pmax, slice(i, j))
    if ev.readings and not ev.readings[0].rule:  # a worst-case pattern's structure decides
        frac = _fractions(times[i:j], ev.fold.period, res, pmin)
        if frac is not None:  # refined over the whole capture, as P was
            p, err = grow(times, float(frac), (i + j) // 2, float(max(res, 1)), no_progress, 0.0)
            ev = _up(times, exact(p, err, times, res), res, kinds, pmax, slice(i, j))
    if ev.readings and burst.any():
        ev = evaluate(every, ev.fold.period, res, whole)
    if ev.readings:
        return ev, err, "", ev.fold.period
    return None, 0.0, ev.refused, ev.fold.period
