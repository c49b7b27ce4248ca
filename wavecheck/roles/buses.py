"""Lines that contradict a step signal through another line: a bus's clock and data, a gate.

**Clocked data** (:func:`clocked_data`): a line ``d`` is data clocked by ``c`` when, while ``c``
runs, ``d`` changes at most once per period of ``c``, always after the same edge of ``c``
(rising or falling) and at nearly the same delay after it. SPI's MOSI/MISO, I2C's SDA, a parallel
bus's lines and a synchronous serial line do this. Then ``c`` is a bus clock, not a STEP, and
``d`` is no DIR (a DIR changes only where its STEP reverses, never in its steady running). Lines
that merely run at the same time fall anywhere in the period; another axis's STEP driven by the
same step timer changes twice within one period (its rising and falling edge).

**Gate** (:func:`gate`): a line ``e`` gates a busier line ``b`` when every edge of ``b`` falls
while ``e`` is at one level, most stretches of ``e`` at that level hold edges of ``b`` (at least two
of them between two edges of ``e``), and ``e`` stays at the other level far longer than ``b``'s
pulses last. An ENABLE, a chip select, a
latch or a frame line does this; a STEP cannot (its pulses are as short as the other lines').
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from wavecheck.capture.edges import Channel
from wavecheck.record import record

__all__ = [
    "BusFindings",
    "Clocked",
    "Gate",
    "clocked_data",
    "confined",
    "find_buses",
    "gate",
    "strobe",
]

I64 = npt.NDArray[np.int64]

_SAMPLE = 1 << 16  # changes of d looked at (the first ones)
_MIN_CLOCKED = 8  # changes of d inside c's runs needed as evidence (2 once c is a bus clock) …
_SAME_EDGE = 0.9  # … this share of them after the same edge of c …
_DELAY_SPREAD = (16, 0.25, 0.125)  # … p10..p90 of their delays within this share of c's period
#   from this many changes on, else the last share (a few changes need a tighter lock)
_STROBE_IDLE = 3.0  # a strobe falls where the clock's edges are this many periods apart
_GATE_FILLED = 0.5  # share of e's active stretches holding edges of b
_GATE_IDLE = (20.0, 4.0)  # e's idle stretches at least this many times b's pulses (the
#   second figure when b is a gated clock)
_GATE_BUSIER = 2  # b has at least this many times the edges of e
_MOST_LINES = 64  # lines whose pairs are looked at, the busiest
_CYCLE_SLACK = 1.25  # a clock's cycle around a change lasts at most this many periods
_CLOCK_SHARE = 0.02  # clocked changes, as a share of the clock's periods, for a bus clock
_DATA_SHARE = 0.05  # … for data (a synchronous design's STEP changes far more rarely)


def _period(ch: Channel) -> float:
    """Median time from one rising edge of ``ch`` to the next (over its first edges)."""
    rising = ch.edges[: 2 * _SAMPLE][ch.initial :: 2]  # level after edge i: initial ^ (i + 1) & 1
    return float(np.median(np.diff(rising))) if len(rising) > 1 else 0.0


@record(frozen=True)
class Clocked:
    """``d`` changes in step with one edge of the clock ``c``."""

    d: Channel
    c: Channel
    changes: int  # changes of d inside c's runs
    share: float  # … per period of c over the time looked at
    edge: str  # "rising", "falling", or "rising and falling" (changes at the clock's edges)

    def evidence(self) -> str:
        """What was seen, in words (from the clock's side)."""
        return (
            f"{self.d.name!r} changes {self.changes:,} times while it runs, each time at or "
            f"shortly after its {self.edge} edge and at most once a period"
        )


def clocked_data(
    d: Channel, c: Channel, resolution: int = 0, least: int = _MIN_CLOCKED
) -> Clocked | None:
    """The evidence that ``d`` is data clocked by ``c`` (``least`` changes of ``d`` at least),
    or None (``resolution``: the capture's, in ticks)."""
    ce, de = c.edges, d.edges[:_SAMPLE]  # the first changes of d tell enough
    if len(ce) < 2 * least or len(de) < least:
        return None
    period = _period(c)
    if period <= 0:
        return None
    i = np.searchsorted(ce, de, side="right")
    ok = (i >= 2) & (i + 1 < len(ce))
    i = i[ok]
    t = de[ok]
    before, after = ce[i - 1], ce[i]
    # inside a run of the clock: both whole cycles around t last about a period (a line
    # pulsing short with long, varying gaps would else be judged only inside its pulses,
    # where every change lies "just after the rising edge")
    cycles = np.maximum(after - ce[i - 2], ce[i + 1] - before)
    inside = cycles <= _CYCLE_SLACK * period
    if np.count_nonzero(inside) < least:
        return None
    i, t, before = i[inside], t[inside], before[inside]
    level = (c.initial ^ (i & 1)).astype(np.int64)  # c's level after its edge before t
    delay = (t - before).astype(np.float64)
    # sampled at the tick the clock changes, data may seem to change with either edge; it is
    # data, not a copy of the clock, when its new level agrees with the clock's about as often
    # as not (another STEP pulsing with this one rises and falls with it)
    at_edge = delay <= 2 * resolution
    d_level = (d.initial ^ ((np.searchsorted(de, t, side="right")) & 1)).astype(np.int64)
    agree = float(np.mean(d_level[at_edge] == level[at_edge])) if at_edge.any() else 1.0
    choices = (
        ("rising", level == 1),
        ("falling", level == 0),
        ("rising and falling", at_edge if 0.1 <= agree <= 0.9 else at_edge & False),
    )
    for name, same in choices:
        n = int(np.count_nonzero(same))
        if n < _SAME_EDGE * len(t) or n < least:
            continue
        p10, p90 = np.percentile(delay[same], [10, 90])
        many, loose, tight = _DELAY_SPREAD
        if p90 - p10 > (loose if n >= many else tight) * period + 2 * resolution:
            return None
        # at most once a period: no two changes between the same two edges of c
        owners = i[same]
        if np.count_nonzero(owners[1:] == owners[:-1]) > (1 - _SAME_EDGE) * n:
            return None
        spanned = np.searchsorted(ce, de[-1]) - np.searchsorted(ce, de[0])
        return Clocked(d, c, n, n / max(spanned / 2, 1), name)
    return None


def strobe(starts: I64, c: Channel, resolution: int = 0) -> int | None:
    """The median delay in ticks after which pulses starting at ``starts`` follow the last edge
    of a burst of the clock ``c``, or None when they do not: each pulse starts while ``c`` idles
    (its edges before and after are 3 periods apart or more), within 2 periods of its last
    edge, all at nearly the same delay (a latch, load or frame strobe of a bus)."""
    ce = c.edges
    if len(starts) < _MIN_CLOCKED or len(ce) < 2 * _MIN_CLOCKED:
        return None
    period = _period(c)
    if period <= 0:
        return None
    i = np.searchsorted(ce, starts, side="right")
    if np.any(i == 0):
        return None
    before = ce[i - 1]
    after = np.where(i < len(ce), ce[np.minimum(i, len(ce) - 1)], np.iinfo(np.int64).max)
    delay = (starts - before).astype(np.float64)
    idle = (after - before).astype(np.float64) >= _STROBE_IDLE * period
    p10, p50, p90 = np.percentile(delay, [10, 50, 90])
    _, _, tight = _DELAY_SPREAD
    if not idle.all() or p50 > 2 * period or p90 - p10 > tight * period + 2 * resolution:
        return None
    return int(p50)


@record(frozen=True)
class Gate:
    """``e`` gates ``b``: every edge of ``b`` falls while ``e`` is at ``level``."""

    e: Channel
    b: Channel
    level: int
    filled: int  # stretches of e at level holding edges of b
    stretches: int  # stretches of e at level

    def evidence(self) -> str:
        """What was seen, in words (from the gate's side)."""
        lv = "high" if self.level else "low"
        return (
            f"all {len(self.b.edges):,} changes of {self.b.name!r} happen while it is {lv} "
            f"({self.filled:,} of its {self.stretches:,} {lv} stretches hold some), none "
            "while it is the other level: an enable, chip select or frame line"
        )


def confined(e: Channel, b: Channel) -> Gate | None:
    """``b`` changes only while ``e`` is at one level, in at least half of ``e``'s stretches
    at that level and in two of them between edges of ``e`` at least; else None."""
    ee, be = e.edges, b.edges
    if len(ee) == 0 or len(be) < 8 or len(be) < _GATE_BUSIER * len(ee):
        return None
    # stretches of e: k = 0 before its first edge … len(ee) after its last; level alternates;
    # an edge of b at the tick of an edge of e falls after it (one search per edge of e, the
    # sparser line)
    bounds = np.concatenate(([0], np.searchsorted(be, ee, side="left"), [len(be)]))
    held = np.diff(bounds) > 0
    levels = e.initial ^ (np.arange(len(ee) + 1) & 1)
    level = int(levels[np.argmax(held)])  # at b's first edge
    if np.any(held & (levels != level)):
        return None
    active = levels == level
    stretches = int(np.count_nonzero(active))
    filled = int(np.count_nonzero(held & active))
    # opened and closed around b's activity at least twice (a line that changed once or twice
    # with b busy on one side proves nothing)
    closed = int(np.count_nonzero((held & active)[1:-1]))
    if filled < _GATE_FILLED * stretches or closed < 2:
        return None
    return Gate(e, b, level, filled, stretches)


def gate(e: Channel, b: Channel, clock: bool = False) -> Gate | None:
    """The evidence that ``e`` gates ``b`` (:func:`confined`, and ``e`` idles 20 times as long
    as ``b``'s pulses last, 4 times when ``b`` is a gated ``clock``), or None."""
    g = confined(e, b)
    if g is None:
        return None
    # the complete idle stretches (stretch j + 1 lies between ee[j] and ee[j + 1]) are long
    # beside b's pulses (the median time b spends at its shorter level): a STEP's pulses are as
    # short as another STEP's
    ee, be = e.edges, b.edges
    levels = e.initial ^ (np.arange(1, len(ee)) & 1)
    idle = np.diff(ee)[levels != g.level]
    d = np.diff(be)
    pulse = min(float(np.median(d[0::2])), float(np.median(d[1::2]))) if len(d) > 1 else 0.0
    if len(idle) and float(np.median(idle)) < _GATE_IDLE[clock] * pulse:
        return None
    return g


@record
class BusFindings:
    """What the relations between lines rule out, channel index → why in words.

    Attributes:
        clocks: bus clocks (a line clocked by them): never a STEP.
        data: data lines of a bus clock that does not run freely: never a STEP, DIR or ENABLE.
        gates: lines that gate a busier line: never a STEP or DIR (an ENABLE may be one).
        words: what each of those lines is, in a word or two, for the summary of a capture.
    """

    clocks: dict[int, str]
    data: dict[int, str]
    gates: dict[int, str]
    words: dict[int, str]

    def no_step(self, index: int) -> str | None:
        """Why channel ``index`` is no STEP, or None."""
        return self.clocks.get(index) or self.data.get(index) or self.gates.get(index)


def _data(out: BusFindings, d: Channel, k: Clocked) -> None:
    out.data.setdefault(
        d.index,
        f"data of bus clock {k.c.index}={k.c.name!r}: changes in step with its {k.edge} edge, "
        "at most once a period",
    )
    out.words[d.index] = "bus data"


def find_buses(
    chans: list[Channel], resolution: int, clock_like: set[int], starts: dict[int, I64]
) -> BusFindings:
    """Clocked data and gates among ``chans`` (changing lines; ``resolution`` in ticks;
    ``clock_like``: the indices of lines that look like a clock or a gated clock on their own),
    among the 64 busiest lines that change twice or more.

    A line is a bus clock when some line changes in step with it in 2 % of its periods or more,
    and that line is its data when it changes in 5 % or more: every output of a synchronous
    design changes on its clock's edge, its STEP too, but far more rarely. A line that gates a
    bus clock or a clock-like line is a chip select, and every line it gates is of that bus;
    pulses (``starts``: pulse starts by channel index) that follow the bursts of a bus clock at
    one delay are its strobe."""
    out = BusFindings({}, {}, {}, {})
    # pairs of lines that change twice or more; of a dump with thousands of signals, the busiest
    busy = sorted((c for c in chans if len(c.edges) >= 2), key=lambda c: -len(c.edges))
    chans = sorted(busy[:_MOST_LINES], key=lambda c: c.index)
    gated: dict[int, list[Channel]] = {}
    gated_level: dict[tuple[int, int], int] = {}
    chans_by = {c.index: c for c in chans}
    for c in chans:
        for d in chans:
            if d is c:
                continue
            k = clocked_data(d, c, resolution)
            if k is not None and k.share >= _CLOCK_SHARE:
                out.clocks.setdefault(c.index, f"clocks a bus: {k.evidence()}")
                out.words.setdefault(c.index, "bus clock")
                if k.share >= _DATA_SHARE:
                    _data(out, d, k)
            g = gate(c, d, d.index in clock_like)
            if g is not None:
                out.gates.setdefault(c.index, g.evidence())
                out.words.setdefault(c.index, "enable/select")
                gated.setdefault(c.index, []).append(d)
                gated_level[(c.index, d.index)] = g.level
    # once a line is a bus clock, a line of a few changes in step with it is its data as well
    for c in chans:
        if c.index not in out.clocks:
            continue
        for d in chans:
            if d is not c and d.index not in out.data and d.index not in out.clocks:
                k = clocked_data(d, c, resolution, least=2)
                if k is not None and k.share >= _DATA_SHARE:
                    _data(out, d, k)
    for li, st in starts.items():
        for c in chans:
            if c.index == li or c.index not in out.clocks or li in out.clocks:
                continue
            delay = strobe(st, c, resolution)
            if delay is not None:
                out.data.setdefault(
                    li,
                    f"a strobe of bus clock {c.index}={c.name!r}: each pulse starts {delay:,} "
                    "ticks after the last edge of one of its bursts",
                )
                out.words.setdefault(li, "bus strobe")
    # the lines a bus clock's chip select frames are that bus's lines
    for ei, lines in gated.items():
        clock = next((b for b in lines if b.index in out.clocks or b.index in clock_like), None)
        if clock is None:
            continue
        e = chans_by[ei]
        out.words[ei] = "chip select"
        out.clocks.setdefault(
            clock.index, f"a gated clock that {ei}={e.name!r} selects: clocks a bus"
        )
        out.words[clock.index] = "bus clock"
        for b in chans:
            if b.index in (ei, clock.index) or b.index in out.clocks:
                continue
            g = confined(e, b)
            if g is not None and g.level == gated_level[(ei, clock.index)]:
                out.data.setdefault(
                    b.index,
                    f"a line of the bus that {ei}={e.name!r} selects (with clock "
                    f"{clock.index}={clock.name!r}): all its changes happen while it is selected",
                )
                out.words.setdefault(b.index, "bus data")
    return out
