"""wavecheck: check every edge of a STEP/DIR capture against a stepper drive's datasheet.

The names below are imported when first used (PEP 562), so that ``import wavecheck.units`` or
``stepgen`` does not load the check engine and its report layers.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from wavecheck.api import Axis, check, check_axes
    from wavecheck.engine import run_check
    from wavecheck.errors import (
        CaptureError,
        ConfigError,
        RuleError,
        UnitError,
        UsageError,
        WavecheckError,
    )
    from wavecheck.report.machine import MachineReport
    from wavecheck.report.model import Report
    from wavecheck.timebase import Timebase

__all__ = [
    "Axis",
    "CaptureError",
    "ConfigError",
    "MachineReport",
    "Report",
    "RuleError",
    "Timebase",
    "UnitError",
    "UsageError",
    "WavecheckError",
    "__version__",
    "check",
    "check_axes",
    "run_check",
]

#: The package version, written only here: pyproject.toml reads it at build time
#: ([tool.setuptools.dynamic]), so the installed distribution always carries this value.
__version__ = "0.1.0"

#: Each public name → the module that defines it.
_HOME = {
    "Axis": "api",
    "check": "api",
    "check_axes": "api",
    "run_check": "engine",
    "CaptureError": "errors",
    "ConfigError": "errors",
    "RuleError": "errors",
    "UnitError": "errors",
    "UsageError": "errors",
    "WavecheckError": "errors",
    "MachineReport": "report.machine",
    "Report": "report.model",
    "Timebase": "timebase",
}


def __getattr__(name: str) -> Any:
    """Import a public name's module on first use."""
    home = _HOME.get(name)
    if home is None:
        raise AttributeError(f"module 'wavecheck' has no attribute {name!r}")
    value = getattr(importlib.import_module(f"wavecheck.{home}"), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
