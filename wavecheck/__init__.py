"""wavecheck: check every edge of a STEP/DIR capture against a stepper drive's datasheet."""

from wavecheck.errors import (
    CaptureError,
    ConfigError,
    RuleError,
    UnitError,
    UsageError,
    WavecheckError,
)
from wavecheck.timebase import Timebase

__all__ = [
    "CaptureError",
    "ConfigError",
    "RuleError",
    "Timebase",
    "UnitError",
    "UsageError",
    "WavecheckError",
]
__version__ = "0.1.0"
