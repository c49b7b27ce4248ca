"""``wavecheck check``'s report outputs and its several-captures mode.

Options added here (see :func:`add_report_arguments`): ``--plot FILE.png``, ``--html FILE.html``,
``--gtkw FILE.gtkw``, ``-q/--quiet``, and the stepgen configuration ``--ini FILE``,
``--hal FILE`` (repeatable), ``--channel N``, ``--latency J`` for the ``config`` and
``latency_safe`` max step rates.

Several captures (``wavecheck check a.sr b.vcd 'runs/*.sr'``): each is checked on its own; a
capture that cannot be read is reported (one line on stderr) and the others go on. stdout gets
each text report and then one summary line per capture; the exit code is the worst one
(2 unusable > 1 fail > 3 indeterminate > 0 pass). JSON becomes ``{"reports": [...], "errors":
[...], "verdict", "exit_code"}``; JUnit has one ``testsuite`` per capture; the HTML page a section
per capture; ``--plot``/``--gtkw`` write one file per capture, named ``FILE-<capture stem>.png``.
One capture keeps the single-report behaviour and output shapes exactly.
"""

from __future__ import annotations

import argparse
import glob
import json
import os
import sys
from collections.abc import Callable
from fractions import Fraction
from pathlib import Path
from typing import Any

from wavecheck.cli.linuxcnc import add_file_arguments
from wavecheck.errors import UsageError, WavecheckError
from wavecheck.linuxcnc.config import LinuxCNCConfig, read_config
from wavecheck.output import atomic_write, output_file
from wavecheck.progress import activate
from wavecheck.report.json import DEFAULT_VIOLATION_CAP, report_dict
from wavecheck.report.model import Report
from wavecheck.report.text import DEFAULT_TEXT_VIOLATIONS, render_text
from wavecheck.units import BASE_PERIOD, LATENCY, format_time, option_ns
from wavecheck.verdict import overall_verdict, worst_exit_code

__all__ = [
    "add_report_arguments",
    "expand_captures",
    "latency_ns",
    "render_json_report",
    "render_junit_report",
    "render_text_report",
    "run_checks",
    "stepgen_config",
    "summary_line",
]

def add_report_arguments(p: argparse.ArgumentParser) -> None:
    """Add the report-file, quiet and LinuxCNC-configuration options to ``check``'s parser."""
    out = p.add_argument_group("reports")  # output_file: checked before any work (wavecheck.output)
    out.add_argument(
        "--plot", type=output_file, metavar="FILE.png", help="timing diagrams and histograms (PNG)"
    )
    out.add_argument(
        "--html", type=output_file, metavar="FILE.html", help="one self-contained HTML page"
    )
    out.add_argument(
        "--gtkw",
        type=output_file,
        metavar="FILE.gtkw",
        help="GTKWave save file with markers at the worst violations (a non-VCD capture is "
        "written as FILE.vcd beside it)",
    )
    out.add_argument(
        "-q", "--quiet", action="store_true", help="no progress bar (it is off anyway when "
        "stderr is not a terminal)"
    )
    cfg = p.add_argument_group("stepgen configuration (config and latency_safe step rates)")
    add_file_arguments(cfg)
    for name, what in _CONFIG_OPTIONS.items():
        cfg.add_argument(
            f"--{name.replace('_', '-')}",
            metavar="T",
            help=f"{what}, with its unit (e.g. 16us; overrides --ini/--hal)"
            + ("; below 1 us is refused as a unit slip" if name == "base_period" else ""),
        )
    cfg.add_argument(
        "--latency",
        metavar="J",
        help="worst base-thread latency, with its unit (e.g. 11us), for latency_safe; "
        "below 100 ns gives a warning",
    )


def expand_captures(patterns: list[str]) -> list[str]:
    """Capture paths from the command line: existing files as given, glob patterns expanded
    (sorted); a pattern matching nothing is an error."""
    out: list[str] = []
    for pat in patterns:
        if glob.has_magic(pat) and not os.path.exists(pat):
            hits = sorted(glob.glob(pat, recursive=True))
            if not hits:
                raise UsageError(f"{pat}: no file matches this pattern")
            out += hits
        else:
            out.append(pat)
    return out


#: check's stepgen-configuration options (config and latency_safe rates), LinuxCNC's names.
_CONFIG_OPTIONS = {
    "base_period": "BASE_PERIOD",
    "steplen": "stepgen steplen",
    "stepspace": "stepgen stepspace",
    "dirsetup": "stepgen dirsetup",
    "dirhold": "stepgen dirhold",
}


# -- stepgen configuration rates -------------------------------------------------------------------
def stepgen_config(args: argparse.Namespace) -> LinuxCNCConfig | None:
    """The stepgen configuration of ``--ini``/``--hal``/``--base-period``/… (None: not given);
    read once and kept on ``args``."""
    if hasattr(args, "_linuxcnc_config"):
        cached: LinuxCNCConfig | None = args._linuxcnc_config
        return cached
    cfg = None
    given = {k: getattr(args, k, None) for k in _CONFIG_OPTIONS}
    if getattr(args, "ini", None) or getattr(args, "hal", None) or any(given.values()):
        cfg = read_config(args.ini, list(args.hal or []), getattr(args, "channel", 0))
        for name, text in given.items():
            if text is None:
                continue
            option = f"--{name.replace('_', '-')}"
            ns = option_ns(text, option, BASE_PERIOD if name == "base_period" else None)
            if ns.denominator != 1 or ns < 0 or (name == "base_period" and ns == 0):
                raise UsageError(f"{option} {text}: must be a whole, positive number of ns")
            if name == "base_period":
                cfg.base_period_ns = int(ns)
            else:
                cfg.params[name] = int(ns)
            cfg.sources[name] = option
    elif getattr(args, "latency", None):
        raise UsageError(
            "--latency needs the stepgen configuration: give --ini/--hal or --base-period"
        )
    args._linuxcnc_config = cfg
    return cfg


def latency_ns(args: argparse.Namespace) -> Fraction | None:
    """``--latency`` in exact ns (None when not given); read (and warned about) once, kept on
    ``args``."""
    if hasattr(args, "_latency_ns"):
        cached: Fraction | None = args._latency_ns
        return cached
    text = getattr(args, "latency", None)
    j = None
    if text is not None:
        j = option_ns(text, "--latency", LATENCY, _warn)
        if j < 0:
            raise UsageError(f"--latency {text}: must not be negative")
    args._latency_ns = j
    return j


def _warn(message: str) -> None:
    print(f"wavecheck: warning: {message}", file=sys.stderr)


def render_text_report(report: Report, args: argparse.Namespace) -> str:
    """The text report (``--max-violations`` listed)."""
    cap = DEFAULT_TEXT_VIOLATIONS if args.max_violations is None else args.max_violations
    return render_text(report, cap)


def _dict(report: Report, args: argparse.Namespace) -> dict[str, Any]:
    cap = DEFAULT_VIOLATION_CAP if args.max_violations is None else args.max_violations
    return report_dict(report, cap)


def render_json_report(report: Report, args: argparse.Namespace) -> str:
    """The JSON report (``--max-violations`` listed)."""
    return json.dumps(_dict(report, args), indent=2, ensure_ascii=False) + "\n"


def render_junit_report(report: Report, args: argparse.Namespace) -> str:
    """JUnit XML of one report."""
    from wavecheck.report.junit import render_junit

    return render_junit([report])


# -- several captures --------------------------------------------------------------------------------
def summary_line(report: Report) -> str:
    """One line: verdict, capture, violations, steps and the worst rule."""
    worst = ""
    margins = [(r.min_margin_ns, r.rule) for r in report.rules if r.min_margin_ns is not None]
    if margins:
        m, rule = min(margins)
        sign = "+" if m > 0 else ""
        worst = f"; closest {rule} {sign}{format_time(m / 10**9)}"
    return (
        f"{report.verdict.upper():<13} {report.capture.path}: {report.total_violations} "
        f"violation(s), {report.steps.count} steps{worst}"
    )


def _per_capture(path: str, capture: str, index: int, stems: dict[str, int]) -> str:
    """``out.png`` → ``out-<capture stem>.png`` (a number added when stems repeat)."""
    p = Path(path)
    stem = Path(capture).stem
    n = stems.get(stem, 0)
    stems[stem] = n + 1
    tag = stem if n == 0 else f"{stem}-{n + 1}"
    return str(p.with_name(f"{p.stem}-{tag}{p.suffix}"))


def _side_outputs(
    args: argparse.Namespace, reports: list[Report], errors: list[tuple[str, str]]
) -> None:
    several = len(reports) + len(errors) > 1
    stems: dict[str, int] = {}
    gstems: dict[str, int] = {}
    pngs: list[bytes | None] = []
    for k, r in enumerate(reports):
        png = None
        if args.plot:
            from wavecheck.report.plot import render_png

            target = _per_capture(args.plot, r.capture.path, k, stems) if several else args.plot
            png = render_png(r)
            atomic_write(target, png)
        pngs.append(png)  # rendered once, embedded in the HTML page too
        if args.gtkw:
            from wavecheck.report.gtkw import write_gtkw

            target = _per_capture(args.gtkw, r.capture.path, k, gstems) if several else args.gtkw
            write_gtkw(r, target)
    if args.html:
        from wavecheck.report.html import write_html

        write_html(
            reports,
            args.html,
            errors=[f"{p}: {e}" if not e.startswith(p) else e for p, e in errors],
            pngs=pngs,
            max_violations=DEFAULT_TEXT_VIOLATIONS
            if args.max_violations is None
            else args.max_violations,
        )


def run_checks(
    args: argparse.Namespace,
    build_report: Callable[[argparse.Namespace, str], Report],
    write_outputs: Callable[[argparse.Namespace, Report], None],
) -> int:
    """Check every capture of ``args.capture`` and write every requested output.

    One capture: ``write_outputs`` (the single-report behaviour) and the side outputs; an
    unusable input raises (exit 2). Several: see the module docstring.
    """
    patterns = args.capture if isinstance(args.capture, list) else [args.capture]
    paths = expand_captures(patterns)
    stepgen_config(args)  # a bad INI/HAL file is reported before any capture is read
    latency_ns(args)
    if len(paths) == 1:
        with activate(f"reading {paths[0]}", quiet=args.quiet, unit="bytes"):
            report = build_report(args, paths[0])
        write_outputs(args, report)
        _side_outputs(args, [report], [])
        return report.exit_code
    reports: list[Report] = []
    errors: list[tuple[str, str]] = []
    codes: list[int] = []
    for path in paths:
        try:
            with activate(f"reading {path}", quiet=args.quiet, unit="bytes"):
                reports.append(build_report(args, path))
            codes.append(reports[-1].exit_code)
        except WavecheckError as err:
            print(f"wavecheck: error: {err}", file=sys.stderr)
            errors.append((path, str(err)))
            codes.append(err.exit_code)
    code = worst_exit_code(codes)
    _write_many(args, reports, errors, code)
    _side_outputs(args, reports, errors)
    return code


def _write_many(
    args: argparse.Namespace, reports: list[Report], errors: list[tuple[str, str]], code: int
) -> None:
    summary = [summary_line(r) for r in reports] + [
        f"{'ERROR':<13} {e if e.startswith(p) else f'{p}: {e}'}" for p, e in errors
    ]
    if args.format == "json":
        verdict: str = overall_verdict([r.verdict for r in reports]) if reports else "unchecked"
        if errors:
            verdict = "error"
        text = (
            json.dumps(
                {
                    "reports": [_dict(r, args) for r in reports],
                    "errors": [{"path": p, "error": e} for p, e in errors],
                    "verdict": verdict,
                    "exit_code": code,
                },
                indent=2,
                ensure_ascii=False,
            )
            + "\n"
        )
    elif args.format == "junit":
        from wavecheck.report.junit import Unreadable, render_junit

        text = render_junit(reports, [Unreadable(p, e) for p, e in errors])
    else:
        parts = [f"== {r.capture.path} ==\n{render_text_report(r, args)}" for r in reports]
        text = "\n".join(parts) + "\n== summary ==\n" + "\n".join(summary) + "\n"
    if args.output:
        atomic_write(args.output, text)
        print("\n".join(summary))
        print(f"report written to {args.output}")
    else:
        sys.stdout.write(text)
