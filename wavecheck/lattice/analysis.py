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
apart (stepgen/lateness.py). Lateness 0 … P − G is read; lateness of a period or more only where
the wire shows it (two write times in one period: a catch-up run), as a lower bound.

How (all times integer ticks, P exact):

1. Comb search (:func:`~wavecheck.lattice.period.coarse`): the densest stretch of edges is
   binned and Fourier-transformed; a lattice puts power at every harmonic h/P whatever the
   lateness (its spread only lowers the higher ones), so each fundamental is scored by its
   harmonics' summed power, refined on exact harmonic sums.
2. The family (:mod:`wavecheck.lattice.period`): the thread may be the comb's period, a fraction
   of it (a stepgen at its maximum rate uses every second invocation: a lattice at 2P fits, its
   other edges a period late) or a multiple (a lattice at P/m fits P's edges with the same
   lateness while that is below P/m). Taken: the period that reads the edges with the fewest
   double writes and the least lateness, the longest among those reading them alike; a
   worst-case pattern (below) the longest that shows it; a multiple m·P when the edges keep to
   residues of k mod m as their spacing varies, which a thread at P would not.
3. P refined (:func:`~wavecheck.lattice.period.grow`) over windows growing ×4, on the floor of
   each phase cluster's lateness (never negative, many invocations nearly on time), then the
   simplest rational within its uncertainty (a whole number of ticks when it is one; 25 µs
   sampled at 3.3 MHz is 165/2).
4. Where lateness 0 lies (:mod:`wavecheck.lattice.reading`), decided by the model's facts: one
   invocation writes once, so two distinct edge times in one period are impossible (counted for
   every anchor at once); latency does not depend on which pin an invocation changes, so a
   reading in which it does (Kuiper test per channel and direction) is no thread's latency,
   except LinuxCNC's worst case ``worst:J:RULE``: two exact lateness values, the on-time edges
   exactly RULE's end events (:mod:`wavecheck.linuxcnc.worstcase`). Natural latency: the
   feasible anchor with the least mean lateness. When the capture cannot tell two readings
   apart (J or P − J; a few edges a sample before the bulk), both are kept, the larger first:
   plan from it.

"Not a lattice" is a statistical statement: for n edges of which m lie within an arc of a
fraction f of P (or within K arcs of total fraction f), the chance that edges timed by anything
else (a hardware timer, grbl's and Smoothieware's step interrupts) fit as well is bounded
(:func:`~wavecheck.lattice.reading.significance`); the capture is lattice-timed only if that is
below 10⁻⁶, P lies in 5 µs (latency-histogram's shortest --base) … 1 ms and is at least 8
samples, and there are at least :data:`MIN_EDGES` edges; the worst lateness is established from
:data:`ESTABLISH_EDGES`.

Every edge is seen up to one sample late and lateness 0 is itself an edge, so each lateness is
exact to ± one sample; the maximum also comes as an upper bound (measured + one sample) that is
never below the true one.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from fractions import Fraction

import numpy as np

from wavecheck.capture.edges import Capture
from wavecheck.errors import UsageError
from wavecheck.lattice.evidence import MIN_MOTION_SHARE, MIN_PAIRS, motion_share, steady_pulse
from wavecheck.lattice.period import (
    MAX_PERIOD_NS,
    MIN_PERIOD_NS,
    WINDOW_EDGES,
    densest,
    grow,
    infer,
    limits,
    simplest_between,
)
from wavecheck.lattice.reading import (
    MAX_LOG10_CHANCE,
    MIN_EDGES,
    MIN_GAP_FRACTION,
    EdgeKinds,
    Evaluation,
    Floats,
    Ints,
    Reading,
    Signatures,
    allowance,
    ascending,
    bursts,
    catch_up,
    evaluate,
    significance,
    widest_gap,
)
from wavecheck.linuxcnc.worstcase import WORST_RULES, end_events
from wavecheck.progress import ProgressCallback, no_progress
from wavecheck.steptypes import StepKind
from wavecheck.units import format_ns

__all__ = [
    "ESTABLISH_EDGES",
    "MAX_PERIOD_NS",
    "MIN_EDGES",
    "MIN_PERIOD_NS",
    "WINDOW_EDGES",
    "Candidate",
    "CatchUp",
    "EdgeKinds",
    "LatencyReport",
    "LatticeFit",
    "Reading",
    "Spike",
    "analyse",
    "analyse_times",
    "common_period",
    "simplest_between",
]

#: Fewest distinct edge times from which the worst lateness counts as established (fewer show
#: a lattice, but lattices at multiples or fractions of P may fit them as well, and a handful
#: of invocations says little of a machine's worst latency).
ESTABLISH_EDGES = 64


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
    no_motion: str = ""
    _ascending: Ints | None = field(default=None, repr=False)

    @property
    def unestablished(self) -> str:
        """Why the worst lateness is not established ("" when it is): no lattice, lateness of a
        period or more (a lower bound only), fewer than :data:`ESTABLISH_EDGES` edge times,
        readings the capture cannot tell apart, or a lattice not shown to be a step generator's
        thread (:mod:`wavecheck.lattice.evidence`)."""
        if not self.lattice:
            return self.reason
        if self.catch_up is not None:
            return (
                f"invocations a period or more late (at least "
                f"{format_ns(self.catch_up.at_least_ns)}, first at "
                f"{float(self.catch_up.first_ns) * 1e-9:.6g} s): only a lower bound is seen"
            )
        if len(self.lateness_num) < ESTABLISH_EDGES:
            return (
                f"only {len(self.lateness_num)} edge times (at least {ESTABLISH_EDGES} are needed "
                "to establish a worst lateness)"
            )
        if self.candidates:
            figures = [self.max_lateness_ns] + [c.max_lateness_ns for c in self.candidates]
            return (
                f"the capture cannot tell {len(figures)} readings of the lattice apart (worst "
                f"lateness {' or '.join(format_ns(f) for f in figures)})"
            )
        return self.no_motion

    @property
    def established(self) -> bool:
        """The worst lateness is known (:attr:`unestablished` gives no reason against it)."""
        return not self.unestablished

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
        if self._ascending is None or len(self._ascending) != n:  # sorted once
            self._ascending = ascending(self.lateness_num)
        rank = max(1, math.ceil(q / 100 * n))
        return Fraction(int(self._ascending[rank - 1]), self.lateness_den) * self.tick_ns

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
        mx = np.full(nb, np.nan)
        starts = np.flatnonzero(np.diff(idx, prepend=-1))  # idx rises with time: runs
        mx[idx[starts]] = np.maximum.reduceat(self.lateness_ns, starts)
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


def _not_lattice(why: str) -> str:
    return f"edges do not lie on a periodic lattice: not a base thread's timing ({why})"


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
    grid = sample_grid(times, tick_ns, res_ticks)
    if grid:  # the analyzer's sample period, or exact times that all fall on it: the same figures
        res_ticks, resolution_ns = grid, grid * tick_ns
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
    pmin, pmax = limits(tick_ns, res_ticks)  # a lattice of the sample grid is none
    if period_ns is not None:
        period = Fraction(period_ns) / tick_ns
        ev = evaluate(times, period, res_ticks, kinds)
        if not ev.readings:  # the given period decides: read it as natural latency
            ev = evaluate(times, period, res_ticks, None)
        i, j = densest(times, int(64 * WINDOW_EDGES * period))
        j = min(j, i + WINDOW_EDGES)
        env, err = grow(
            times, float(period), (i + j) // 2, float(max(res_ticks, 1)), progress,
            float(times[j - 1] - times[i]) / 8,
        )  # fmt: skip
    else:
        found, err, why, p_ticks = infer(times, res_ticks, kinds, pmin, pmax, progress)
        if found is None:
            report.reason = _not_lattice(why.format(period=format_ns(p_ticks * tick_ns)))
            return report
        ev, env = found, float(found.fold.period)
    if grid:
        report.notes.append(
            f"every edge time is a whole multiple of {format_ns(resolution_ns)} apart: taken as "
            "the analyzer's sample period, which the file does not state (each figure is exact to "
            "± that; a lattice of that grid is the analyzer's, not a thread's)"
        )
    report = _fill(report, times, mask, ev, given, env, err, res_ticks, pmin)
    if report.lattice and not given and kinds is not None:
        pulse = steady_pulse(report.invocation, kinds.bits, len(kinds.names))
        share, pairs = (
            motion_share(report.invocation, kinds.bits, 2 * len(kinds.names))
            if pulse is None
            else (1.0, 0)
        )
        if pulse is None and (share < MIN_MOTION_SHARE or pairs < MIN_PAIRS):
            report.no_motion = (
                f"the lattice is not shown to be a step generator's thread: no line's pulses "
                f"last one whole number of periods, and {share:.0%} of {pairs} successive step "
                f"intervals change gradually, as a motion's do (at least {MIN_MOTION_SHARE:.0%}"
                f" of {MIN_PAIRS} or more are needed); another periodic clock, such as a "
                "sensor's frame clock, makes such edges too"
            )
    return report


def sample_grid(times: Ints, tick_ns: Fraction, res_ticks: int) -> int:
    """The analyzer's sample period (ticks) when the file states none (an export with 1 ns
    times, a VCD without a sample rate) but every edge time is a multiple of it apart, it is
    shorter than any base period, and at least :data:`ESTABLISH_EDGES` edges show it (fewer
    may share a grid by chance); else 0. A 500 kHz analyzer's 2 µs grid exported with 1 ns
    times is such a grid: a lattice commensurate with it is the analyzer's, not a thread's.
    (So is an exact simulation whose P and latency are whole µs: its figures widen by the µs.)"""
    if res_ticks or len(times) < ESTABLISH_EDGES:  # a stated sample period is the analyzer's
        return 0
    g = int(np.gcd.reduce(np.diff(times)))
    return g if g > 1 and g * tick_ns < MIN_PERIOD_NS else 0


def _fill(
    report: LatencyReport, times: Ints, mask: Ints, ev: Evaluation,
    given: bool, env: float, err: float, res: int,
    pmin: float,
) -> LatencyReport:  # fmt: skip
    """The report's figures from the reading with the largest lateness (the one to plan from);
    the others become candidates."""
    fold = ev.fold
    readings = sorted(ev.readings, key=lambda r: -r.max_lateness)
    reading = readings[0]
    tick = report.tick_ns
    k, lat, moved = catch_up(fold, reading)
    span_p = max(int(k.max() - k.min()), 1)
    q = max(res, 1)
    p99, in_arc, f, chance = significance(lat, fold.b, q, fold.period, span_p)
    if ev.readings[0] is not reading or moved:  # the evidence: the most plausible reading's
        _, _, _, chance = significance(
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
    gap, need = widest_gap(lat, fold.a), max(MIN_GAP_FRACTION * fold.a, 2 * q * fold.b)
    if gap < need:
        bad.append(
            f"no empty arc between the edges' phases at {float(report.period_ns):.6g} ns (the "
            f"widest is {gap / fold.a:.1%} of the period, at least {need / fold.a:.1%} is needed): "
            "a thread that is never a period late leaves part of each period without edges"
        )
    collisions = reading.collisions
    if collisions > allowance(len(times)) + int(np.count_nonzero(bursts(times, pmin))):
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
    report.reason = (
        "edges lie on a periodic lattice, as a software base thread's do (so may a sampling clock's)"
        if not bad
        else bad[0]
    )
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
        report.candidates.append(Candidate(fold.period * tick, r.max_lateness * tick, _how(r)))
    if report.candidates:
        report.notes.append(
            "the capture cannot tell these readings apart (so the worst lateness is not "
            "established); the figures are those of the one with the largest lateness"
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


def _how(r: Reading) -> str:
    """How another reading of the same lattice differs."""
    return "lateness 0 elsewhere on the same lattice" + (
        f" (worst case of {r.rule})" if r.rule else ""
    )


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
    order = np.argsort(allt, kind="stable")  # a merge of sorted runs: linear
    allt = allt[order]
    first = np.flatnonzero(np.concatenate([[True], allt[1:] != allt[:-1]]))
    mask = np.bitwise_or.reduceat(bits[order], first)
    kinds = np.bitwise_or.reduceat(kind[order], first)
    return allt[first].astype(np.int64), mask, kinds, counts


def common_period(
    times: Ints, tick_ns: Fraction, resolution_ns: Fraction
) -> tuple[Fraction | None, str]:
    """Whether edge ``times`` (ticks, sorted, unique: the steps of several axes) lie on one
    periodic lattice: the one analysis ``wavecheck latency`` makes (:func:`analyse_times`, its
    evidence rules included), so ``check``'s note and ``latency`` give one answer on the same
    edges. (P in ns or None, why not.)"""
    r = analyse_times(times, tick_ns=tick_ns, resolution_ns=resolution_ns)
    if not r.lattice or r.period_ns is None:
        return None, r.reason
    return r.period_ns, ""


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
