"""Violation regions (:mod:`wavecheck.sigrok.regions`): runs of violations merged and widened so
that a whole-capture view shows each as a box of its own (issue 36)."""

from __future__ import annotations

from itertools import pairwise

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from wavecheck.sigrok.regions import GAP_SHARE, WIDTH_SHARE, regions

END = 1_000_000  # gap 2500 samples, narrowest region 10000


@pytest.mark.parametrize(
    "spans, want",
    [
        # a lone violation: widened about its middle to input / WIDTH_SHARE
        ([(500_000, 500_009, "dir_hold")], [(495_004, 505_004, {"dir_hold": 1})]),
        # near the end: widened within the input
        ([(999_990, 999_999, "dir_hold")], [(990_000, 1_000_000, {"dir_hold": 1})]),
        # closer than the gap: one region, its counts per rule
        ([(100_000, 100_010, "step_high"), (102_000, 102_010, "step_low"),
          (104_000, 104_010, "step_high")], [(97_005, 107_005, {"step_high": 2, "step_low": 1})]),
        # further apart than the gap and the width: two regions
        ([(100_000, 120_000, "a"), (200_000, 220_000, "b")],
         [(100_000, 120_000, {"a": 1}), (200_000, 220_000, {"b": 1})]),
        # apart by more than the gap, but widening joins them
        ([(100_000, 100_001, "a"), (104_000, 104_001, "a")], [(95_000, 109_000, {"a": 2})]),
    ],
)  # fmt: skip
def test_regions(spans: list[tuple[int, int, str]], want: list[tuple[int, int, dict]]) -> None:  # type: ignore[type-arg]
    starts, ends, rules = zip(*spans, strict=True)
    got = regions(starts, ends, rules, 0, END)
    assert [(r.start, r.end, r.counts) for r in got] == want


def test_texts() -> None:
    (one,) = regions([10], [19], ["dir_hold"], 0, 1000)
    assert one.texts() == ["1 violation: dir_hold ×1", "dir_hold ×1", "1", "!"]
    (two,) = regions([10, 20], [12, 22], ["b", "a"], 0, 1000)
    assert two.texts()[0] == "2 violations: a ×1, b ×1"


@given(st.lists(st.tuples(st.integers(0, END - 1), st.integers(0, 5000)), min_size=1, max_size=60))
def test_every_violation_in_exactly_one_region(spans: list[tuple[int, int]]) -> None:
    """Every violation lies in one region; regions are apart by more than the gap, at least the
    narrowest width (or the input), within the input; the counts add up."""
    starts = [s for s, _ in spans]
    ends = [min(END, s + w) for s, w in spans]
    got = regions(starts, ends, ["r"] * len(spans), 0, END)
    assert sum(r.counts["r"] for r in got) == len(spans)
    for s, e in zip(starts, ends, strict=True):
        assert sum(r.start <= s and e <= r.end for r in got) == 1
    gaps = np.array([b.start - a.end for a, b in pairwise(got)])
    assert (gaps > END // GAP_SHARE).all()
    assert all(0 <= r.start and r.end <= END and r.end - r.start >= END // WIDTH_SHARE for r in got)
