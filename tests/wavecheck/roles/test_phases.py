"""Phase groups (:mod:`wavecheck.roles.phases`): found only with evidence of a motor, and the
search bounded by the groups it looks at (work counted, never wall-clock time)."""

from __future__ import annotations

import numpy as np
import pytest

from wavecheck.capture.edges import Capture
from wavecheck.roles import propose
from wavecheck.roles.phases import BUDGET, find_phase_groups

from ..waves import capture

US = 1000


def _quadrature(dwells: list[int], t0: int = 0) -> tuple[list[int], list[int]]:
    """Edges of A and B walking the quadrature table forward with these dwell times."""
    times = t0 + np.cumsum(dwells)
    return times[0::2].tolist(), times[1::2].tolist()


def _lines(kind: str, n: int, seed: int = 1) -> dict[str, tuple[int, list[int]]]:
    """``n`` lines that pairwise change in turns: random bus data on one clock, or square waves
    of two periods at random offsets (any two at one period are a quadrature pair)."""
    rng = np.random.default_rng(seed)
    clock = np.arange(1, 60) * 100 * US
    out = {}
    for i in range(n):
        if kind == "data":
            bits = rng.integers(0, 2, len(clock))
            out[f"n{i}"] = (0, clock[np.flatnonzero(np.diff(np.r_[0, bits]))].tolist())
        else:
            phase = int(rng.integers(0, 4))
            out[f"n{i}"] = (0, (np.arange(phase, 120, 4 + i % 2) * 100 * US + i).tolist())
    return out


@pytest.mark.parametrize("kind", ["data", "waves"])
@pytest.mark.parametrize("n", [55, 100])
def test_search_is_bounded_by_groups_looked_at(kind: str, n: int) -> None:
    """An 8 KB VCD of 55 such lines took 40 s (every clique of 5 lines was tried: 3.5 M of
    them); now the search looks at BUDGET groups at most and says it stopped."""
    cap = capture(_lines(kind, n))
    search = find_phase_groups(cap.channels)
    assert search.looked <= BUDGET
    assert not search.groups  # nothing here reverses, pauses or changes rate
    p = propose(cap)
    assert not p.axes
    if search.cut_short:
        assert any("was not established" in u.why for u in p.unassigned)


def test_a_quadrature_pair_among_bus_lines_is_found_within_the_budget() -> None:
    signals = _lines("data", 60)
    dwells = [400 * US] * 4 + [200 * US] * 40 + [400 * US] * 4  # speeds up, runs, slows down
    a, b = _quadrature(dwells, 50 * US)
    signals |= {"qa": (0, a), "qb": (0, b)}
    search = find_phase_groups(capture(signals).channels)
    assert [{c.name for c in g.channels} for g in search.groups] == [{"qa", "qb"}]
    assert search.looked <= BUDGET


def _quad_capture(dwells: list[int], names: tuple[str, str] = ("a", "b")) -> Capture:
    a, b = _quadrature(dwells, 10 * US)
    return capture({names[0]: (0, a), names[1]: (0, b)})


def test_quadrature_at_one_rate_is_not_established() -> None:
    """A divider's two nets (a Johnson counter) are quadrature at one rate forever: no motor is
    shown by that; the same walk that speeds up and slows down is one."""
    steady = propose(_quad_capture([100 * US] * 64))
    assert not steady.axes and not steady.ambiguous
    assert all("free-running divider" in u.why for u in steady.unassigned)
    ramp = [int(d) * US for d in np.linspace(400, 100, 16)] + [100 * US] * 48
    moving = propose(_quad_capture(ramp + ramp[::-1]))
    assert [(a.kind, a.step_type) for a in moving.axes] == [("phases", 2)]
    named = propose(_quad_capture([100 * US] * 64, ("phase-A", "phase-B")))
    assert [(a.kind, a.step_type) for a in named.axes] == [("phases", 2)]


def test_three_lines_walking_hall_states_need_names() -> None:
    """1,3,2,6,4,5 is LinuxCNC's step type 4 and a BLDC motor's Hall sensor sequence."""
    table = (1, 3, 2, 6, 4, 5)
    dwells = np.r_[np.linspace(400, 100, 12), np.full(60, 100)].astype(np.int64) * US
    times = 10 * US + np.cumsum(dwells)
    states = [table[(k + 1) % 6] for k in range(len(times))]
    lines = {}
    prev = table[0]
    edges: dict[int, list[int]] = {0: [], 1: [], 2: []}
    for t, s in zip(times.tolist(), states, strict=True):
        for bit in range(3):
            if (s ^ prev) >> bit & 1:
                edges[bit].append(t)
        prev = s
    for names in (("h1", "h2", "h3"), ("phase-A", "phase-B", "phase-C")):
        lines = {n: ((table[0] >> k) & 1, edges[k]) for k, n in enumerate(names)}
        p = propose(capture(lines))
        if names[0] == "h1":
            assert not p.axes and all("Hall sensors" in u.why for u in p.unassigned), p.text()
        else:
            assert [(a.kind, a.step_type) for a in p.axes] == [("phases", 4)], p.text()


@pytest.mark.parametrize("names", [("DAV", "NRFD", "NDAC"), ("D0", "D1", "D2")])
def test_a_gpib_handshake_is_no_axis(names: tuple[str, str, str]) -> None:
    """Issue 33: GPIB's DAV, NRFD and NDAC were taken as three axes. Per byte NRFD rises, DAV
    falls, NRFD falls, NDAC rises, DAV rises, NDAC falls: DAV and NDAC walk quadrature one
    cycle a byte, then wait for the next; with or without their names, no axis."""
    rng = np.random.default_rng(5)
    dav: list[int] = []
    nrfd: list[int] = []
    ndac: list[int] = []
    t = 100 * US
    for _ in range(6):  # messages of 8..19 bytes
        for _ in range(int(rng.integers(8, 20))):
            a = int(rng.integers(2, 6)) * US
            nrfd += [t, t + a + US]
            dav += [t + a, t + a + 4 * US]
            ndac += [t + a + 3 * US, t + a + 5 * US]
            t += a + int(rng.integers(8, 30)) * US
        t += 2000 * US
    p = propose(capture({names[0]: (1, dav), names[1]: (0, nrfd), names[2]: (0, ndac)}))
    assert not p.axes and not p.ambiguous, p.text()
