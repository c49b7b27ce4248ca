"""JUnit XML for CI systems: one ``testsuite`` per capture, one ``testcase`` per rule.

The layout is the one Jenkins, GitLab, GitHub Actions reporters and Azure read (the Ant/Jenkins
"junit-10" schema): ``<testsuites>`` → ``<testsuite name tests failures errors skipped time>``
→ ``<testcase classname name time>`` with at most one ``<failure message type>``, ``<error>`` or
``<skipped message>`` child.

- ``classname`` is the capture (its path without the extension, so CI tools that split class
  names at dots do not take ``.vcd`` for a class), ``name`` the rule id.
- A failing rule is a ``<failure type="fail">`` whose message is the worst violation (measured,
  limit, margin, time); the element's text lists the first few violations.
- An unchecked rule (no interval of its kind in the capture, no channel for it: the message says
  why) and a rule the drive states no limit for are ``<skipped>``.
- **Indeterminate is a failure** (``type="indeterminate"``): the capture cannot show that the
  rule is met, and ``wavecheck check`` exits non-zero (3) for it; reporting it as skipped would
  show a green dashboard for a red job. The message says which sample rate would decide it.
- A rule the run requires (``--require``) that is unchecked or indeterminate is a
  ``<failure type="required">`` saying why (the command exits 4), also when the drive states no
  figure for it or the step type has no such rule (a test case of its own).
- The suite's properties carry ``verdict`` and ``verdict_line``, which names the rules not
  checked and why (``PASS (dir_setup, dir_hold not checked: no DIR channel)``).
- A capture that could not be read at all is one ``<testcase name="read">`` with an ``<error>``.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from collections.abc import Iterable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import PurePath

from wavecheck.engine import Report, RuleResult, Violation
from wavecheck.report import claims
from wavecheck.units import format_frequency, format_ns
from wavecheck.verdict import Unmet

__all__ = [
    "Suites",
    "Unreadable",
    "classname",
    "join_suites",
    "render_junit",
    "render_suites",
    "required_failure",
]

_LISTED = 10


@dataclass(frozen=True)
class Unreadable:
    """A capture that could not be checked (its path and the one-line error)."""

    path: str
    message: str


def classname(path: str) -> str:
    """The JUnit class name of a capture: its path without the file extension."""
    p = PurePath(path)
    return str(p.with_suffix("")) if p.suffix else str(p)


def _classname(report: Report) -> str:
    """:func:`classname`, with ``.AXIS`` for one axis of several."""
    return classname(report.capture.path) + (f".{report.axis}" if report.axis is not None else "")


def _describe(v: Violation) -> str:
    if v.margin_ns is None:
        return f"{v.rule} at {float(v.time_s):.9f} s: {v.detail or 'state sequence error'}"
    sign = "+" if v.margin_ns > 0 else ""
    return (
        f"{v.rule} at {float(v.time_s):.9f} s: measured {format_ns(v.measured_ns)}, limit "
        f"{format_ns(v.limit_ns)} (margin {sign}{format_ns(v.margin_ns)})"
    )


def required_failure(case: ET.Element, u: Unmet) -> str:
    """Mark ``case`` as a required rule that was not decided (``--require``)."""
    ET.SubElement(
        case,
        "failure",
        message=f"required but {u.said}: {u.why}",
        type="required",
    )
    return "failure"


def _testcase(suite: ET.Element, report: Report, r: RuleResult, why: str, u: Unmet | None) -> str:
    case = ET.SubElement(suite, "testcase", classname=_classname(report), name=r.rule, time="0")
    if u is not None:
        return required_failure(case, u)
    if r.verdict == "fail":
        worst = r.worst_violations(_LISTED)
        el = ET.SubElement(
            case,
            "failure",
            message=f"{r.violations} violation(s); worst: {_describe(worst[0])}",
            type="fail",
        )
        lines = [_describe(v) for v in worst]
        if r.violations > len(worst):
            lines.append(f"... and {r.violations - len(worst)} more")
        el.text = "\n".join(lines)
        return "failure"
    if r.verdict == "indeterminate":
        hz = r.decide_samplerate_hz
        how = f"; sampling faster than {format_frequency(hz)} would decide it" if hz else ""
        ET.SubElement(
            case,
            "failure",
            message=f"{r.indeterminate} interval(s) cannot be decided at a resolution of "
            f"{format_ns(r.resolution_ns)} (limit {format_ns(r.limit_ns)}){how}",
            type="indeterminate",
        )
        return "failure"
    if r.verdict == "unchecked":
        ET.SubElement(case, "skipped", message=f"{r.rule} not checked: {why}")
        return "skipped"
    return "pass"


def _rate_properties(report: Report) -> list[tuple[str, str]]:
    """``max_step_rate_hz.<name>`` for every max step rate the report has (exact Hz, 6 digits)."""
    named = report.rates.named().items()
    return [(f"max_step_rate_hz.{k}", f"{float(v):.6g}") for k, v in named if v is not None]


def _suite(root: ET.Element, report: Report, require: Sequence[str]) -> None:
    name = report.capture.path + (f" [axis {report.axis}]" if report.axis is not None else "")
    suite = ET.SubElement(root, "testsuite", name=name)
    props = ET.SubElement(suite, "properties")
    unmet = {u.rule: u for u in claims.unmet(report, require)}
    why = {s.rule: s.why for s in claims.rule_statuses(report)}
    for key, value in (
        ("drive", report.drive.id),
        ("verdict", report.verdict),
        ("verdict_line", claims.verdict_line(report)),
        ("steps", str(report.steps.count)),
        ("step_type", str(report.step_type.number)),
        *_rate_properties(report),
    ):
        ET.SubElement(props, "property", name=key, value=value)
    counts = {"failure": 0, "skipped": 0, "pass": 0}
    for r in report.rules:
        counts[_testcase(suite, report, r, why[r.rule], unmet.pop(r.rule, None))] += 1
    for rule in report.not_stated:
        case = ET.SubElement(suite, "testcase", classname=_classname(report), name=rule, time="0")
        if rule in unmet:
            counts[required_failure(case, unmet.pop(rule))] += 1
            continue
        ET.SubElement(case, "skipped", message=f"drive {report.drive.id} states no {rule} limit")
        counts["skipped"] += 1
    for rule, u in unmet.items():  # required, but the step type has no such rule
        case = ET.SubElement(suite, "testcase", classname=_classname(report), name=rule, time="0")
        counts[required_failure(case, u)] += 1
    if report.verdict == "unchecked":
        # Nothing could be checked: the command exits 3, so the suite must not read as green.
        case = ET.SubElement(
            suite, "testcase", classname=_classname(report), name="verdict", time="0"
        )
        ET.SubElement(
            case,
            "failure",
            message="nothing was checked: no rule found an interval of its kind in the capture "
            "(check the mapping and that the capture holds steps)",
            type="unchecked",
        )
        counts["failure"] += 1
    suite.set("tests", str(sum(counts.values())))
    suite.set("failures", str(counts["failure"]))
    suite.set("errors", "0")
    suite.set("skipped", str(counts["skipped"]))
    suite.set("time", "0")


def _error_suite(root: ET.Element, err: Unreadable) -> None:
    suite = ET.SubElement(
        root, "testsuite", name=err.path, tests="1", failures="0", errors="1", skipped="0", time="0"
    )
    case = ET.SubElement(suite, "testcase", classname=classname(err.path), name="read", time="0")
    ET.SubElement(case, "error", message=err.message, type="unusable input")


def render_junit(
    reports: Sequence[Report],
    errors: Sequence[Unreadable] = (),
    name: str = "wavecheck",
    require: Sequence[str] = (),
) -> str:
    """The JUnit XML document for ``reports`` (and captures that could not be checked);
    ``require``: the rules ``--require`` asks to be decided."""
    root = _root(reports, errors, name, require)
    for key in _COUNTS:
        root.set(key, str(sum(int(s.get(key, "0")) for s in root)))
    root.set("time", "0")
    ET.indent(root)
    return _DECLARATION + ET.tostring(root, encoding="unicode") + "\n"


def _root(
    reports: Sequence[Report],
    errors: Sequence[Unreadable],
    name: str,
    require: Sequence[str] = (),
) -> ET.Element:
    root = ET.Element("testsuites", name=name)
    for report in reports:
        _suite(root, report, require)
    for err in errors:
        _error_suite(root, err)
    return root


_DECLARATION = '<?xml version="1.0" encoding="UTF-8"?>\n'
_COUNTS = ("tests", "failures", "errors", "skipped")


@dataclass(frozen=True)
class Suites:
    """The ``testsuite`` elements of some reports as they stand inside :func:`render_junit`'s
    ``<testsuites>`` (indented one level), and their counts (tests, failures, errors, skipped):
    a document of many captures is joined from these (:func:`join_suites`) one by one."""

    text: str
    counts: tuple[int, int, int, int]


def render_suites(
    reports: Sequence[Report] = (),
    errors: Sequence[Unreadable] = (),
    require: Sequence[str] = (),
) -> Suites:
    """:func:`render_junit`'s suites of ``reports`` and ``errors``, to be joined."""
    root = _root(reports, errors, "", require)
    ET.indent(root)
    for suite in root:
        suite.tail = None
    text = "\n  ".join(ET.tostring(suite, encoding="unicode") for suite in root)
    c = [sum(int(s.get(key, "0")) for s in root) for key in _COUNTS]
    return Suites(text, (c[0], c[1], c[2], c[3]))


def join_suites(
    pieces: Iterable[str], counts: Sequence[int], name: str = "wavecheck"
) -> Iterator[str]:
    """One JUnit document of ``pieces`` (:attr:`Suites.text`, not empty, in order) whose summed
    ``counts`` are given, in pieces: what :func:`render_junit` of their reports gives."""
    root = ET.Element("testsuites", name=name)
    for key, n in zip(_COUNTS, counts, strict=True):
        root.set(key, str(n))
    root.set("time", "0")
    root.text = "\n  "
    ET.SubElement(root, "suites").tail = "\n"
    head, _, foot = ET.tostring(root, encoding="unicode").partition("<suites />")
    yield _DECLARATION + head
    for k, piece in enumerate(pieces):
        yield piece if k == 0 else "\n  " + piece
    yield foot + "\n"
