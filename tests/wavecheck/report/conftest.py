"""Fixtures of the report tests: stepgen-like G202 traces, failing and passing."""

from __future__ import annotations

import pytest

from tests.engine_probe import run_check
from tests.wavecheck.report.traces import stepgen_trace
from tests.wavecheck.waves import capture, g202
from wavecheck.engine.outcome import Report


@pytest.fixture(scope="module")
def failing_report() -> Report:
    """G202, P = 20 µs, J = 11 µs worst case: three DIR holds of 9 µs (< 20 µs)."""
    return run_check(capture(stepgen_trace()), g202(), pictures=True)


@pytest.fixture(scope="module")
def passing_report() -> Report:
    """G202, P = 25 µs, no latency: every rule passes; dir_hold 25 µs is the closest (+5 µs)."""
    return run_check(capture(stepgen_trace(period_ns=25_000, latency_ns=0)), g202(), pictures=True)
