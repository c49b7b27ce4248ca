"""wavecheck: check every edge of a STEP/DIR capture against a stepper drive's datasheet."""

from wavecheck.api import Axis, check, check_axes
from wavecheck.engine.plan import run_check
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
