"""Timing checks: generic measurements, exact verdicts, and the drive's rules compiled from them."""

from wavecheck.checks.compile import RuleSet, applicable_rules, run_rules
from wavecheck.checks.primitives import Intervals, holds, periods, setups, widths
from wavecheck.checks.result import (
    FAIL,
    INDETERMINATE,
    PASS,
    RuleResult,
    Verdict,
    Violation,
    evaluate,
    sequence_result,
)

__all__ = [
    "FAIL",
    "INDETERMINATE",
    "PASS",
    "Intervals",
    "RuleResult",
    "RuleSet",
    "Verdict",
    "Violation",
    "applicable_rules",
    "evaluate",
    "holds",
    "periods",
    "run_rules",
    "sequence_result",
    "setups",
    "widths",
]
