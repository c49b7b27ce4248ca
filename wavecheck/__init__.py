"""wavecheck: check every edge of a STEP/DIR capture against a stepper drive's datasheet."""

from typing import TYPE_CHECKING, Any

from wavecheck.errors import (
    CaptureError,
    ConfigError,
    RuleError,
    UnitError,
    UsageError,
    WavecheckError,
)
from wavecheck.timebase import Timebase

if TYPE_CHECKING:
    from wavecheck.api import check
    from wavecheck.engine import run_check
    from wavecheck.report.model import Report

# The check API is imported on first use: stepgen imports wavecheck.errors, and the engine
# imports stepgen's step tables, so an eager import here would be circular.
_LAZY = {
    "check": "wavecheck.api",
    "run_check": "wavecheck.engine",
    "Report": "wavecheck.report.model",
}


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        import importlib

        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'wavecheck' has no attribute {name!r}")


__all__ = [
    "CaptureError",
    "ConfigError",
    "Report",
    "RuleError",
    "Timebase",
    "UnitError",
    "UsageError",
    "WavecheckError",
    "check",
    "run_check",
]
__version__ = "0.1.0"
