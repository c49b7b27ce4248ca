"""``wavecheck check`` on several captures (``wavecheck check a.sr b.vcd 'runs/*.sr' -j N``).

Each is checked on its own, spread over N worker processes (default: the usable cores); a capture that cannot be read is
reported (one line on stderr) and the others go on. Each summary line prints as its capture
finishes (stdout with ``-o``, else stderr when it is a terminal). Per capture only its summary
line is kept in memory, its piece of the document in a temporary file, never the report (figures
and GTKWave files are written as each capture is checked), so memory does not grow with the
number of captures. The document lists the captures in input order: stdout gets each text
report and then one summary line per capture; the exit code is the worst one
(2 unusable > 1 fail > 3 indeterminate > 0 pass). JSON becomes ``{"reports": [...], "errors":
[...], "verdict", "exit_code"}``; JUnit has one ``testsuite`` per capture; the HTML page a section
per capture; ``--plot``/``--gtkw`` write one file per capture, named ``FILE-<capture stem>.png``.
One capture keeps the single-report behaviour and output shapes exactly.
"""

from __future__ import annotations

import argparse
import functools
import os
import sys
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

from wavecheck.cli._formats import FORMATS, Checked, Part, axis_reports
from wavecheck.cli._main import glob_matches
from wavecheck.cli._reports import Asked, asked
from wavecheck.cli._tuning_args import required
from wavecheck.engine import MachineReport, Report
from wavecheck.errors import UsageError, WavecheckError
from wavecheck.output import atomic_write, figure_format
from wavecheck.progress import activate
from wavecheck.record import record
from wavecheck.report.claims import exit_code, not_checked, requirement_line
from wavecheck.report.text import DEFAULT_TEXT_VIOLATIONS
from wavecheck.units import format_time
from wavecheck.verdict import worst_exit_code

__all__ = ["Builder", "expand_captures", "run_checks", "summary_line"]

Builder = Callable[[argparse.Namespace, Asked, str], Checked]
"""Checks one capture (the path) as the arguments and what they ask say."""


def expand_captures(patterns: list[str]) -> list[str]:
    """Capture paths from the command line: existing files as given, glob patterns expanded
    (sorted); a pattern matching nothing is an error."""
    out: list[str] = []
    for pat in patterns:
        matches = None if os.path.exists(pat) else glob_matches(pat)
        if matches is not None:
            hits = sorted(matches)
            if not hits:
                raise UsageError(f"{pat}: no file matches this pattern")
            out += hits
        else:
            out.append(pat)
    return out


def summary_line(checked: Checked, require: tuple[str, ...] = ()) -> str:
    """One line: verdict, capture, violations, steps (per axis), the worst rule, the rules not
    checked and why, and the required rules not decided (``--require``)."""
    tail = "".join(
        f"; {x}" for x in (not_checked(checked), requirement_line(checked, require)) if x
    )
    if isinstance(checked, MachineReport):
        steps = ", ".join(f"{r.axis} {r.steps.count}" for r in checked.axes)
        return (
            f"{checked.verdict.upper():<13} {checked.capture.path}: {checked.total_violations} "
            f"violation(s), steps {steps}{tail}"
        )
    report = checked
    worst = ""
    margins = [(r.min_margin_ns, r.rule) for r in report.rules if r.min_margin_ns is not None]
    if margins:
        m, rule = min(margins)
        sign = "+" if m > 0 else ""
        worst = f"; closest {rule} {sign}{format_time(m / 10**9)}"
    return (
        f"{report.verdict.upper():<13} {report.capture.path}: {report.total_violations} "
        f"violation(s), {report.steps.count} steps{worst}{tail}"
    )


def _per_capture(path: str, capture: str, stems: dict[str, int]) -> str:
    """``out.png`` → ``out-<capture stem>.png`` (a number added when stems repeat); ``capture``
    may end in ``#AXIS`` for one axis of several (``out-<stem>-<axis>.png``)."""
    p = Path(path)
    capture, _, axis = capture.partition("#")
    stem = Path(capture).stem + (f"-{axis}" if axis else "")
    n = stems.get(stem, 0)
    stems[stem] = n + 1
    tag = stem if n == 0 else f"{stem}-{n + 1}"
    return str(p.with_name(f"{p.stem}-{tag}{p.suffix}"))


def _tagged(r: Report) -> str:
    return r.capture.path if r.axis is None else f"{r.capture.path}#{r.axis}"


class _Spool:
    """Pieces of text in an unnamed temporary file, read back in any order: what the documents
    of many captures keep per capture, so that memory does not grow with their number."""

    def __init__(self) -> None:
        import tempfile

        self._file = tempfile.TemporaryFile()
        self._where: dict[int, tuple[int, int]] = {}

    def put(self, key: int, text: str) -> None:
        data = text.encode("utf-8")
        self._file.seek(0, os.SEEK_END)
        self._where[key] = (self._file.tell(), len(data))
        self._file.write(data)

    def get(self, key: int) -> str:
        at, size = self._where[key]
        self._file.seek(at)
        return self._file.read(size).decode("utf-8")

    def close(self) -> None:
        self._file.close()


class _SideOutputs:
    """``--plot``, ``--gtkw`` and ``--html``, written capture by capture as each is checked (in
    this process, in input order): a capture's figure and GTKWave file at once, and of the HTML
    page its summary row and its section (spooled) until the page is written at the end."""

    def __init__(self, args: argparse.Namespace, several: bool) -> None:
        self.args = args
        self.several = several  # per-capture file names (else several axes of one capture)
        self._stems: dict[str, int] = {}
        self._gstems: dict[str, int] = {}
        self._rows: list[Any] = []  # html.PageRow
        self._sections = _Spool() if args.html else None

    def add(self, checked: Checked) -> None:
        """Write the figures and GTKWave files of ``checked``; keep its HTML section."""
        args = self.args
        reports = axis_reports(checked)
        several = self.several or len(reports) > 1
        for r in reports:
            target = None
            if args.plot:
                target = _per_capture(args.plot, _tagged(r), self._stems) if several else args.plot
            fmt = figure_format(target) if target else "png"
            png = None
            if target or args.html:
                from wavecheck.report.plot import render_png

                if args.html or fmt == "png":  # rendered once, embedded in the HTML page too
                    png = render_png(r)
                if target:
                    data = png if png is not None and fmt == "png" else render_png(r, fmt=fmt)
                    atomic_write(target, data)
            if args.gtkw:
                from wavecheck.report.gtkw import write_gtkw

                gtkw = _per_capture(args.gtkw, _tagged(r), self._gstems) if several else args.gtkw
                _gtkw_written(gtkw, write_gtkw(r, gtkw))
            if self._sections is not None:
                from wavecheck.report.html import PageRow, html_section

                self._rows.append(PageRow.of(r, required(args)))
                cap = (
                    DEFAULT_TEXT_VIOLATIONS if args.max_violations is None else args.max_violations
                )
                section = html_section(r, len(self._rows), png, cap, required(args))
                self._sections.put(len(self._rows), section)

    def finish(self, errors: list[tuple[str, str]]) -> None:
        """Write the HTML page (``errors``: the captures that could not be checked)."""
        if self._sections is None:
            return
        from wavecheck.report.html import html_page

        spool = self._sections
        sections = (spool.get(k) for k in range(1, len(self._rows) + 1))
        try:
            atomic_write(
                self.args.html,
                html_page(
                    self._rows,
                    sections,
                    errors=[f"{p}: {e}" if not e.startswith(p) else e for p, e in errors],
                ),
            )
        finally:
            spool.close()


def _gtkw_written(target: str, vcd: Path | None) -> None:
    """Say so when the GTKWave file's signals went to another VCD than ``STEM.vcd`` (that name
    holds a file wavecheck did not write, which is kept)."""
    if vcd is not None and vcd.name != f"{Path(target).stem}.vcd":
        print(
            f"wavecheck: {Path(target).stem}.vcd is not wavecheck's (kept): {target}: its "
            f"signals are in {vcd}",
            file=sys.stderr,
        )


def _jobs(args: argparse.Namespace, count: int) -> int:
    """Worker processes for ``count`` captures: ``-j N``, default the usable cores; 1 (in this
    process) when per-capture files are asked for (their names follow the input order) or the
    HTML page needs every report."""
    jobs = getattr(args, "jobs", None)
    if jobs is not None and jobs < 1:
        raise UsageError(f"-j/--jobs must be 1 or more, got {jobs}")
    if jobs is None:
        try:
            jobs = len(os.sched_getaffinity(0))
        except AttributeError:  # pragma: no cover - not Linux
            jobs = os.cpu_count() or 1
    if args.plot or args.gtkw or args.html or getattr(args, "steps_csv", None):
        return 1
    return max(1, min(jobs, count))


@record
class _Outcome:
    """What the outputs need of one capture of several (never the report itself, so memory
    does not grow with the number of captures): its summary line, exit code and verdict, and
    the piece of the ``--format`` document (text report, JSON text, or JUnit suites and their
    counts), which the parent spools to a file."""

    index: int
    path: str
    summary: str
    code: int
    verdict: str | None = None
    piece: str = ""
    counts: tuple[int, int, int, int] | None = None  # JUnit's tests, failures, errors, skipped
    error: str | None = None


_WORKER: tuple[argparse.Namespace, Asked, Builder, _SideOutputs | None] | None = None


def _init_worker(
    args: argparse.Namespace, what: Asked, build_report: Builder, side: _SideOutputs | None
) -> None:
    global _WORKER
    _WORKER = (args, what, build_report, side)


def _check_one(index: int, path: str) -> _Outcome:
    """Check one capture of several (in a worker process, or in this one with its side
    outputs)."""
    assert _WORKER is not None
    args, what, build_report, side = _WORKER
    try:
        with activate(f"reading {path}", quiet=args.quiet or side is None, unit="bytes"):
            checked = build_report(args, what, path)
    except WavecheckError as err:
        text = str(err)
        line = f"{'ERROR':<13} {text if text.startswith(path) else f'{path}: {text}'}"
        return _Outcome(index, path, line, err.exit_code, error=text)
    if side is not None:
        side.add(checked)
    piece, counts = FORMATS[args.format].piece(checked, args)
    return _Outcome(
        index,
        path,
        summary_line(checked, required(args)),
        exit_code(checked, required(args)),
        checked.verdict,
        piece,
        counts,
    )


def _outcomes(
    args: argparse.Namespace,
    what: Asked,
    build_report: Builder,
    paths: list[str],
    jobs: int,
    side: _SideOutputs | None = None,
) -> Iterator[_Outcome]:
    """Every capture's outcome, as each finishes (in input order with one job, in this process
    with ``side`` written as each is checked)."""
    if jobs == 1:
        _init_worker(args, what, build_report, side or _SideOutputs(args, several=True))
        for k, path in enumerate(paths):
            yield _check_one(k, path)
        return
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor, as_completed

    methods = multiprocessing.get_all_start_methods()
    context = multiprocessing.get_context("fork" if "fork" in methods else None)
    # a few captures per task: one task per capture costs more in messages than a small
    # capture's check; several tasks per worker keep the load even
    size = max(1, min(_MAX_BATCH, len(paths) // (jobs * 4)))
    batches = [list(range(k, min(k + size, len(paths)))) for k in range(0, len(paths), size)]
    with ProcessPoolExecutor(
        jobs,
        mp_context=context,
        initializer=_init_worker,
        initargs=(args, what, build_report, None),
    ) as pool:
        futures = [pool.submit(_check_batch, [(k, paths[k]) for k in b]) for b in batches]
        for future in as_completed(futures):
            yield from future.result()


#: The most captures a worker checks per task (their summary lines print when the task ends).
_MAX_BATCH = 16


def _check_batch(batch: list[tuple[int, str]]) -> list[_Outcome]:
    return [_check_one(k, path) for k, path in batch]


def run_checks(
    args: argparse.Namespace,
    build_report: Builder,
    write_outputs: Callable[[argparse.Namespace, Checked], None],
) -> int:
    """Check every capture of ``args.capture`` and write every requested output.

    One capture: ``write_outputs`` (the single-report behaviour) and the side outputs; an
    unusable input raises (exit 2). Several: see the module docstring; spread over ``-j``
    worker processes, each summary line printed as its capture finishes (to stdout with ``-o``,
    else to a terminal's stderr), the documents in input order at the end.
    """
    patterns = args.capture if isinstance(args.capture, list) else [args.capture]
    paths = expand_captures(patterns)
    what = asked(args)  # once: a bad option or INI/HAL file before any capture is read
    if len(paths) == 1:
        with activate(f"reading {paths[0]}", quiet=args.quiet, unit="bytes"):
            report = build_report(args, what, paths[0])
        write_outputs(args, report)
        side = _SideOutputs(args, several=False)
        side.add(report)
        side.finish([])
        return exit_code(report, required(args))
    jobs = _jobs(args, len(paths))
    stream = (
        None
        if args.quiet
        else (sys.stdout if args.output else (sys.stderr if sys.stderr.isatty() else None))
    )
    side = _SideOutputs(args, several=True)
    done: list[_Outcome | None] = [None] * len(paths)
    spool = _Spool()
    try:
        for outcome in _outcomes(args, what, build_report, paths, jobs, side):
            if outcome.error is not None:
                print(f"wavecheck: error: {outcome.error}", file=sys.stderr, flush=True)
            if stream is not None:
                print(outcome.summary, file=stream, flush=True)
            if outcome.error is None:
                spool.put(outcome.index, outcome.piece)
                outcome.piece = ""
            done[outcome.index] = outcome
        outcomes = [o for o in done if o is not None]
        code = worst_exit_code([o.code for o in outcomes])
        _write_many(args, outcomes, spool, code)
    finally:
        spool.close()
    side.finish([(o.path, o.error) for o in outcomes if o.error is not None])
    return code


def _write_many(
    args: argparse.Namespace, outcomes: list[_Outcome], spool: _Spool, code: int
) -> None:
    """The ``--format`` document of several captures, in input order: to ``-o`` (the summary
    lines were printed as the captures finished) or stdout, piece by piece from ``spool``."""
    pieces = _document(args, outcomes, spool, code)
    if args.output:
        atomic_write(args.output, pieces)
        if not args.quiet:
            print(f"report written to {args.output}")
    else:
        for piece in pieces:
            sys.stdout.write(piece)


def _document(
    args: argparse.Namespace, outcomes: list[_Outcome], spool: _Spool, code: int
) -> Iterator[str]:
    """The document's text in pieces (each capture's from ``spool``), by its format."""
    ok = [
        Part(o.path, o.summary, o.verdict, o.counts, functools.partial(spool.get, o.index))
        for o in outcomes
        if o.error is None
    ]
    failed = [o for o in outcomes if o.error is not None]
    errors = [(o.path, o.error) for o in failed if o.error is not None]
    yield from FORMATS[args.format].join(ok, errors, [o.summary for o in failed], code)
