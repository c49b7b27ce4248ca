"""``stepgen plan``'s outputs: text for people, JSON, and INI/HAL snippets to paste."""

from __future__ import annotations

import json
import math
from fractions import Fraction
from typing import Any

from stepgen.plan import PARAMS, Plan
from wavecheck.units import exact_ns, format_time, json_number

__all__ = ["plan_to_dict", "render_hal", "render_ini", "render_json", "render_text"]


def _rate(hz: Fraction) -> int:
    """A step rate rounded down to a whole step/s (Stepper Tuning's 16,129 and 38,461)."""
    return math.floor(hz)


def plan_to_dict(p: Plan) -> dict[str, Any]:
    """The JSON document of a plan (keys are a public contract, see ``stepgen plan --help``)."""
    return {
        "drive": {"id": p.drive.id, "name": p.drive.name, "active_edge": p.drive.active_edge},
        "latency": {"ns": json_number(p.latency_ns), "source": p.latency_source},
        "step_inverted": p.step_inverted,
        "active_edge_at": p.active_at,
        "min_base_period_ns": math.ceil(p.min_base_period_ns),
        "min_base_period_step_rate_hz": _rate(p.min_base_period_rate_hz),
        "simple_base_period_ns": math.ceil(p.simple_base_period_ns),
        "simple_base_period_step_rate_hz": _rate(p.simple_base_period_rate_hz),
        "base_period_ns": p.base_period_ns,
        "base_period_given": p.base_period_given,
        "params": {
            name: {"ns": prm.ns, "periods": prm.periods, "reason": prm.reason}
            for name, prm in p.params.items()
        },
        "max_step_rate_hz": _rate(p.max_step_rate_hz),
        "margins_ns": {rule: json_number(m) for rule, m in p.margins_ns.items()},
        "requirements": [
            {
                "rule": r.rule,
                "what": r.what,
                "limit_ns": json_number(r.limit_ns),
                "formula": r.formula,
                "periods": r.periods,
                "worst_ns": json_number(r.worst_ns),
                "margin_ns": json_number(r.margin_ns),
            }
            for r in p.requirements
        ],
        "shortest_output_ns": json_number(p.shortest_output_ns),
        "assumptions": list(p.assumptions),
        "guidance": p.guidance,
        "warnings": list(p.warnings),
    }


def render_json(p: Plan) -> str:
    """The plan as indented JSON (with a trailing newline)."""
    return json.dumps(plan_to_dict(p), indent=2, ensure_ascii=False) + "\n"


def _us(ns: Fraction | int) -> str:
    return format_time(Fraction(ns) / 10**9)


def render_text(p: Plan, other: Plan | None = None) -> str:
    """The plan for people: figures, the parameters, rates, margins, assumptions, warnings.

    ``other``: the same plan under the other STEP-pin reading, summarised in one line.
    """
    d = p.drive
    lines = [
        f"stepgen plan for {d.name} ({d.id}), latency J = {_us(p.latency_ns)} ({p.latency_source or 'given'})",
        f"  {p.guidance}",
        "",
        f"minimum BASE_PERIOD  {exact_ns(p.min_base_period_ns):>8} ns  = J + longer of step high/low "
        f"-> max {_rate(p.min_base_period_rate_hz):,} steps/s",
        f"simple BASE_PERIOD   {exact_ns(p.simple_base_period_ns):>8} ns  = J + longest requirement "
        f"-> max {_rate(p.simple_base_period_rate_hz):,} steps/s",
        f"chosen BASE_PERIOD   {p.base_period_ns:>8} ns  "
        + ("(given)" if p.base_period_given else "(the minimum rounded up to a whole us)"),
        "",
        "parameter  periods        ns  why",
    ]
    for prm in p.params.values():
        lines.append(f"{prm.name:<10} {prm.periods:>7} {prm.ns:>9}  {prm.reason}")
    lines += [
        "",
        f"max step rate {_rate(p.max_step_rate_hz):,} steps/s = 1 / ((steplen + stepspace)·P) "
        f"= 1 / ({p.step_periods} x {p.base_period_ns} ns)",
    ]
    pin = "inverted" if p.step_inverted else "not inverted"
    lines.append(
        f"(these figures assume the STEP pin {pin}: the drive's {d.active_edge} edge is the "
        f"{p.active_at} of stepgen's pulse)"
    )
    if other is not None:
        alt = ", ".join(f"{prm.name} {prm.periods}" for prm in other.params.values())
        flag = "with --invert-step" if other.step_inverted else "without --invert-step"
        lines.append(
            f"(the other reading, {flag}: {alt} -> {_rate(other.max_step_rate_hz):,} steps/s)"
        )
    lines += [
        "",
        f"{'requirement':<13} {'interval':<42} {'formula':<36} {'worst':>8} {'limit':>8} "
        f"{'margin':>9} (ns)",
    ]
    for r in p.requirements:
        lines.append(
            f"{r.rule:<13} {r.what:<42} {r.formula:<36} {exact_ns(r.worst_ns):>8} {exact_ns(r.limit_ns):>8} "
            f"{exact_ns(r.margin_ns):>9}"
        )
    changed = _changed(p, "  ")
    if changed:
        lines += ["", "figures changed on the command line (the table uses them):", *changed]
    lines += ["", "assumptions:"] + [f"  - {a}" for a in p.assumptions]
    if p.warnings:
        lines += ["", "warnings:"] + [f"  ! {w}" for w in p.warnings]
    return "\n".join(lines) + "\n"


def _changed(p: Plan, lead: str) -> list[str]:
    """The drive's figures ``--limit``/``--margin`` changed, each beside its datasheet figure."""
    figures = [(rule, fig) for rule, fig in p.drive.limits.items() if fig.applied]
    rate = p.drive.max_rate
    out = [
        f"{lead}{rule}: {exact_ns(fig.value)} ns applied ({fig.applied}); datasheet "
        + ("none" if fig.datasheet is None else f"{exact_ns(fig.datasheet)} ns")
        for rule, fig in figures
    ]
    if rate is not None and rate.applied:
        out.append(
            f"{lead}max_rate: {_rate(rate.value):,} steps/s applied ({rate.applied}); datasheet "
            + ("none" if rate.datasheet is None else f"{_rate(rate.datasheet):,} steps/s")
        )
    return out


def _header(p: Plan, comment: str) -> list[str]:
    pin = "INVERTED" if p.step_inverted else "not inverted"
    return [
        f"{comment} stepgen plan: {p.drive.name} ({p.drive.id}), latency {_us(p.latency_ns)}"
        f" ({p.latency_source or 'given'})",
        f"{comment} assumes the STEP pin {pin}: the drive's {p.drive.active_edge} (active) edge is "
        f"the {p.active_at} of stepgen's pulse",
        f"{comment} max step rate {_rate(p.max_step_rate_hz)} steps/s; shortest output time "
        f"{exact_ns(p.shortest_output_ns)} ns under worst latency",
        *_changed(p, f"{comment} "),
    ]


def render_ini(p: Plan, channel: int = 0) -> str:
    """An INI snippet: ``[EMCMOT] BASE_PERIOD`` and StepConf-style ``[JOINT_N]`` timing keys."""
    lines = _header(p, "#")
    lines += ["[EMCMOT]", f"BASE_PERIOD = {p.base_period_ns}", "", f"[JOINT_{channel}]"]
    for name in PARAMS:
        lines.append(f"{name.upper()} = {p.params[name].ns}")
    return "\n".join(lines) + "\n"


def render_hal(p: Plan, channel: int = 0) -> str:
    """A HAL snippet: the ``setp stepgen.N.*`` lines (BASE_PERIOD is stated in a comment)."""
    lines = _header(p, "#")
    lines.append(f"# BASE_PERIOD = {p.base_period_ns} ns ([EMCMOT] in the INI file)")
    if p.step_inverted:
        lines.append("# invert the STEP output pin, e.g. setp parport.0.pin-02-out-invert 1")
    for name in PARAMS:
        lines.append(f"setp stepgen.{channel}.{name} {p.params[name].ns}")
    return "\n".join(lines) + "\n"
