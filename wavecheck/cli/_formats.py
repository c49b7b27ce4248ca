"""The report formats of ``--format`` (``check``, ``watch``): one record per format, and nothing
else branches on the format.

Each :class:`ReportFormat` gives the document of one capture (:attr:`~ReportFormat.render`), a
capture's piece of the document of several, rendered where the capture was checked (a worker
process; :attr:`~ReportFormat.piece`), and the document of several joined from those pieces in
input order (:attr:`~ReportFormat.join`). A new format is one more entry in :data:`FORMATS`.
"""

from __future__ import annotations

import argparse
import itertools
import json
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Any

from wavecheck.cli._axis_args import required
from wavecheck.engine import MachineReport, Report
from wavecheck.report.json import DEFAULT_VIOLATION_CAP, report_dict
from wavecheck.report.machine import machine_dict, render_machine_text
from wavecheck.report.text import DEFAULT_TEXT_VIOLATIONS, render_text
from wavecheck.verdict import overall_verdict

__all__ = ["FORMATS", "Checked", "Part", "ReportFormat", "axis_reports"]

Checked = Report | MachineReport
"""What one capture gives: a report, or one per axis."""

#: JUnit's counts of a piece: tests, failures, errors, skipped.
Counts = tuple[int, int, int, int]

#: A report's indentation inside ``{"reports": [ … ]}`` (json.dumps with indent=2).
_NESTED = " " * 4


def axis_reports(checked: Checked) -> list[Report]:
    """The reports of ``checked``: its axes, or itself."""
    return checked.axes if isinstance(checked, MachineReport) else [checked]


@dataclass(frozen=True)
class Part:
    """One capture of several as their document needs it: its summary line, verdict, JUnit
    counts and its piece, read back (from the spool) only when the document is written."""

    path: str
    summary: str
    verdict: str | None
    counts: Counts | None
    text: Callable[[], str]


@dataclass(frozen=True)
class ReportFormat:
    """One ``--format``.

    Attributes:
        render: the document of one capture.
        piece: one capture's piece of the document of several, and (JUnit) its counts.
        join: the document of several, in pieces: the captures checked (in input order), the
            ones that could not be (path, error), the summary lines of those, the exit code.
    """

    render: Callable[[Checked, argparse.Namespace], str]
    piece: Callable[[Checked, argparse.Namespace], tuple[str, Counts | None]]
    join: Callable[[list[Part], list[tuple[str, str]], list[str], int], Iterator[str]]


# -- text ------------------------------------------------------------------------------------------
def render_text_report(report: Checked, args: argparse.Namespace) -> str:
    """The text report (``--max-violations`` listed)."""
    cap = DEFAULT_TEXT_VIOLATIONS if args.max_violations is None else args.max_violations
    if isinstance(report, MachineReport):
        return render_machine_text(report, cap, required(args))
    return render_text(report, cap, required(args))


def _text_piece(checked: Checked, args: argparse.Namespace) -> tuple[str, Counts | None]:
    return render_text_report(checked, args), None


def _text_join(
    ok: list[Part], errors: list[tuple[str, str]], error_lines: list[str], code: int
) -> Iterator[str]:
    for k, part in enumerate(ok):
        yield ("\n" if k else "") + f"== {part.path} ==\n" + part.text()
    summary = [part.summary for part in ok] + error_lines
    yield "\n== summary ==\n" + "\n".join(summary) + "\n"


# -- JSON ------------------------------------------------------------------------------------------
def _dict(report: Checked, args: argparse.Namespace) -> dict[str, Any]:
    cap = DEFAULT_VIOLATION_CAP if args.max_violations is None else args.max_violations
    if isinstance(report, MachineReport):
        return machine_dict(report, cap, required(args))
    return report_dict(report, cap, required(args))


def render_json_report(report: Checked, args: argparse.Namespace) -> str:
    """The JSON report (``--max-violations`` listed)."""
    return json.dumps(_dict(report, args), indent=2, ensure_ascii=False) + "\n"


def _json_piece(checked: Checked, args: argparse.Namespace) -> tuple[str, Counts | None]:
    """Rendered where the capture was checked, nested in ``"reports": [ … ]``."""
    text = json.dumps(_dict(checked, args), indent=2, ensure_ascii=False)
    return text.replace("\n", "\n" + _NESTED), None


def _json_join(
    ok: list[Part], errors: list[tuple[str, str]], error_lines: list[str], code: int
) -> Iterator[str]:
    verdict: str = overall_verdict([str(p.verdict) for p in ok]) if ok else "unchecked"  # type: ignore[arg-type]
    if errors:
        verdict = "error"
    doc = {
        "reports": [],
        "errors": [{"path": p, "error": e} for p, e in errors],
        "verdict": verdict,
        "exit_code": code,
    }
    text = json.dumps(doc, indent=2, ensure_ascii=False) + "\n"
    if not ok:
        yield text
        return
    # each report was rendered by its worker: json.dumps's own layout, spliced in
    head, _, foot = text.partition('"reports": []')
    yield f'{head}"reports": [\n{_NESTED}'
    for k, part in enumerate(ok):
        yield part.text() if k == 0 else f",\n{_NESTED}" + part.text()
    yield "\n  ]" + foot


# -- JUnit -----------------------------------------------------------------------------------------
def render_junit_report(report: Checked, args: argparse.Namespace) -> str:
    """JUnit XML of one capture (a testsuite per axis)."""
    from wavecheck.report.junit import render_junit

    return render_junit(axis_reports(report), require=required(args))


def _junit_piece(checked: Checked, args: argparse.Namespace) -> tuple[str, Counts | None]:
    from wavecheck.report.junit import render_suites

    suites = render_suites(axis_reports(checked), require=required(args))
    return suites.text, suites.counts


def _junit_join(
    ok: list[Part], errors: list[tuple[str, str]], error_lines: list[str], code: int
) -> Iterator[str]:
    from wavecheck.report.junit import Unreadable, join_suites, render_suites

    unreadable = render_suites(errors=[Unreadable(p, e) for p, e in errors])
    counts = [p.counts for p in ok if p.counts is not None] + [unreadable.counts]
    pieces = (p.text() for p in ok)
    yield from join_suites(
        itertools.chain(pieces, [unreadable.text] if errors else []),
        [sum(c[k] for c in counts) for k in range(4)],
    )


#: ``--format`` name → its format.
FORMATS: dict[str, ReportFormat] = {
    "text": ReportFormat(render_text_report, _text_piece, _text_join),
    "json": ReportFormat(render_json_report, _json_piece, _json_join),
    "junit": ReportFormat(render_junit_report, _junit_piece, _junit_join),
}
