"""wavecheck: check every edge of a STEP/DIR capture against a stepper drive's datasheet.

The names below are loaded when first used, so ``import wavecheck`` (and ``wavecheck --help``)
costs no numpy: :func:`check`, :func:`check_axes`, :class:`Axis`, :class:`CheckOptions`,
:class:`Report`, :class:`MachineReport`, :class:`Timebase` and the errors.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

from wavecheck.errors import (
    CaptureError,
    ConfigError,
    RuleError,
    UnitError,
    UsageError,
    WavecheckError,
)

if TYPE_CHECKING:
    from wavecheck.api import Axis, check, check_axes
    from wavecheck.engine import CheckOptions, MachineReport, Report
    from wavecheck.timebase import Timebase

__all__ = [
    "Axis",
    "CaptureError",
    "CheckOptions",
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
]

#: The package version, written only here: pyproject.toml reads it at build time
#: ([tool.setuptools.dynamic]), so the installed distribution always carries this value.
__version__ = "0.1.0"

_LAZY = {
    "Axis": "wavecheck.api",
    "check": "wavecheck.api",
    "check_axes": "wavecheck.api",
    "CheckOptions": "wavecheck.engine",
    "MachineReport": "wavecheck.engine",
    "Report": "wavecheck.engine",
    "Timebase": "wavecheck.timebase",
}


def __getattr__(name: str) -> Any:
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'wavecheck' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value
