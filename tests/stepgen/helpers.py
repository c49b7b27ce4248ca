"""Small helpers shared by the stepgen tests."""

from __future__ import annotations

import numpy as np

from stepgen.reference import InvocationRun


def levels(run: InvocationRun, pin: str) -> np.ndarray:
    """The pin's level after every invocation (0/1), rebuilt from its toggle indices."""
    flips = np.zeros(run.n_periods + 1, dtype=np.int64)
    np.add.at(flips, run.toggles[pin], 1)
    return (np.cumsum(flips)[: run.n_periods] & 1).astype(np.int64)


def counts_per_period(run: InvocationRun) -> np.ndarray:
    """The counts value after every invocation."""
    out = np.zeros(run.n_periods, dtype=np.int64)
    if len(run.counts_at):
        marks = np.zeros(run.n_periods, dtype=np.int64)
        marks[run.counts_at] = 1
        idx = np.cumsum(marks) - 1
        has = idx >= 0
        out[has] = run.counts_val[idx[has]]
    return out
