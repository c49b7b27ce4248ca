"""Verdicts and the exit codes they give, in one place.

A rule is ``pass``, ``fail``, ``indeterminate`` (the sample rate cannot decide it) or
``unchecked`` (no interval of its kind in the capture). Exit codes of both command-line tools:
0 pass, 1 a rule failed, 2 unusable input or usage, 3 only indeterminate or unchecked results.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from typing import Literal

__all__ = [
    "EXIT_FAIL",
    "EXIT_INDETERMINATE",
    "EXIT_PASS",
    "EXIT_USAGE",
    "Verdict",
    "exit_code",
    "overall_verdict",
    "qualified_verdict",
    "verdict_of_exit",
    "worst_exit_code",
]

Verdict = Literal["pass", "fail", "indeterminate", "unchecked"]

EXIT_PASS = 0
EXIT_FAIL = 1
EXIT_USAGE = 2
EXIT_INDETERMINATE = 3

_EXIT: dict[str, int] = {
    "pass": EXIT_PASS,
    "fail": EXIT_FAIL,
    "indeterminate": EXIT_INDETERMINATE,
    "unchecked": EXIT_INDETERMINATE,
}
#: How bad an exit code is when several runs are summed up: usage > fail > indeterminate > pass.
_SEVERITY = {EXIT_PASS: 0, EXIT_INDETERMINATE: 1, EXIT_FAIL: 2, EXIT_USAGE: 3}


def overall_verdict(verdicts: Iterable[Verdict | str]) -> Verdict:
    """fail if any is fail, else indeterminate if any is, else pass if any is, else unchecked
    (``unchecked`` rules never turn a pass into a fail)."""
    seen = set(verdicts)
    for v in ("fail", "indeterminate", "pass"):
        if v in seen:
            return v  # type: ignore[return-value]
    return "unchecked"


def exit_code(verdict: Verdict | str) -> int:
    """The exit code of an overall verdict: 0 pass, 1 fail, 3 indeterminate or unchecked."""
    return _EXIT[verdict]


def verdict_of_exit(code: int) -> Verdict | None:
    """The verdict an exit code stands for (3 → indeterminate), None for 2 (unusable input)."""
    return {EXIT_PASS: "pass", EXIT_FAIL: "fail", EXIT_INDETERMINATE: "indeterminate"}.get(code)  # type: ignore[return-value]


def worst_exit_code(codes: Iterable[int]) -> int:
    """The worst of several exit codes: 2 > 1 > 3 > 0."""
    return max(codes, key=lambda c: _SEVERITY.get(c, 3), default=EXIT_PASS)


def qualified_verdict(verdict: Verdict | str, unchecked: Mapping[str, Sequence[str]]) -> str:
    """The verdict as a report's verdict line says it: upper case, followed by the rules that
    were not checked grouped by why (``unchecked``: reason → rule ids), so a PASS never hides an
    unchecked rule: ``PASS (dir_setup, dir_hold not checked: no DIR channel)``."""
    parts = [f"{', '.join(rules)} not checked: {why}" for why, rules in unchecked.items() if rules]
    return verdict.upper() + (f" ({'; '.join(parts)})" if parts else "")
