"""The one engine: edge blocks in, per-axis results out. Import it from here, not its modules.

A capture (a file read block by block, a pipe, a live device, a simulation, a capture already in
memory) is a :class:`~wavecheck.capture.blocks.BlockSource`. What a check is asked is one options
object (:mod:`.options`), its channels and axes named by :mod:`.interface` and :mod:`.mapping`.
:mod:`.run` finds the axes and feeds every axis (:mod:`.axis`) the same blocks; each axis is
resolved against the capture's channels (:mod:`.resolve`), its steps decoded (:mod:`.decode`),
every rule's intervals measured (:mod:`.intervals`, :mod:`.primitives`) and judged exactly
(:mod:`.judge`), and merged window by window into one result per rule (:mod:`.results`,
:mod:`.rates`), in memory that follows a window, not the capture. What needs more than the
results is fed as the engine runs (:mod:`.sinks`, :mod:`.trace`, :mod:`.windows`), and
:mod:`.outcome` holds the reports.

The names below are the engine's face for the rest of the package (``tests/architecture/
test_engine_door.py`` forbids importing its modules from outside it). They load on first use,
as ``wavecheck``'s own names do, so importing one costs only its module.

- ask: :class:`CheckOptions`, :data:`DEFAULT_BLOCK_EDGES`, :data:`DEFAULT_KEEP`; axes
  (:class:`AxisMap`, :func:`parse_axes`, :func:`axes_from_tables`, :func:`per_axis`,
  :func:`split_per_axis`, :func:`split_invert`, :func:`check_axis_names`) and channel roles
  (:func:`parse_map`, :func:`role_name`, :func:`find_channel`, :func:`build_interface`,
  :class:`StepInterface`, :class:`RoleSignal`);
- run: :func:`check_source`, :func:`check_capture`, :func:`start`, :func:`machine_for`,
  :class:`MachineCheck`, :func:`axes_for`, :func:`needs_waveforms`, :func:`plan_axes`,
  :class:`AxisPlan`, :func:`auto_map`, :func:`default_step_type`, :func:`resolve_resolution_ns`;
- read the results: :class:`Report`, :class:`MachineReport`, :class:`RuleResult`,
  :class:`StepCounts`, :class:`Violation`, :class:`Histogram`, :data:`PASS`, :data:`FAIL`,
  :data:`INDETERMINATE`, :func:`thresholds`, :func:`figure_of`, :func:`planned_rules`,
  :func:`pulse_level`;
- steps and intervals on the way: :func:`decode_steps`, :class:`StepEvents`, :class:`StepSink`,
  :class:`StepCollector`, :class:`StepTrace`, :class:`Intervals`.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from wavecheck.engine.decode import StepEvents
    from wavecheck.engine.decode import decode as decode_steps
    from wavecheck.engine.interface import (
        RoleSignal,
        StepInterface,
        build_interface,
        find_channel,
        parse_map,
        role_name,
    )
    from wavecheck.engine.intervals import figure_of, planned_rules
    from wavecheck.engine.judge import FAIL, INDETERMINATE, PASS, Histogram, Violation
    from wavecheck.engine.judge import _thresholds as thresholds
    from wavecheck.engine.mapping import (
        AxisMap,
        axes_from_tables,
        check_axis_names,
        parse_axes,
        per_axis,
        split_invert,
        split_per_axis,
    )
    from wavecheck.engine.options import DEFAULT_BLOCK_EDGES, DEFAULT_KEEP, CheckOptions
    from wavecheck.engine.outcome import MachineReport, Report
    from wavecheck.engine.primitives import Intervals
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

#: The modules of the face, each with the names it gives: the name it has there, but two
#: (``_RENAMED``): ``thresholds`` is :func:`.judge._thresholds`, and ``decode_steps`` is
#: :func:`.decode.decode` (``decode`` names the module, which importing it sets on the package).
_MODULES: dict[str, tuple[str, ...]] = {
    "options": ("CheckOptions", "DEFAULT_BLOCK_EDGES", "DEFAULT_KEEP"),
    "mapping": (
        "AxisMap",
        "parse_axes",
        "axes_from_tables",
        "per_axis",
        "split_per_axis",
        "split_invert",
        "check_axis_names",
    ),
    "interface": (
        "parse_map",
        "role_name",
        "find_channel",
        "build_interface",
        "StepInterface",
        "RoleSignal",
    ),
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
    "judge": ("Violation", "Histogram", "PASS", "FAIL", "INDETERMINATE", "thresholds"),
    "intervals": ("figure_of", "planned_rules"),
    "rates": ("pulse_level",),
    "decode": ("decode_steps", "StepEvents"),
    "sinks": ("StepSink", "StepCollector"),
    "trace": ("StepTrace",),
    "primitives": ("Intervals",),
}
_FACE = {name: module for module, names in _MODULES.items() for name in names}
_RENAMED = {"thresholds": "_thresholds", "decode_steps": "decode"}

__all__ = [
    "AxisMap",
    "AxisPlan",
    "CheckOptions",
    "DEFAULT_BLOCK_EDGES",
    "DEFAULT_KEEP",
    "FAIL",
    "Histogram",
    "INDETERMINATE",
    "Intervals",
    "MachineCheck",
    "MachineReport",
    "PASS",
    "Report",
    "RoleSignal",
    "RuleResult",
    "StepCollector",
    "StepCounts",
    "StepEvents",
    "StepInterface",
    "StepSink",
    "StepTrace",
    "Violation",
    "auto_map",
    "axes_for",
    "axes_from_tables",
    "build_interface",
    "check_axis_names",
    "check_capture",
    "check_source",
    "decode_steps",
    "default_step_type",
    "figure_of",
    "find_channel",
    "machine_for",
    "needs_waveforms",
    "parse_axes",
    "parse_map",
    "per_axis",
    "plan_axes",
    "planned_rules",
    "pulse_level",
    "resolve_resolution_ns",
    "role_name",
    "split_invert",
    "split_per_axis",
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
