"""Generic measurements: widths, periods, setups, holds — partial intervals never measured."""

from __future__ import annotations

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from wavecheck.steps.primitives import Intervals, holds, periods, setups, sorted_search, widths

A = np.asarray


def test_widths_skip_partial_intervals() -> None:
    edges = A([10, 15, 30, 37, 50], dtype=np.int64)  # initial 0: high 10-15, 30-37, 50-end(partial)
    hi = widths(0, edges, 1)
    assert hi.start.tolist() == [10, 30] and hi.measured.tolist() == [5, 7]
    lo = widths(0, edges, 0)  # 0..10 is partial (capture start); 15-30, 37-50
    assert lo.start.tolist() == [15, 37] and lo.measured.tolist() == [15, 13]
    hi1 = widths(1, edges, 1)  # initially high: 0..10 partial; 15-30; 37-50
    assert hi1.measured.tolist() == [15, 13]


def test_periods() -> None:
    assert periods(A([5, 9, 20], dtype=np.int64)).measured.tolist() == [4, 11]
    assert len(periods(A([5], dtype=np.int64))) == 0


def test_setups_and_holds() -> None:
    act = A([100, 200, 300, 400], dtype=np.int64)
    data = A([50, 150, 200, 420], dtype=np.int64)
    s = setups(data, act)  # 50→100, 150→200, 200→200 (0), 420→none (capture ends)
    assert s.start.tolist() == [50, 150, 200] and s.measured.tolist() == [50, 50, 0]
    h = holds(act, data)  # 50: no step before (capture start), 150←100, 200←200 (0), 420←400
    assert h.start.tolist() == [100, 200, 400] and h.measured.tolist() == [50, 0, 20]


def test_concat_orders_by_start() -> None:
    a = Intervals(A([10, 30], dtype=np.int64), A([11, 31], dtype=np.int64))
    b = Intervals(A([20], dtype=np.int64), A([25], dtype=np.int64))
    c = Intervals.concat([a, b, Intervals.empty()])
    assert c.start.tolist() == [10, 20, 30] and c.measured.tolist() == [1, 5, 1]


@given(
    st.lists(st.integers(0, 10**6), unique=True, min_size=0, max_size=50), st.sampled_from([0, 1])
)
def test_widths_partition_the_edge_gaps(raw: list[int], initial: int) -> None:
    edges = A(sorted(raw), dtype=np.int64)
    hi, lo = widths(initial, edges, 1), widths(initial, edges, 0)
    # high and low stretches between edges are exactly all the gaps between successive edges
    assert sorted(hi.measured.tolist() + lo.measured.tolist()) == sorted(np.diff(edges).tolist())
    assert len(hi) + len(lo) == max(len(edges) - 1, 0)


@given(
    st.lists(st.integers(0, 1000), unique=True, max_size=30),
    st.lists(st.integers(0, 1000), unique=True, max_size=30),
)
def test_setups_holds_match_brute_force(ref_raw: list[int], data_raw: list[int]) -> None:
    ref, data = sorted(ref_raw), sorted(data_raw)
    s = setups(A(data, dtype=np.int64), A(ref, dtype=np.int64))
    want_s = [(d, min(r for r in ref if r >= d)) for d in data if any(r >= d for r in ref)]
    assert list(zip(s.start.tolist(), s.end.tolist(), strict=True)) == want_s
    h = holds(A(ref, dtype=np.int64), A(data, dtype=np.int64))
    want_h = [(max(r for r in ref if r <= d), d) for d in data if any(r <= d for r in ref)]
    assert list(zip(h.start.tolist(), h.end.tolist(), strict=True)) == want_h


_sorted_ticks = st.lists(st.integers(-50, 400), max_size=120).map(sorted)


@given(ref=_sorted_ticks, keys=_sorted_ticks, side=st.sampled_from(["left", "right"]))
def test_sorted_search_is_searchsorted(ref: list[int], keys: list[int], side: str) -> None:
    """Dense events (counted over their span) and sparse or repeated ones (binary search): the
    same indexes as numpy's searchsorted."""
    r, k = A(ref, dtype=np.int64), A(keys, dtype=np.int64)
    want = np.searchsorted(r, k, side=side)
    assert sorted_search(r, k, side).tolist() == want.tolist()
    strict = np.unique(r)  # strictly increasing: the counted path when dense
    want = np.searchsorted(strict, k, side=side)
    assert sorted_search(strict, k, side).tolist() == want.tolist()
