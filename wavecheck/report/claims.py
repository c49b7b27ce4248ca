"""What a check's verdict claims: the rules it did not check and why, and ``--require``.

Every report of ``check`` (and of ``watch``, the API, the pytest plugin and the cocotb monitor)
describes its rules as :class:`~wavecheck.verdict.RuleStatus` rows here, the way ``config`` does
for a firmware configuration (:attr:`wavecheck.firmware.evaluate.ConfigResult.statuses`); the
verdict line, the unmet requirements and the exit code then come from :mod:`wavecheck.verdict`,
one mechanism for both. Why a rule was not checked, in order:

- a role it needs is not mapped: ``no DIR channel`` (``no ENABLE channel``);
- the drive states no figure for it: ``drive tb6600 states no figure``;
- a signal it reads never changes in the capture: ``DIR never changes``;
- every interval it found touches an unknown (x/z) stretch;
- otherwise: no interval of its kind in the capture (fewer than two steps, no reversal …).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from wavecheck.engine import MachineReport, Report, RuleResult
from wavecheck.rules import RULE_IDS, rule
from wavecheck.units import format_ns
from wavecheck.verdict import (
    EXIT_REQUIRED,
    RuleStatus,
    Unmet,
    check_require,
    qualified_verdict,
    required_exit_code,
    required_line,
    unchecked_by_reason,
    unchecked_phrase,
    unmet_requirements,
)

__all__ = [
    "exit_code",
    "not_checked",
    "outcome_line",
    "requirement_line",
    "required_dict",
    "rule_statuses",
    "statuses",
    "unchecked",
    "unmet",
    "verdict_line",
]

Checked = Report | MachineReport


def _reports(checked: Checked) -> list[Report]:
    return checked.axes if isinstance(checked, MachineReport) else [checked]


def _roles(report: Report, rule_id: str) -> tuple[str, ...]:
    """The roles a rule reads for this report's step type (a rule of the pulses' own edges: the
    pulse roles)."""
    return rule(rule_id).roles_for(report.step_type) or report.step_type.pulse_roles


def _why_unchecked(report: Report, r: RuleResult) -> str:
    roles = _roles(report, r.rule)
    missing = [role for role in roles if report.interface.get(role) is None]
    if missing:
        return f"no {' or '.join(m.upper() for m in missing)} channel"
    channels = {c.name: c for c in report.capture.channels}
    still = []
    for role in roles:
        sig = report.interface.get(role)
        ch = channels.get(sig.channel) if sig is not None else None
        if ch is not None and ch.edge_count == 0:
            still.append(role.upper())
    if still:
        return f"{' and '.join(still)} never change{'s' if len(still) == 1 else ''}"
    if r.unknown:
        return f"each of its {r.unknown} interval(s) touches an unknown (x/z) stretch"
    return "no interval of its kind in the capture"


def _why_indeterminate(r: RuleResult) -> str:
    return (
        f"{r.indeterminate} interval(s) within one sample of the limit at T = "
        f"{format_ns(r.resolution_ns)}"
    )


def rule_statuses(report: Report) -> list[RuleStatus]:
    """The rules of one report: those it evaluated, then those the drive states no figure for."""
    out = []
    for r in report.rules:
        why = ""
        if r.verdict == "unchecked":
            why = _why_unchecked(report, r)
        elif r.verdict == "indeterminate":
            why = _why_indeterminate(r)
        out.append(RuleStatus(r.rule, r.verdict, why, report.axis))
    no_figure = f"drive {report.drive.id} states no figure"
    out += [
        RuleStatus(rule_id, "unchecked", no_figure, report.axis, stated=False)
        for rule_id in report.not_stated
    ]
    return out


def statuses(checked: Checked) -> list[RuleStatus]:
    """The rules of every axis of ``checked``."""
    return [s for r in _reports(checked) for s in rule_statuses(r)]


def unchecked(checked: Checked) -> dict[str, tuple[str, ...]]:
    """Why → the rules of ``checked`` not checked for that reason (``AXIS.RULE`` for a rule not
    checked on every axis)."""
    return unchecked_by_reason(statuses(checked))


def not_checked(checked: Checked) -> str:
    """``dir_setup, dir_hold not checked: no DIR channel; …``: what the verdict line adds to
    the verdict ("" when every rule was checked)."""
    return unchecked_phrase(unchecked(checked))


def verdict_line(checked: Checked) -> str:
    """``PASS (dir_setup, dir_hold not checked: no DIR channel)``; several axes:
    ``FAIL (2 axes; y.dir_setup … not checked: …)``."""
    lead = f"{len(checked.axes)} axes" if isinstance(checked, MachineReport) else ""
    return qualified_verdict(checked.verdict, unchecked(checked), lead)


def outcome_line(checked: Checked, require: Sequence[str] = ()) -> str:
    """The verdict line with the run's outcome first: as :func:`verdict_line`, or, when a
    required rule was not decided and the run exits 4, ``NOT DECIDED (exit 4: required dir_hold
    not checked: no DIR channel); the rules checked: PASS (…)`` — the first line of a report
    says what its exit code says."""
    line = verdict_line(checked)
    missing = unmet(checked, require)
    if required_exit_code(checked.exit_code, missing) != EXIT_REQUIRED:
        return line
    what = required_line(missing, statuses(checked)).removeprefix("required but not decided: ")
    return f"NOT DECIDED (exit {EXIT_REQUIRED}: required {what}); the rules checked: {line}"


def unmet(checked: Checked, require: Sequence[str]) -> tuple[Unmet, ...]:
    """The required rules (``--require``) that ``checked`` did not decide."""
    check_require(require, RULE_IDS)
    return unmet_requirements(statuses(checked), require)


def requirement_line(checked: Checked, require: Sequence[str]) -> str:
    """``required but not decided: …`` for the required rules ``checked`` did not
    decide; empty when there are none."""
    return required_line(unmet(checked, require), statuses(checked))


def exit_code(checked: Checked, require: Sequence[str] = ()) -> int:
    """The run's exit code: the verdict's, or 4 when a required rule was not decided
    (:func:`wavecheck.verdict.required_exit_code`)."""
    return required_exit_code(checked.exit_code, unmet(checked, require))


def required_dict(require: Sequence[str], unmet: Sequence[Unmet]) -> dict[str, Any]:
    """``{"rules": [...], "unmet": [{rule, axis, verdict, why}]}`` of ``--require``."""
    return {
        "rules": list(require),
        "unmet": [
            {"rule": u.rule, "axis": u.axis, "verdict": u.verdict, "why": u.why} for u in unmet
        ],
    }
