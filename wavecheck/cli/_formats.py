"""The report formats of ``--format``: one renderer per format, and nothing else branches on
the format.

``check`` and ``watch``: each :class:`ReportFormat` gives the document of one capture
(:attr:`~ReportFormat.render`), a capture's piece of the document of several, rendered where the
capture was checked (a worker process; :attr:`~ReportFormat.piece`), and the document of several
joined from those pieces in input order (:attr:`~ReportFormat.join`). A new format is one more
entry in :data:`FORMATS`.

The other commands (``compare``, ``config``, ``crosscheck``, ``drives``, ``follow``, ``info``,
``latency``, ``measure``) each have a :class:`Formats`: format name → the renderer of the
command's result; it adds ``--format`` and renders the one asked for. :func:`json_text` makes the
JSON renderer of a function giving the document's dictionary, :func:`lazy` a renderer whose
module loads only when a document is rendered (``wavecheck --help`` stays light).
"""

from __future__ import annotations

import argparse
import importlib
import itertools
from collections.abc import Callable, Iterator, Mapping
from typing import TYPE_CHECKING, Any, Generic, ParamSpec, TypeAlias

from wavecheck.cli._tuning_args import required
from wavecheck.record import record

if TYPE_CHECKING:  # the reports load numpy: imported where used (wavecheck drives has none)
    from wavecheck.engine import MachineReport, Report

__all__ = [
    "FORMATS",
    "Checked",
    "Formats",
    "Part",
    "ReportFormat",
    "axis_reports",
    "json_text",
    "lazy",
]

P = ParamSpec("P")

Checked: TypeAlias = "Report | MachineReport"
"""What one capture gives: a report, or one per axis."""

#: JUnit's counts of a piece: tests, failures, errors, skipped.
Counts = tuple[int, int, int, int]

#: A report's indentation inside ``{"reports": [ … ]}`` (json.dumps with indent=2).
_NESTED = " " * 4


def axis_reports(checked: Checked) -> list[Report]:
    """The reports of ``checked``: its axes, or itself."""
    from wavecheck.engine import MachineReport

    return checked.axes if isinstance(checked, MachineReport) else [checked]


@record(frozen=True)
class Part:
    """One capture of several as their document needs it: its summary line, verdict, JUnit
    counts and its piece, read back (from the spool) only when the document is written."""

    path: str
    summary: str
    verdict: str | None
    counts: Counts | None
    text: Callable[[], str]


@record(frozen=True)
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
    from wavecheck.engine import MachineReport
    from wavecheck.report.machine import render_machine_text
    from wavecheck.report.text import DEFAULT_TEXT_VIOLATIONS, render_text

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
    from wavecheck.engine import MachineReport
    from wavecheck.report.json import DEFAULT_VIOLATION_CAP, report_dict
    from wavecheck.report.machine import machine_dict

    cap = DEFAULT_VIOLATION_CAP if args.max_violations is None else args.max_violations
    if isinstance(report, MachineReport):
        return machine_dict(report, cap, required(args))
    return report_dict(report, cap, required(args))


def _dumps(doc: Any) -> str:
    """``doc`` as every JSON report is written (json is imported here: a text run needs none)."""
    import json

    return json.dumps(doc, indent=2, ensure_ascii=False)


def render_json_report(report: Checked, args: argparse.Namespace) -> str:
    """The JSON report (``--max-violations`` listed)."""
    return _dumps(_dict(report, args)) + "\n"


def _json_piece(checked: Checked, args: argparse.Namespace) -> tuple[str, Counts | None]:
    """Rendered where the capture was checked, nested in ``"reports": [ … ]``."""
    text = _dumps(_dict(checked, args))
    return text.replace("\n", "\n" + _NESTED), None


def _json_join(
    ok: list[Part], errors: list[tuple[str, str]], error_lines: list[str], code: int
) -> Iterator[str]:
    from wavecheck.verdict import overall_verdict

    verdict: str = overall_verdict([str(p.verdict) for p in ok]) if ok else "unchecked"  # type: ignore[arg-type]
    if errors:
        verdict = "error"
    doc = {
        "reports": [],
        "errors": [{"path": p, "error": e} for p, e in errors],
        "verdict": verdict,
        "exit_code": code,
    }
    text = _dumps(doc) + "\n"
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


# -- the other commands ----------------------------------------------------------------------------
@record(frozen=True)
class Formats(Generic[P]):
    """The ``--format`` of a command: format name → the renderer of its result (the first is
    the default)."""

    renderers: Mapping[str, Callable[P, str]]
    help: str = "report format"

    def add_argument(self, p: Any) -> None:
        """Add ``--format`` (its choices: the formats, in order) to ``p``."""
        names = tuple(self.renderers)
        p.add_argument("--format", choices=names, default=names[0], help=self.help)

    def render(self, name: str, *args: P.args, **kwargs: P.kwargs) -> str:
        """The document in format ``name``."""
        return self.renderers[name](*args, **kwargs)


def json_text(doc: Callable[P, Any]) -> Callable[P, str]:
    """The JSON renderer of ``doc`` (the document's dictionary): indented, characters kept."""

    def render(*args: P.args, **kwargs: P.kwargs) -> str:
        return _dumps(doc(*args, **kwargs)) + "\n"

    return render


def lazy(module: str, name: str) -> Callable[..., Any]:
    """``module.name``, imported when first called (a renderer of a heavy module)."""

    def call(*args: Any, **kwargs: Any) -> Any:
        return getattr(importlib.import_module(module), name)(*args, **kwargs)

    return call
