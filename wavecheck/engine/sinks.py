"""What needs more of a check than its results: step and interval sinks the engine feeds.

The engine keeps, per rule, only mergeable results (:mod:`wavecheck.engine.results`). Whatever
needs every step (``--steps-csv``, ``compare``'s :class:`~wavecheck.compare.StepCollector`,
``follow``, the common-timer note, the plot's step trace) or every interval (``wavecheck
measure``'s percentiles) is a *sink*: the engine hands it each window's new steps or intervals,
in time order, once each, and keeps nothing for it.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Protocol

import numpy as np

from wavecheck.capture.edges import EdgeArray
from wavecheck.rules import Rule
from wavecheck.steps.primitives import Intervals

if TYPE_CHECKING:
    import numpy.typing as npt

__all__ = ["IntervalSink", "StepSink", "TimerSample"]

_EMPTY = np.zeros(0, dtype=np.int64)


class StepSink(Protocol):
    """Takes each window's new steps (ticks increasing; direction +1, −1, 0 unknown)."""

    def add(self, ticks: EdgeArray, direction: npt.NDArray[np.int8]) -> None: ...


class IntervalSink(Protocol):
    """Takes each window's complete, known intervals of each measured rule (not judged)."""

    def add_intervals(self, rule: Rule, intervals: Intervals) -> None: ...


class TimerSample:
    """The first ``limit`` step ticks (the several-axes common-timer note reads a bounded
    sample, stated in the note)."""

    def __init__(self, limit: int) -> None:
        self.limit = limit
        self._parts: list[EdgeArray] = []
        self.kept = 0
        self.seen = 0

    def add(self, ticks: EdgeArray, direction: npt.NDArray[np.int8]) -> None:
        self.seen += len(ticks)
        room = self.limit - self.kept
        if room > 0 and len(ticks):
            self._parts.append(ticks[:room].copy())
            self.kept += min(room, len(ticks))

    @property
    def ticks(self) -> EdgeArray:
        """The sampled step ticks, increasing."""
        return np.concatenate(self._parts) if self._parts else _EMPTY.copy()
