"""Exact verdicts: pass ⟺ W − T ≥ limit (first), fail ⟺ W + T ≤ limit, else indeterminate."""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from tests.engine_probe import FullRule
from wavecheck.engine.judge import FAIL, INDETERMINATE, PASS, Histogram, evaluate
from wavecheck.engine.results import RuleResult
from wavecheck.steps.primitives import Intervals
from wavecheck.timebase import Timebase


def _ev(measured_ticks: list[int], limit_ns, tick_ns=1, res_ns=0) -> FullRule:
    """The intervals judged (:func:`evaluate`) and merged into the rule's result, as the engine
    does with one window."""
    start = np.arange(len(measured_ticks), dtype=np.int64) * 10**6
    iv = Intervals(start, start + np.asarray(measured_ticks, dtype=np.int64))
    tb = Timebase(Fraction(tick_ns) / 10**9)
    result = RuleResult("step_high", Fraction(limit_ns), None, tb, Fraction(res_ns))
    result.add(evaluate("step_high", iv, Fraction(limit_ns), tb, Fraction(res_ns)), start[:0])
    return FullRule(result, iv)


def test_exactly_at_the_minimum_passes_one_tick_shorter_fails() -> None:
    r = _ev([4500, 4499, 4501], 4500)
    assert r.outcome.tolist() == [PASS, FAIL, PASS]
    assert r.violations == 1 and r.verdict == "fail"
    assert r.min_margin_ns == -1 and r.min_margin_at_tick == 10**6


def test_limit_not_a_whole_number_of_ticks() -> None:
    # 12 MHz: tick = 250/3 ns. Limit 4.5 us = 54 ticks exactly; 1 us = 12 ticks; 200 ns = 2.4 ticks
    r = _ev([2, 3], 200, tick_ns=Fraction(250, 3))
    assert r.outcome.tolist() == [FAIL, PASS]  # 166.67 ns < 200 ns ≤ 250 ns
    r = _ev([54, 53], 4500, tick_ns=Fraction(250, 3))
    assert r.outcome.tolist() == [PASS, FAIL]
    assert r.min_margin_ns == Fraction(250, 3) * 53 - 4500


def test_resolution_turns_near_boundary_indeterminate() -> None:
    # T = 500 ns: pass needs W ≥ limit + 500, fail needs W ≤ limit − 500
    r = _ev([5000, 4999, 4500, 4001, 4000], 4500, res_ns=500)
    assert r.outcome.tolist() == [PASS, INDETERMINATE, INDETERMINATE, INDETERMINATE, FAIL]
    assert r.verdict == "fail" and r.indeterminate == 3
    r = _ev([5000, 4999], 4500, res_ns=500)
    assert r.verdict == "indeterminate"
    # closest undecided: 4999 is 499 ns from the limit → T' < 249.5 ns → > 4.008 MHz
    assert r.decide_samplerate_hz == Fraction(2 * 10**9, 499)


def test_measured_equal_to_limit_with_resolution_cannot_be_decided() -> None:
    r = _ev([4500], 4500, res_ns=1)
    assert r.verdict == "indeterminate" and r.decide_samplerate_hz is None


def test_unchecked_when_no_interval() -> None:
    r = _ev([], 4500)
    assert r.verdict == "unchecked" and r.checked == 0
    assert r.min_margin_ns is None and r.min_margin_at_s is None


def test_worst_violations_first() -> None:
    r = _ev([100, 50, 4600, 70, 50], 4500)
    worst = r.worst_violations(3)
    assert [v.measured_ns for v in worst] == [50, 50, 70]
    assert [v.start_tick for v in worst] == [10**6, 4 * 10**6, 3 * 10**6]
    assert worst[0].margin_ns == -4450 and worst[0].time_s == Fraction(1, 1000)
    assert len(r.worst_violations(10)) == 4


@given(
    w=st.lists(st.integers(0, 20000), max_size=40),
    limit=st.fractions(min_value=0, max_value=20000, max_denominator=7),
    tick=st.sampled_from([Fraction(1), Fraction(250, 3), Fraction(500), Fraction(41, 3)]),
    res_ticks=st.integers(0, 3),
)
def test_verdicts_match_exact_rational_definition(w, limit, tick, res_ticks) -> None:
    res = tick * res_ticks
    r = _ev(w, limit, tick_ns=tick, res_ns=res)
    for wi, got in zip(w, r.outcome.tolist(), strict=True):
        x = wi * tick
        want = PASS if x - res >= limit else FAIL if x + res <= limit else INDETERMINATE
        assert got == want


@pytest.mark.parametrize("res", [0, 1])
def test_zero_limit(res: int) -> None:
    r = _ev([0, 1], 0, res_ns=res)
    assert r.outcome.tolist() == ([PASS, PASS] if res == 0 else [INDETERMINATE, PASS])


@given(
    w=st.lists(st.integers(0, 6), min_size=1, max_size=60),
    n=st.integers(1, 70),
)
def test_worst_n_is_a_prefix_of_the_full_order(w: list[int], n: int) -> None:
    """Capping the list never changes which violations come first: worst margin, ties in time
    order (many equal intervals, as a real capture at one sample rate has)."""
    r = _ev(w, 7)
    everything = [(v.measured_ns, v.start_tick) for v in r.worst_violations(len(w))]
    assert everything == sorted(everything)
    assert [(v.measured_ns, v.start_tick) for v in r.worst_violations(n)] == everything[:n]


def _bin(w: int) -> int:
    """The definition: bin 0 for w ≤ 0, else 4·(e − 1) + q + 1, 2^(e−1) ≤ w < 2^e, q the quarter."""
    if w <= 0:
        return 0
    e = w.bit_length()
    return 4 * (e - 1) + (4 * (w - 2 ** (e - 1))) // 2 ** (e - 1) + 1


@given(
    w=st.lists(st.integers(-3, 2**53 - 1), max_size=30)
    | st.lists(st.integers(-3, 300), max_size=30)
    | st.builds(
        lambda base, d: [base + x for x in d],
        st.integers(0, 2**52),
        st.lists(st.integers(0, 70000), max_size=30),
    )
)
def test_histogram_bins_match_the_definition(w: list[int]) -> None:
    """Both ways of counting (each length when they span few ticks, else by bin) give the
    definition's bins and counts."""
    a = np.array(w, dtype=np.int64)
    assert Histogram.bins(a).tolist() == [_bin(x) for x in w]
    counts: dict[int, int] = {}
    for x in w:
        counts[_bin(x)] = counts.get(_bin(x), 0) + 1
    assert Histogram.of(a).counts == tuple(sorted(counts.items()))
