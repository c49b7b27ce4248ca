"""The one engine: edge blocks in, per-axis results out. Import it from here (or a side door).

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

The names below are the engine's face for the rest of the package; two side doors give what
a few users need beyond it: :mod:`.planning` (plan and judge without running) and :mod:`.parts`
(the parts of a report beyond its rules). ``tests/architecture/test_engine_door.py`` forbids
importing any other module of the engine from outside it. The names load on first use, as
``wavecheck``'s own names do, so importing one costs only its module.

- ask: :class:`CheckOptions`;
- run: :func:`check_source` (a block source), :func:`check_capture` (a capture in memory),
  :func:`start` (block by block, with step sinks, :class:`StepSink`), and for a live check
  :func:`axes_for`, :func:`needs_waveforms`, :func:`machine_for`, :class:`MachineCheck`;
- read the results: :class:`Report`, :class:`MachineReport`, :class:`RuleResult`,
  :class:`Violation`.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from wavecheck.engine.judge import Violation
    from wavecheck.engine.options import CheckOptions
    from wavecheck.engine.outcome import MachineReport, Report
    from wavecheck.engine.results import RuleResult
    from wavecheck.engine.run import (
        MachineCheck,
        axes_for,
        check_capture,
        check_source,
        machine_for,
        needs_waveforms,
        start,
    )
    from wavecheck.engine.sinks import StepSink

#: The modules of the face, each with the names it gives.
_MODULES: dict[str, tuple[str, ...]] = {
    "options": ("CheckOptions",),
    "run": (
        "check_source",
        "check_capture",
        "start",
        "machine_for",
        "MachineCheck",
        "axes_for",
        "needs_waveforms",
    ),
    "outcome": ("Report", "MachineReport"),
    "results": ("RuleResult",),
    "judge": ("Violation",),
    "sinks": ("StepSink",),
}
_FACE = {name: module for module, names in _MODULES.items() for name in names}

__all__ = [
    "CheckOptions",
    "MachineCheck",
    "MachineReport",
    "Report",
    "RuleResult",
    "StepSink",
    "Violation",
    "axes_for",
    "check_capture",
    "check_source",
    "machine_for",
    "needs_waveforms",
    "start",
]


def __getattr__(name: str) -> Any:
    where = _FACE.get(name)
    if where is None:
        raise AttributeError(f"module 'wavecheck.engine' has no attribute {name!r}")
    module = importlib.import_module(f"wavecheck.engine.{where}")
    value = getattr(module, name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *__all__})
