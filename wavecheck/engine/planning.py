"""A side door of the engine: what a check will judge, worked out without running it.

For the few users that plan or judge outside a run (``wavecheck info``, ``follow``, the
pytest plugin's rule list, the latency inference, the PulseView decoder's adapter, the
firmware capture check): the axes a capture maps to and their plans, the default step type, the
resolution a capture is judged at, the rules a drive and step type bring, each rule's figure, the
pass/fail thresholds in ticks and the level of the pulses at the drive. Every name here is the
engine's own object (nothing is restated), so a judgement made from them agrees with a check.
"""

from __future__ import annotations

from wavecheck.engine.intervals import figure_of, planned_rules
from wavecheck.engine.judge import _thresholds as thresholds
from wavecheck.engine.rates import pulse_level
from wavecheck.engine.resolve import (
    AxisPlan,
    auto_map,
    default_step_type,
    plan_axes,
    resolve_resolution_ns,
)

__all__ = [
    "AxisPlan",
    "auto_map",
    "default_step_type",
    "figure_of",
    "plan_axes",
    "planned_rules",
    "pulse_level",
    "resolve_resolution_ns",
    "thresholds",
]
