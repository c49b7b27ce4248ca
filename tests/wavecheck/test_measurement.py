"""``wavecheck.measurement``: the figures a scope user reads off, from check's own interval builder."""

from __future__ import annotations

from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from tests.conftest import write_vcd
from tests.engine_probe import run_check
from wavecheck.capture.open import open_capture
from wavecheck.drives.library import load_drive
from wavecheck.drives.overrides import tune_drive
from wavecheck.engine.options import CheckOptions
from wavecheck.engine.trace import StepTrace
from wavecheck.measurement import IntervalCounts, _exact_sum, measure
from wavecheck.rules import TIME_RULES, rule
from wavecheck.steps.mapping import AxisMap
from wavecheck.steps.primitives import Intervals
from wavecheck.timebase import Timebase

REPO = Path(__file__).resolve().parents[2]
GOLDEN = REPO / "captures" / "golden"
NS = Timebase(Fraction(1, 10**9))

#: golden trace → (step type, user table): the types they were simulated with (their .toml).
GOLDEN_TYPES = {
    "a4988-spike": (0, None),
    "g202-p16-dirhold2-worst": (0, None),
    "g202-p20-worst-dirhold": (0, None),
    "stepgen0": (0, None),
    "xylotex-dirsetup-zero": (0, None),
    "updown-uniform": (1, None),
    "stepgen1-quadrature": (2, None),
    "user-type15-velocity": (15, (1, 3, 2, 6, 4, 5)),
}


def test_every_golden_trace_is_listed() -> None:
    assert {p.stem for p in GOLDEN.glob("*.vcd")} == set(GOLDEN_TYPES)


@pytest.mark.parametrize("name", sorted(GOLDEN_TYPES))
@pytest.mark.parametrize("edge", ["rising", "falling"])
def test_measure_gives_checks_intervals_for_every_rule(name: str, edge: str) -> None:
    """One engine: for every rule of the step type, measure's intervals are the very intervals
    check judges (a drive stating every figure), so its shortest is check's shortest, to the tick."""
    number, table = GOLDEN_TYPES[name]
    cap = open_capture(GOLDEN / f"{name}.vcd")
    every = [f"{r}=1ns" for r in TIME_RULES] + ["max_rate=10MHz"]
    drive = tune_drive(load_drive("gecko-g202"), every)
    report = run_check(cap, drive, None, (), number, active_edge=edge, user_table=table)  # type: ignore[arg-type]
    options = CheckOptions(step_type={None: number}, active_edge=edge, user_table=table)  # type: ignore[arg-type]
    (m,) = measure(cap, options).axes
    judged = {r.rule: report.rule(r.rule) for r in report.rules if r.limit_ns is not None}
    assert set(judged) == {s.rule for s in m.stats}  # every interval kind of the step type
    for s in m.stats:
        r = judged[s.rule]
        lengths, counts = np.unique(r.intervals.measured, return_counts=True)
        assert np.array_equal(m.distributions[s.rule][0], lengths)
        assert np.array_equal(m.distributions[s.rule][1], counts)
        assert s.count == r.checked
        assert s.min_ns == r.min_measured_ns and s.max_ns == r.max_measured_ns
        if s.count:
            assert s.min_at == r.min_margin_at_tick
    assert m.steps.count == report.steps.count
    assert m.steps.final_position == report.steps.final_position
    assert m.sequence_errors == len(report.steps.sequence_errors)
    assert m.sequence_errors == 0  # decoded with the table it was made with


def test_figures_of_a_known_wave(tmp_path: Path) -> None:
    """Pulses of 1, 2, 3 and 4 us every 10 us, DIR up 500 ns before the third: every figure is
    known by construction."""
    us = 1000
    step = [
        t
        for k, w in enumerate((1, 2, 3, 4))
        for t in (10 * us * (k + 1), 10 * us * (k + 1) + w * us)
    ]
    vcd = write_vcd(tmp_path / "w.vcd", {"step": (0, step), "dir": (0, [29 * us + 500])})
    m = measure(open_capture(vcd), CheckOptions())
    a = m.axes[0]
    high = a.stat("step_high")
    assert (high.count, high.min_ns, high.max_ns, high.mean_ns) == (4, 1000, 4000, 2500)
    assert high.min_at == 10 * us and high.max_at == 40 * us
    assert high.percentiles == {1: 1000, 5: 1000, 50: 2000, 95: 4000, 99: 4000}
    assert a.stat("step_period").count == 3 and a.rate_max_hz == a.rate_min_hz == 100_000
    assert (
        a.stat("dir_setup").min_ns == 500 and a.stat("dir_hold").min_ns == 9500
    )  # 20 us → 29.5 us
    assert a.steps.forward == 2 and a.steps.reverse == 2
    assert a.reversal_ticks.tolist() == [30 * us] and a.stat("enable_setup").count == 0
    assert m.resolution_ns == 0


def test_resolution_is_the_sample_period(smoothie_sr: Path) -> None:
    options = CheckOptions(axes=(AxisMap("x", {"step": "5", "dir": "6"}),))
    m = measure(open_capture(smoothie_sr), options)
    assert m.resolution_ns == Fraction(1000, 12)  # 12 MHz
    with pytest.raises(KeyError):
        m.axis("y")


@given(st.lists(st.integers(-(2**40), 2**62), max_size=50))
def test_exact_sum_never_overflows(values: list[int]) -> None:
    assert _exact_sum(np.asarray(values, dtype=np.int64)) == sum(values)


@given(
    st.lists(st.integers(0, 10**6), min_size=1, max_size=200),
    st.lists(st.integers(1, 200), max_size=6),
)
def test_percentiles_are_measured_values(widths: list[int], cuts: list[int]) -> None:
    """The counts of the distinct lengths, merged window by window, give exact percentiles."""
    start = np.arange(len(widths), dtype=np.int64) * 10**7
    iv = Intervals(start, start + np.asarray(widths))
    counts = IntervalCounts([rule("step_high")])
    bounds = sorted({0, len(widths), *(c for c in cuts if c < len(widths))})
    for a, b in zip(bounds, bounds[1:], strict=False):
        counts.add_intervals(rule("step_high"), Intervals(iv.start[a:b], iv.end[a:b]))
    s = counts.kinds["step_high"].stats(NS)
    ordered = sorted(widths)
    for p, v in s.percentiles.items():  # inverted CDF: the smallest value with ≥ p % at or below
        k = next(i for i in range(len(ordered)) if (i + 1) * 100 >= p * len(ordered))
        assert v == ordered[k]
    assert s.mean_ns == Fraction(sum(widths), len(widths))
    assert s.min_ticks == min(widths) and s.max_ticks == max(widths)


def test_reversals_skip_unknown_steps() -> None:
    d = np.array([1, 1, 0, -1, -1, 0, 0, -1, 1], dtype=np.int8)
    trace = StepTrace()
    trace.add(np.arange(9, dtype=np.int64) * 10, d)
    assert trace.reversal_ticks.tolist() == [30, 80] and trace.reversals == 2
