"""Text and JSON of ``wavecheck config`` (one shape for every firmware) and of the ``firmware``
section of ``check --firmware``."""

from __future__ import annotations

from collections.abc import Sequence
from fractions import Fraction
from typing import Any

from wavecheck.drives.datasheet import Figure
from wavecheck.firmware.capture import FirmwareCheck
from wavecheck.firmware.evaluate import ConfigResult, PairRow
from wavecheck.firmware.guarantee import GeneratorGuarantee, Guaranteed
from wavecheck.rules import rule
from wavecheck.units import format_ns, format_rate, json_number
from wavecheck.verdict import Unmet, required_exit_code, required_line, unmet_requirements

__all__ = [
    "config_dict",
    "config_junit",
    "config_text",
    "firmware_check_dict",
    "firmware_check_lines",
    "guaranteed_dict",
]

_MARK = {"uncertain": "?", "not_enforced": "!", "default": "*", "unknown": ""}


def _mark(fig: Guaranteed) -> str:
    """The figure's status mark; ``?`` too when the firmware may fall short of it (a band)."""
    mark = _MARK.get(fig.status, "")
    return mark + ("?" if fig.banded and "?" not in mark else "")


def _g(fig: Guaranteed | None, rate: bool = False) -> str:
    if fig is None or fig.value is None:
        return "unknown"
    text = format_rate(fig.value) if rate else format_ns(fig.value)
    return text + _mark(fig)


def _limit(fig: Figure | None, ns: Fraction | None) -> str:
    if ns is None:
        return "-"
    text = format_ns(ns) + (fig.mark if fig else "")
    if fig is not None and fig.datasheet is not None:
        text += f" (datasheet {format_ns(fig.datasheet)}, {fig.applied})"
    return text


def _axis_head(a: GeneratorGuarantee) -> str:
    level = "high" if a.pulse_level else "low"
    edges = "every edge is a step" if a.both_edges else f"{a.leading_edge} edge starts a pulse"
    return f"axis {a.axis}: pulses {level} at the pin, {edges}"


def config_text(result: ConfigResult, require: Sequence[str] = ()) -> str:
    """The text report of ``wavecheck config`` (``require``: ``--require``)."""
    cfg, results = result.config, result.pairs
    out = [f"{cfg.firmware} configuration {cfg.path}"]
    out += [f"  read: {f}" for f in cfg.files if f != cfg.path]
    out += [f"  note: {n}" for n in cfg.notes]
    out += [f"  not modelled: {u}" for u in cfg.unsupported]
    for res in results:
        a = res.axis
        out += ["", f"{_axis_head(a)}; drive {res.drive.id} ({res.drive.active_edge} edge)"]
        out += [f"  {k}: {v}" for k, v in a.info.items()]
        rows = [["rule", "generator", "limit", "margin", "verdict", "from"]]
        for r in res.rows:
            rate = rule(r.rule).figure == "max_rate"
            gen = (
                "-"
                if r.source is None
                else (
                    _g(r.source, rate=True)
                    if rate
                    else (
                        format_ns(r.guaranteed_ns) + _mark(r.source)
                        if r.guaranteed_ns is not None
                        else "unknown"
                    )
                )
            )
            lim = (
                (format_rate(r.limit.value) + r.limit.mark if r.limit else "-")
                if rate
                else _limit(r.limit, r.limit_ns)
            )
            where = (
                f"{r.source.setting} ({r.source.where})"
                if r.source is not None and r.source.where
                else (r.source.setting if r.source else "")
            )
            rows.append(
                [r.rule, gen, lim, format_ns(r.margin_ns, signed=True), r.verdict.upper(), where]
            )
        widths = [max(len(row[i]) for row in rows) for i in range(len(rows[0]))]
        out += [
            "  " + "  ".join(c.ljust(w) for c, w in zip(row, widths, strict=True)).rstrip()
            for row in rows
        ]
        out.append(f"  max step rate this pair allows: {format_rate(res.max_rate_hz)}")
        for r in res.rows:
            if r.fix:
                out.append(f"  fix {r.rule}: {r.fix}")
            if r.verdict == "indeterminate" or (r.note and r.verdict != "unchecked"):
                out.append(f"  {r.rule}: {r.note}")
        out += [f"  note: {n}" for n in res.notes]
    out += [
        "",
        "* = firmware default, ? = the firmware may fall short of it (the note says by how "
        "much), ! = not enforced by the firmware (measure it)",
        f"verdict: {result.verdict_line}",
    ]
    unmet = unmet_requirements(result.statuses, require)
    out += [line for line in [required_line(unmet, result.statuses)] if line]
    return "\n".join(out) + "\n"


def guaranteed_dict(fig: Guaranteed | None) -> dict[str, Any] | None:
    """A guaranteed figure as JSON. ``short_by``: how far the wire figure may fall below
    ``value`` (its unit; for a max rate, Hz above it), 0 when kept exactly, null with
    ``short_bounded`` false when no source bounds it; ``short_why`` says why, with the firmware
    line."""
    if fig is None:
        return None
    return {
        "value": json_number(fig.value),
        "setting": fig.setting,
        "where": fig.where,
        "unit": fig.unit,
        "status": fig.status,
        "note": fig.note,
        "disputed": json_number(fig.disputed),
        "short_by": json_number(fig.short_by),
        "short_bounded": fig.short_by is not None,
        "short_why": fig.short_why,
    }


def _axis_dict(a: GeneratorGuarantee) -> dict[str, Any]:
    return {
        "axis": a.axis,
        "aliases": list(a.aliases),
        "pulse_level": a.pulse_level,
        "active_edge": a.active_edge,
        "both_edges": a.both_edges,
        "dir_inverted": a.dir_inverted,
        "step_high_ns": guaranteed_dict(a.step_high),
        "step_low_ns": guaranteed_dict(a.step_low),
        "pulse_ns": guaranteed_dict(a.pulse),
        "idle_ns": guaranteed_dict(a.idle),
        "dir_setup_ns": guaranteed_dict(a.dir_setup),
        "dir_hold_ns": guaranteed_dict(a.dir_hold),
        "dir_hold_trailing_ns": guaranteed_dict(a.dir_hold_trailing),
        "dir_setup_trailing_ns": guaranteed_dict(a.dir_setup_trailing),
        "max_rate_hz": guaranteed_dict(a.max_rate),
        "info": dict(a.info),
        "notes": list(a.notes),
    }


def config_dict(result: ConfigResult, require: Sequence[str] = ()) -> dict[str, Any]:
    """The JSON report of ``wavecheck config`` (``require``: ``--require``)."""
    from wavecheck.report.claims import required_dict

    cfg, results = result.config, result.pairs
    unmet = unmet_requirements(result.statuses, require)
    return {
        "firmware": cfg.firmware,
        "path": cfg.path,
        "files": list(cfg.files),
        "notes": list(cfg.notes),
        "unsupported": list(cfg.unsupported),
        "axes": [_axis_dict(a) for a in cfg.axes],
        "pairs": [
            {
                "axis": res.axis.axis,
                "drive": res.drive.id,
                "verdict": res.verdict,
                "max_rate_hz": json_number(res.max_rate_hz),
                "notes": list(res.notes),
                "rules": [
                    {
                        "rule": r.rule,
                        "generator_ns": json_number(r.guaranteed_ns),
                        "generator": guaranteed_dict(r.source),
                        "limit_ns": json_number(r.limit_ns),
                        "limit_status": r.limit.status if r.limit else None,
                        "limit_datasheet_ns": json_number(
                            rule(r.rule).limit_ns(r.limit.datasheet)
                            if r.limit is not None and r.limit.datasheet is not None
                            else None
                        ),
                        "margin_ns": json_number(r.margin_ns),
                        "worst_ns": json_number(r.worst_ns),
                        "short_by_ns": json_number(
                            r.guaranteed_ns - r.worst_ns
                            if r.guaranteed_ns is not None and r.worst_ns is not None
                            else None
                        ),
                        "in_band": r.in_band,
                        "verdict": r.verdict,
                        "fix": r.fix,
                        "note": r.note,
                        "why_unchecked": r.why_unchecked,
                    }
                    for r in res.rows
                ],
            }
            for res in results
        ],
        "verdict": result.verdict,
        "verdict_line": result.verdict_line,
        "unchecked": [
            {"why": why, "rules": list(rules)} for why, rules in result.unchecked.items()
        ],
        "unchecked_axes": [
            {"why": why, "axes": list(axes)} for why, axes in result.config.unchecked_axes
        ],
        "required": required_dict(require, unmet),
        "exit_code": required_exit_code(result.exit_code, unmet),
    }


def _junit_case(suite: Any, classname: str, row: PairRow, unmet: Unmet | None) -> str:
    """One rule as a JUnit test case (the conventions of :mod:`wavecheck.report.junit`)."""
    import xml.etree.ElementTree as ET

    from wavecheck.report.junit import required_failure

    case = ET.SubElement(suite, "testcase", classname=classname, name=row.rule, time="0")
    if unmet is not None:
        return required_failure(case, unmet)
    lim = format_ns(row.limit_ns)
    gen = format_ns(row.guaranteed_ns, missing="unknown")
    if row.verdict in ("fail", "indeterminate"):
        what = "fails" if row.verdict == "fail" else "cannot be proven"
        el = ET.SubElement(case, "failure", type=row.verdict,
                           message=f"{row.rule} {what}: generator {gen}, limit {lim}")  # fmt: skip
        el.text = "\n".join(x for x in (row.note, f"fix: {row.fix}" if row.fix else "") if x)
        return "failure"
    if row.verdict == "unchecked":
        ET.SubElement(case, "skipped", message=row.why_unchecked or row.note or "not checked")
        return "skipped"
    return "pass"


def config_junit(result: ConfigResult, require: Sequence[str] = ()) -> str:
    """JUnit XML of ``wavecheck config``: one ``testsuite`` per axis/drive pair, one
    ``testcase`` per rule (failure: fail or indeterminate, or a required rule not decided;
    skipped: unchecked, with why)."""
    import xml.etree.ElementTree as ET

    from wavecheck.report.junit import classname, required_failure

    unmet = {(u.axis, u.rule): u for u in unmet_requirements(result.statuses, require)}
    root = ET.Element("testsuites", name="wavecheck config")
    base = classname(result.config.path)
    for pair in result.pairs:
        suite = ET.SubElement(root, "testsuite",
                              name=f"{result.config.path} [axis {pair.axis.axis}, drive {pair.drive.id}]")  # fmt: skip
        props = ET.SubElement(suite, "properties")
        for key, value in (("firmware", result.config.firmware), ("drive", pair.drive.id),
                           ("verdict", pair.verdict),
                           ("verdict_line", result.verdict_line)):  # fmt: skip
            ET.SubElement(props, "property", name=key, value=value)
        counts = {"failure": 0, "skipped": 0, "pass": 0}
        for row in pair.rows:
            u = unmet.pop((pair.axis.axis, row.rule), None)
            counts[_junit_case(suite, f"{base}.{pair.axis.axis}", row, u)] += 1
        for axis, rule_id in [k for k in unmet if k[0] == pair.axis.axis]:  # no such rule here
            case = ET.SubElement(suite, "testcase", classname=f"{base}.{axis}",
                                 name=rule_id, time="0")  # fmt: skip
            counts[required_failure(case, unmet.pop((axis, rule_id)))] += 1
        if pair.verdict == "unchecked":  # the command exits 3: the suite must not read as green
            case = ET.SubElement(suite, "testcase", classname=f"{base}.{pair.axis.axis}",
                                 name="verdict", time="0")  # fmt: skip
            ET.SubElement(case, "failure", type="unchecked",
                          message="nothing was checked: the drive states none of the figures")  # fmt: skip
            counts["failure"] += 1
        suite.set("tests", str(sum(counts.values())))
        suite.set("failures", str(counts["failure"]))
        suite.set("errors", "0")
        suite.set("skipped", str(counts["skipped"]))
        suite.set("time", "0")
    for key in ("tests", "failures", "errors", "skipped"):
        root.set(key, str(sum(int(s.get(key, "0")) for s in root)))
    root.set("time", "0")
    ET.indent(root)
    return '<?xml version="1.0" encoding="UTF-8"?>\n' + ET.tostring(root, encoding="unicode") + "\n"


def firmware_check_lines(fc: FirmwareCheck) -> list[str]:
    """The ``firmware`` section of the text report of ``check --firmware``."""
    out = [
        f"firmware: {fc.firmware} {fc.path}, axis {fc.axis.axis} (apart from the drive rules): "
        f"{fc.verdict.upper()}"
    ]
    if fc.pairing:
        out.append(f"  paired: {fc.pairing}")
    for c in fc.comparisons:
        out.append(f"  {c.what:<10} {c.verdict.upper():<13} {c.message}")
    return out


def firmware_check_dict(fc: FirmwareCheck) -> dict[str, Any]:
    """The ``firmware`` section of the JSON report of ``check --firmware``."""
    return {
        "firmware": fc.firmware,
        "path": fc.path,
        "axis": fc.axis.axis,
        "pairing": fc.pairing,
        "verdict": fc.verdict,
        "findings": sum(c.verdict == "fail" for c in fc.comparisons),
        "comparisons": [
            {
                "what": c.what,
                "rule": c.rule,
                "configured": json_number(c.configured),
                "measured": json_number(c.measured),
                "unit": c.unit,
                "at_s": json_number(c.at_s),
                "setting": c.setting,
                "where": c.where,
                "verdict": c.verdict,
                "message": c.message,
                "short_by": json_number(c.short_by),
                "short_bounded": c.short_by is not None,
            }
            for c in fc.comparisons
        ],
    }
