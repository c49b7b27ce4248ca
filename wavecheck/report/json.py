"""The JSON report: the design's keys, exact values printed as JSON numbers.

Top-level keys: ``capture``, ``drive``, ``steps``, ``rules``, ``violations`` (capped, worst first),
``violations_total`` (the uncapped count; added beside the design's keys so the cap is visible),
``violations_listed`` (how many ``violations`` lists) and ``violations_truncated`` (true when it
lists fewer than ``violations_total``: raise ``--max-violations`` to list more),
``max_step_rate_hz``, ``verdict``; beside them what the verdict claims (:mod:`wavecheck.report.claims`):
``verdict_line`` (``PASS (dir_setup, dir_hold not checked: no DIR channel)``), ``unchecked``
(``[{why, rules}]``, as ``config``'s JSON), ``required`` (``{rules, unmet: [{rule, axis, verdict,
why}]}``, ``--require``) and ``exit_code``. Times: ``*_ns`` in ns, ``*_s`` in s, rates in Hz. A value that
does not exist (no interval measured, no limit) is ``null``.

How sure each limit is: ``rules[].limit_status`` (datasheet, secondary, firmware-default, preset,
uncertain) and ``limit_source`` (a key of ``drive.sources``, the full references);
``drive.active_edge_status`` likewise for the edge. ``capture.assumptions`` states what the check
assumed (ENABLE level, DIR level meaning forward, inversions, uncertain limits). Every violation
up to the cap is listed one by one (the text and HTML reports group identical ones).
"""

from __future__ import annotations

from collections.abc import Sequence
from fractions import Fraction
from typing import TYPE_CHECKING, Any, cast

from wavecheck.engine import MachineReport, Report, RuleResult, Violation
from wavecheck.report import claims
from wavecheck.report.assumptions import assumptions
from wavecheck.rules import rule
from wavecheck.units import json_number

if TYPE_CHECKING:
    from wavecheck.firmware.capture import FirmwareCheck
    from wavecheck.linuxcnc.stepgen_config import ConfigRates

__all__ = ["DEFAULT_VIOLATION_CAP", "claims_dict", "render_json", "report_dict"]

DEFAULT_VIOLATION_CAP = 1000


def _rule(r: RuleResult) -> dict[str, Any]:
    fig = r.figure
    return {
        "id": r.rule,
        "limit_ns": json_number(r.limit_ns),
        "checked": r.checked,
        "violations": r.violations,
        "indeterminate": r.indeterminate,
        "unknown": r.unknown,  # intervals touching an x/z stretch, not judged
        "unknown_at_s": [json_number(r.timebase.seconds(int(t))) for t in r.unknown_ticks[:100]],
        "min_margin_ns": json_number(r.min_margin_ns),
        "min_margin_at_s": json_number(r.min_margin_at_s),
        "min_measured_ns": json_number(r.min_measured_ns),
        "verdict": r.verdict,
        "decide_samplerate_hz": json_number(r.decide_samplerate_hz),
        "limit_source": fig.source if fig else None,
        "limit_status": fig.status if fig else None,
        # --limit / --margin: the datasheet figure beside the applied one
        "limit_datasheet_ns": json_number(_datasheet_ns(r)),
        "limit_applied": fig.applied if fig else "",
    }


def _datasheet_ns(r: RuleResult) -> Fraction | None:
    fig = r.figure
    if fig is None or fig.datasheet is None:
        return None
    return rule(r.rule).limit_ns(fig.datasheet)


def _violation(v: Violation) -> dict[str, Any]:
    d: dict[str, Any] = {
        "rule": v.rule,
        "time_s": json_number(v.time_s),
        "measured_ns": json_number(v.measured_ns),
        "limit_ns": json_number(v.limit_ns),
        "margin_ns": json_number(v.margin_ns),
    }
    if v.detail:
        d["detail"] = v.detail
    return d


def claims_dict(checked: Report | MachineReport, require: Sequence[str] = ()) -> dict[str, Any]:
    """``verdict_line``, ``unchecked``, ``required`` and ``exit_code`` of a report or a run of
    several axes (:mod:`wavecheck.report.claims`)."""
    unchecked = claims.unchecked(checked)
    return {
        "verdict_line": claims.verdict_line(checked),
        "unchecked": [{"why": why, "rules": list(rules)} for why, rules in unchecked.items()],
        "required": claims.required_dict(require, claims.unmet(checked, require)),
        "exit_code": claims.exit_code(checked, require),
    }


def report_dict(
    report: Report, violation_cap: int = DEFAULT_VIOLATION_CAP, require: Sequence[str] = ()
) -> dict[str, Any]:
    """The report as plain JSON-ready data (see the module docstring for the keys)."""
    cap = report.capture
    mapped = {sig.channel: role for role, sig in report.interface.signals.items()}
    steps = report.steps
    rates = report.rates
    listed = [_violation(v) for v in report.violations(violation_cap)]
    return {
        "capture": {
            "path": cap.path,
            "format": cap.format,
            "resolution_ns": json_number(report.resolution_ns),
            "duration_s": json_number(cap.duration_s),
            "samplerate_hz": json_number(cap.samplerate_hz),
            "channels": [
                {
                    "index": c.index,
                    "name": c.name,
                    "edges": c.edge_count,
                    "role": mapped.get(c.name),
                }
                for c in cap.channels
            ],
            "mapping": report.mapping,
            "inverted": list(report.inverted),
            "notes": list(report.notes),
            "assumptions": assumptions(report),
        },
        "drive": {
            "id": report.drive.id,
            "name": report.drive.name,
            "source": str(report.drive.path),
            "interface": report.drive.interface,
            "active_edge": report.active_edge,
            "active_edge_status": (
                report.drive.edge_status if report.active_edge == report.drive.active_edge else None
            ),
            "sources": dict(report.drive.sources),
            "rules_not_stated": list(report.not_stated),
            "rules_not_applicable": list(report.not_applicable),
        },
        "steps": {
            "step_type": report.step_type.number,
            "step_type_name": report.step_type.name,
            "forward_dir_level": report.forward_level
            if report.step_type.kind == "step-dir"
            else None,
            "count": steps.count,
            "forward": steps.forward,
            "reverse": steps.reverse,
            "unknown_direction": steps.unknown,
            "ambiguous": steps.ambiguous_count,
            "final_position": steps.final_position,
            "position_unknown_from_s": None
            if steps.lost_from is None
            else json_number(report.capture.timebase.seconds(steps.lost_from)),
        },
        "rules": [_rule(r) for r in report.rules],
        "violations": listed,
        "violations_total": report.total_violations,
        "violations_listed": len(listed),
        "violations_truncated": len(listed) < report.total_violations,
        "max_step_rate_hz": {
            "drive": json_number(rates.drive),
            "drive_limited_by": rates.drive_limited_by,
            "observed": json_number(rates.observed),
            "observed_at_s": json_number(rates.observed_at_s),
            "headroom": json_number(rates.headroom),
            "longest_pulse_ns": json_number(rates.longest_pulse_ns),
            "idle_min_ns": json_number(rates.idle_min_ns),
            "pulse_level": rates.pulse_level,
            "typical_pulse_ns": json_number(rates.typical_pulse_ns),
            "headroom_limited_by": rates.headroom_limited_by,
            "headroom_note": rates.headroom_note,
            **_configured(rates.configured),
        },
        "verdict": report.verdict,
        **claims_dict(report, require),
        **_firmware(report),
    }


def _firmware(report: Report) -> dict[str, Any]:
    """``check --firmware``: the capture against its own configuration (key absent otherwise)."""
    if report.firmware is None:
        return {}
    from wavecheck.report.firmware import firmware_check_dict

    return {"firmware": firmware_check_dict(cast("FirmwareCheck", report.firmware))}


def _configured(cfg: ConfigRates | None) -> dict[str, Any]:
    """``config``, ``latency_safe`` and ``config_notes`` when a stepgen configuration was given."""
    if cfg is None:
        return {}
    return {
        "config": json_number(cfg.config),
        "latency_safe": json_number(cfg.latency_safe),
        "config_notes": list(cfg.notes),
    }


def render_json(
    report: Report, violation_cap: int = DEFAULT_VIOLATION_CAP, require: Sequence[str] = ()
) -> str:
    """The JSON report as text (indented, ending in a newline)."""
    import json  # here: ``check``'s text report loads this module for its constants only

    data = report_dict(report, violation_cap, require)
    return json.dumps(data, indent=2, ensure_ascii=False) + "\n"
