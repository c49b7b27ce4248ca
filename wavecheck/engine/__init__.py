"""The one engine: edge blocks in, per-axis results out. Import it from here, not its modules.

A capture (a file read block by block, a pipe, a live device, a simulation, a capture already in
memory) is a :class:`~wavecheck.capture.blocks.BlockSource`. What a check is asked is one options
object (:mod:`.options`), its channels and axes named as :mod:`wavecheck.steps` reads them.
:mod:`.run` finds the axes and feeds every axis (:mod:`.axis`) the same blocks; each axis is
resolved against the capture's channels (:mod:`.resolve`), its steps decoded
(:mod:`wavecheck.steps.decode`), every rule's intervals measured (:mod:`.intervals`) and judged
exactly (:mod:`.judge`), and merged window by window into one result per rule (:mod:`.results`,
:mod:`.rates`), in memory that follows a window, not the capture. What needs more than the
results is fed as the engine runs (:mod:`.sinks`, :mod:`.trace`, :mod:`.windows`), and
:mod:`.outcome` holds the reports.

The names below are the engine's face for the rest of the package (``tests/architecture/
test_engine_door.py`` forbids importing its modules from outside it). They load on first use,
as ``wavecheck``'s own names do, so importing one costs only its module.

- ask: :class:`CheckOptions` (:data:`DEFAULT_BLOCK_EDGES`);
- run: :func:`check_source` (a block source), :func:`check_capture` (a capture in memory),
  :func:`start` (block by block, with step sinks), and for a live check :func:`axes_for`,
  :func:`needs_waveforms`, :func:`machine_for`, :class:`MachineCheck`;
- plan without running: :func:`plan_axes`, :class:`AxisPlan`, :func:`auto_map`,
  :func:`default_step_type`, :func:`resolve_resolution_ns`, :func:`planned_rules`;
- read the results: :class:`Report`, :class:`MachineReport`, :class:`RuleResult`,
  :class:`StepCounts`, :class:`Violation`, :class:`Histogram`, :class:`StepTrace`;
- judge one interval as the engine does (the PulseView decoder): :func:`figure_of`,
  :func:`thresholds`, :func:`pulse_level`;
- steps on the way: :class:`StepSink`, :class:`StepCollector`.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from wavecheck.engine.intervals import figure_of, planned_rules
    from wavecheck.engine.judge import Histogram, Violation
    from wavecheck.engine.judge import _thresholds as thresholds
    from wavecheck.engine.options import DEFAULT_BLOCK_EDGES, CheckOptions
    from wavecheck.engine.outcome import MachineReport, Report
    from wavecheck.engine.rates import pulse_level
    from wavecheck.engine.resolve import (
        AxisPlan,
        auto_map,
        default_step_type,
        plan_axes,
        resolve_resolution_ns,
    )
    from wavecheck.engine.results import RuleResult, StepCounts
    from wavecheck.engine.run import (
        MachineCheck,
        axes_for,
        check_capture,
        check_source,
        machine_for,
        needs_waveforms,
        start,
    )
    from wavecheck.engine.sinks import StepCollector, StepSink
    from wavecheck.engine.trace import StepTrace

#: The modules of the face, each with the names it gives: the name it has there, but
#: ``thresholds`` (``_RENAMED``), which is :func:`.judge._thresholds`.
_MODULES: dict[str, tuple[str, ...]] = {
    "options": ("CheckOptions", "DEFAULT_BLOCK_EDGES"),
    "run": (
        "check_source",
        "check_capture",
        "start",
        "machine_for",
        "MachineCheck",
        "axes_for",
        "needs_waveforms",
    ),
    "resolve": ("plan_axes", "AxisPlan", "auto_map", "default_step_type", "resolve_resolution_ns"),
    "outcome": ("Report", "MachineReport"),
    "results": ("RuleResult", "StepCounts"),
    "judge": ("Violation", "Histogram", "thresholds"),
    "intervals": ("figure_of", "planned_rules"),
    "rates": ("pulse_level",),
    "sinks": ("StepSink", "StepCollector"),
    "trace": ("StepTrace",),
}
_FACE = {name: module for module, names in _MODULES.items() for name in names}
_RENAMED = {"thresholds": "_thresholds"}

__all__ = [
    "AxisPlan",
    "CheckOptions",
    "DEFAULT_BLOCK_EDGES",
    "Histogram",
    "MachineCheck",
    "MachineReport",
    "Report",
    "RuleResult",
    "StepCollector",
    "StepCounts",
    "StepSink",
    "StepTrace",
    "Violation",
    "auto_map",
    "axes_for",
    "check_capture",
    "check_source",
    "default_step_type",
    "figure_of",
    "machine_for",
    "needs_waveforms",
    "plan_axes",
    "planned_rules",
    "pulse_level",
    "resolve_resolution_ns",
    "start",
    "thresholds",
]


def __getattr__(name: str) -> Any:
    where = _FACE.get(name)
    if where is None:
        raise AttributeError(f"module 'wavecheck.engine' has no attribute {name!r}")
    module = importlib.import_module(f"wavecheck.engine.{where}")
    value = getattr(module, _RENAMED.get(name, name))
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *__all__})
