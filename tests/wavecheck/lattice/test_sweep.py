"""The lateness sweep of issue 25: P ∈ {20, 25, 34, 50} µs × uniform, spike and worst-case
latency at 10 … 95 % of P × 3 seeds × two sample rates, each capture a short stepgen run with
ramps, cruises at the maximum step rate and reversals (tests/wavecheck/lattice_captures.py).

Facts checked (stepgen reference §2.1, stepgen/lateness.py): every pin a make-pulses invocation
changes changes at its one moment k·P + l_k, l_k ≥ 0; the model's worst case runs the end events
of RULE's intervals on time and every other invocation J late. Required: a lattice at exactly P,
and a maximum lateness never below the true one (the bound: measured + one sample) and within a
sample of it. Where the capture cannot tell two readings apart (a few edges a sample before the
bulk at 95 % of P and 1 MHz), both are reported and the worst lateness is not established
(issue 33): the true one must be among them, the figures (the larger) never below it. The
worst-case seed picks the rule: 1 step_high, 2 dir_hold, 3 step_period.
"""

from __future__ import annotations

from fractions import Fraction

import pytest

from tests.wavecheck.lattice.captures import capture, roles, run, true_lateness
from wavecheck.lattice import analyse

pytestmark = pytest.mark.slow

PERIODS_US = (20, 25, 34, 50)
FRACTIONS = (0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 0.95)
RATES = (1_000_000, 3_300_000)  # 25 and 34 us are 82.5 and 112.2 samples at 3.3 MHz
RULES = {1: "step_high", 2: "dir_hold", 3: "step_period"}


def _model(kind: str, j_ns: int, seed: int) -> str:
    if kind == "uniform":
        return f"uniform:{j_ns}ns"
    if kind == "spike":
        return f"spike:{j_ns}ns@20ms"
    return f"worst:{j_ns}ns:{RULES[seed]}"


@pytest.mark.parametrize("seed", (1, 2, 3))
@pytest.mark.parametrize("kind", ("uniform", "spike", "worst"))
@pytest.mark.parametrize("fraction", FRACTIONS)
@pytest.mark.parametrize("period_us", PERIODS_US)
def test_sweep(period_us: int, fraction: float, kind: str, seed: int) -> None:
    p_ns = period_us * 1000
    trace = run(p_ns, _model(kind, int(p_ns * fraction), seed), seed)
    truth = true_lateness(trace)
    for rate in RATES:
        sample = Fraction(10**9, rate)
        r = analyse(capture(trace, rate), list(trace.pins), roles=roles(trace))
        where = (trace.latency.text, rate, r.reason, r.candidates)
        # two readings the capture cannot tell apart (95 % of P): not established (issue 33)
        assert r.lattice and r.established != bool(r.candidates), where
        bound = r.max_lateness_bound_ns
        assert bound is not None and r.max_lateness_ns is not None
        assert bound >= truth, where  # never under-reported
        readings = [(r.period_ns, r.max_lateness_ns)] + [
            (c.period_ns, c.max_lateness_ns) for c in r.candidates
        ]
        assert any(p == p_ns and abs(m - truth) <= sample for p, m in readings), where
        if not r.candidates:
            assert r.period_ns == p_ns, where
            assert abs(r.max_lateness_ns - truth) <= sample, where
