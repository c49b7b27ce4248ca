"""Relations that make a line no STEP (wavecheck.roles.buses): a bus's clock, data and strobe,
a chip select, an ENABLE; and those that must not (another STEP on the same step timer, a
synchronous design's STEP on its clock)."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from wavecheck.capture.edges import Channel
from wavecheck.roles import propose
from wavecheck.roles.buses import clocked_data, confined, find_buses, gate, strobe

from ..waves import capture, move, pulses

RNG = np.random.default_rng(2026)


def _ch(name: str, edges: list[int], initial: int = 0, index: int = 0) -> Channel:
    return Channel(name, index, initial, np.asarray(edges, dtype=np.int64))


def _spi(n_bytes: int = 40) -> tuple[list[int], list[int], list[int], list[int]]:
    """SCK (mode 0, 100 ns period), MOSI changing 5 ns after each falling edge, CS low around
    each byte, a LOAD strobe 30 ns after each byte: edge ticks (ns)."""
    sck, mosi, cs, load = [], [], [], []
    level = 0
    t = 1000
    for _ in range(n_bytes):
        cs.append(t - 100)
        for bit in RNG.integers(0, 2, 8):
            if bit != level:
                mosi.append(t - 45)  # set after the previous falling edge (or before the first)
                level = int(bit)
            sck += [t, t + 50]
            t += 100
        cs.append(t + 50)
        load += [t + 30, t + 60]
        t += 2000
    return sck, mosi, cs, load


def test_spi_lines() -> None:
    sck, mosi, cs, load = _spi()
    c, d = _ch("SCK", sck), _ch("MOSI", mosi)
    k = clocked_data(d, c)
    assert k is not None and k.edge == "falling" and k.changes > 100
    g = gate(_ch("CS", cs, initial=1), c, clock=True)
    assert g is not None and g.level == 0 and g.filled == 40
    assert strobe(np.asarray(load[0::2]), c) == 80  # 30 ns after the last falling edge at +50
    cap = capture({"SCK": (0, sck), "MOSI": (0, mosi), "CS": (1, cs), "LOAD": (0, load)})
    found = find_buses(cap.channels, 0, {0}, {3: np.asarray(load[0::2], dtype=np.int64)})
    assert found.words == {
        0: "bus clock",
        1: "bus data",
        2: "chip select",
        3: "bus strobe",
    }
    p = propose(cap)
    assert not p.axes and p.summary() == (
        "SPI-like bus (clock SCK; data MOSI; chip select CS; strobe LOAD)"
    )


def test_two_steps_on_one_step_timer_are_not_a_bus() -> None:
    """A diagonal move: the Y pulses start and end with X pulses (one step timer): Y follows
    X's rising and falling edges, so it is no data clocked by one edge of X."""
    xs = move(1000, 400, 40_000)
    ys = xs[::2]
    x, y = _ch("X", pulses(xs, 2000)), _ch("Y", pulses(ys, 2000))
    assert clocked_data(y, x) is None and clocked_data(x, y) is None
    cap = capture({"X": (0, pulses(xs, 2000)), "Y": (0, pulses(ys, 2000))})
    assert [a.role("step").channel for a in propose(cap).axes] == ["X", "Y"]


def test_a_synchronous_designs_step_changes_on_its_clock_but_is_no_data() -> None:
    """An FPGA step generator: STEP and DIR change on the rising edge of a 50 MHz clock, but in
    far fewer than 5 % of its periods: data of no bus, and the clock is never a STEP."""
    starts = [(s // 20) * 20 for s in move(10_000, 300, 40_000)]
    clk = list(range(0, starts[-1] + 100_000, 10))
    cap = capture(
        {"c0": (0, clk), "c1": (0, pulses(starts, 2000)), "c2": (0, [starts[150] + 7000])}
    )
    assert clocked_data(cap.channels[1], cap.channels[0]) is not None  # in step with the clock …
    found = find_buses(cap.channels, 0, {0}, {})
    assert 1 not in found.data and 2 not in found.data  # … but no data of it
    p = propose(cap)
    assert p.unambiguous and p.map_args() == "--map step=c1,dir=c2"


def test_enable_gates_the_steps_and_is_never_a_step() -> None:
    """grbl_cnc_3 (issue 26): an ENABLE high around each of 7 like moves, its 7 high stretches
    as alike as a pulse train's: all the steps happen while it is high, so it is their ENABLE,
    no axis of its own."""
    steps: list[int] = []
    en: list[int] = []
    t = 1_000_000
    for _ in range(7):
        starts = move(t + 30_000_000, 300, 400_000)
        steps += starts
        en += [t, starts[-1] + 25_000_000]
        t = starts[-1] + 2_300_000_000
    e, s = _ch("EN", en), _ch("STEP", pulses(steps, 10_000))
    g = gate(e, s)
    assert g is not None and g.level == 1 and g.filled == 7
    p = propose(capture({"EN": (0, en), "STEP (Y axis)": (0, pulses(steps, 10_000))}))
    assert p.map_args() == "--map 'step=STEP (Y axis),enable=EN'"
    # another STEP with few pulses, all in the pauses of a busy one, gates nothing
    z = _ch("Z", pulses([en[1] + 1_000_000 + k * 700_000_000 for k in range(6)], 10_000))
    assert gate(z, s) is None


def _confined_per_edge(e: Channel, b: Channel) -> tuple[int, int, int] | None:
    """:func:`confined` told edge by edge of ``b`` (the level of ``e`` at each): the oracle of
    its one search per edge of ``e``."""
    ee, be = e.edges, b.edges
    if len(ee) == 0 or len(be) < 8 or len(be) < 2 * len(ee):
        return None
    k = np.searchsorted(ee, be, side="right")
    at = e.initial ^ (k & 1)
    if np.any(at != at[0]):
        return None
    held = np.bincount(k, minlength=len(ee) + 1) > 0
    active = (e.initial ^ (np.arange(len(ee) + 1) & 1)) == at[0]
    filled, stretches = int(np.count_nonzero(held & active)), int(np.count_nonzero(active))
    if filled < 0.5 * stretches or np.count_nonzero((held & active)[1:-1]) < 2:
        return None
    return int(at[0]), filled, stretches


@given(
    st.integers(0, 1),
    st.lists(st.integers(0, 400), min_size=1, max_size=12, unique=True),
    st.lists(st.integers(0, 400), min_size=8, max_size=120, unique=True),
    st.integers(0, 1),
    st.sets(st.integers(0, 400), max_size=2),
)
@settings(max_examples=300, deadline=None)
def test_confined_is_the_per_edge_rule(
    initial: int, e_edges: list[int], ticks: list[int], level: int, strays: set[int]
) -> None:
    """A gate's stretches are counted with one search per edge of the gate (not per edge of the
    busy line); edges at the same tick included, the answer is the per-edge one. The busy line
    changes while the gate is at ``level`` (and at a few ``strays``), so gates are found too."""
    e = Channel(name="e", index=0, initial=initial, edges=np.array(sorted(e_edges), np.int64))
    at = initial ^ (np.searchsorted(e.edges, np.array(ticks, np.int64), side="right") & 1)
    kept = sorted({t for t, lv in zip(ticks, at, strict=True) if lv == level} | strays)
    b = Channel(name="b", index=1, initial=0, edges=np.array(kept, np.int64))
    g = confined(e, b)
    assert (None if g is None else (g.level, g.filled, g.stretches)) == _confined_per_edge(e, b)
