"""``wavecheck check 'runs/*.vcd' -j N`` (issues 14 and 18): captures spread over N processes,
each summary line printed as it finishes, the documents in input order and identical whatever
N, only what the outputs need kept per capture, and each drive file parsed once per process."""

from __future__ import annotations

import argparse
import dataclasses
import gc
import json
import shutil
import tempfile
import weakref
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tests.conftest import write_vcd
from wavecheck.cli import _batch, main
from wavecheck.cli._reports import Asked, asked
from wavecheck.drives import library
from wavecheck.report import plot
from wavecheck.report.html import render_html
from wavecheck.report.junit import Unreadable, render_junit

US = 1000


def _runs(folder: Path, count: int = 7) -> list[Path]:
    """``count`` small VCDs; every third has a 200 ns DIR setup (fails gecko-g202's 1 µs)."""
    paths = []
    for k in range(count):
        rising = [10 * US + 40 * US * i for i in range(20)]
        step = sorted(rising + [t + 5 * US for t in rising])
        flip = rising[10] + (5 * US - 200 if k % 3 == 0 else -12 * US)  # G202 steps on the fall
        paths.append(write_vcd(folder / f"r{k}.vcd", {"STEP": (0, step), "DIR": (0, [flip])}))
    return paths


ARGS = ["--drive", "gecko-g202", "--map", "step=STEP,dir=DIR"]


@pytest.mark.parametrize("fmt", ["text", "json", "junit"])
def test_documents_identical_for_any_number_of_jobs(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], fmt: str
) -> None:
    _runs(tmp_path)
    (tmp_path / "r9.vcd").write_text("")  # unreadable: an error entry, the others go on
    docs = []
    for jobs in ("1", "2", "3"):
        code = main(["check", str(tmp_path / "*.vcd"), *ARGS, "--format", fmt, "-j", jobs])
        out, err = capsys.readouterr()
        assert code == 2 and "r9.vcd: the file is empty" in err
        docs.append(out)
    assert docs[0] == docs[1] == docs[2]
    names = [str(tmp_path / f"r{k}.vcd") for k in range(7)]
    if fmt == "json":
        data = json.loads(docs[0])
        assert [r["capture"]["path"] for r in data["reports"]] == names  # input order
        assert [e["path"] for e in data["errors"]] == [str(tmp_path / "r9.vcd")]
        assert [r["verdict"] for r in data["reports"]] == ["fail", "pass", "pass"] * 2 + ["fail"]
    elif fmt == "junit":
        root = ET.fromstring(docs[0])
        assert [s.get("name") for s in root.findall("testsuite")] == [
            *names,
            names[0][:-6] + "r9.vcd",
        ]
        assert root.get("errors") == "1"
    else:
        summary = docs[0].split("== summary ==\n", 1)[1].splitlines()
        assert [line.split()[1].rstrip(":") for line in summary] == [
            *names,
            str(tmp_path / "r9.vcd"),
        ]


#: Kinds of capture for the tables below: a check that passes, one that fails (a 200 ns DIR
#: setup against the G202's 1 µs), and three that cannot be checked (exit 2).
KINDS = ("pass", "fail", "empty", "cut-header", "no-dir")


def _capture(path: Path, kind: str) -> None:
    rising = [10 * US + 40 * US * i for i in range(20)]
    step = sorted(rising + [t + 5 * US for t in rising])
    if kind in ("pass", "fail"):
        flip = rising[10] + (5 * US - 200 if kind == "fail" else -12 * US)
        write_vcd(path, {"STEP": (0, step), "DIR": (0, [flip])})
    elif kind == "no-dir":
        write_vcd(path, {"STEP": (0, step)})
    else:
        path.write_text("" if kind == "empty" else "$timescale 1 ns $end\n$var wire 1 ! STEP $e")


def _plain_and_parallel(
    folder: Path, kinds: list[str], argv: list[str], capsys: pytest.CaptureFixture[str]
) -> tuple[Any, Any]:
    """The same captures checked with ``-j 1`` (the plain path) and then ``-j 2``: each run's
    exit code, stdout, stderr and the files it wrote under ``folder/out`` (name → bytes)."""
    for k, kind in enumerate(kinds):
        _capture(folder / f"c{k:02d}.vcd", kind)
    out = folder / "out"
    runs = []
    for jobs in ("1", "2"):
        out.mkdir()
        code = main(["check", str(folder / "c*.vcd"), *ARGS, *argv, "-j", jobs])
        printed = capsys.readouterr()
        files = {f.name: f.read_bytes() for f in sorted(out.iterdir())}
        shutil.rmtree(out)
        runs.append((code, printed.out, printed.err, files))
    return runs[0], runs[1]


@settings(max_examples=12, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(
    kinds=st.lists(st.sampled_from(KINDS), min_size=2, max_size=9),
    fmt=st.sampled_from(["text", "json", "junit"]),
    to_file=st.booleans(),
)
def test_two_jobs_give_what_one_job_gives(
    capsys: pytest.CaptureFixture[str], kinds: list[str], fmt: str, to_file: bool
) -> None:
    """The fast path (``-j 2``: workers, pieces spooled) against the plain one (``-j 1``, in
    this process): the same exit code, document, error lines and files, for any mix of captures
    that pass, fail or cannot be read. Only the order of the streamed summary lines (as each
    capture finishes) may differ."""
    argv = ["--format", fmt]
    with tempfile.TemporaryDirectory() as tmp:  # a fresh folder for each example
        argv += ["-o", f"{tmp}/out/report"] if to_file else []
        one, two = _plain_and_parallel(Path(tmp), kinds, argv, capsys)
    assert one[0] == two[0] == _worst(kinds)
    assert sorted(one[2].splitlines()) == sorted(two[2].splitlines())
    assert one[3] == two[3] and len(one[3]) == int(to_file)
    if to_file:  # stdout: a summary line per capture, as each finishes, then where it went
        assert sorted(one[1].splitlines()) == sorted(two[1].splitlines())
        assert len(one[1].splitlines()) == len(kinds) + 1
    else:
        assert one[1] == two[1]
    errors = [line for line in one[2].splitlines() if line.startswith("wavecheck: error:")]
    assert len(errors) == sum(k not in ("pass", "fail") for k in kinds)


def _worst(kinds: list[str]) -> int:
    return 2 if set(kinds) - {"pass", "fail"} else (1 if "fail" in kinds else 0)


def test_two_jobs_write_the_files_one_job_writes(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """With every output asked for (the document to ``-o``, figures, GTKWave files, the HTML
    page), ``-j 2`` writes byte for byte the files of ``-j 1``."""
    monkeypatch.setattr(plot, "render_png", lambda r: b"\x89PNG " + r.capture.path.encode())
    kinds = ["pass", "fail", "empty", "pass", "no-dir", "fail"]
    out = tmp_path / "out"
    argv = ["--format", "junit", "-o", f"{out}/r.xml", "--plot", f"{out}/p.png",
            "--gtkw", f"{out}/g.gtkw", "--html", f"{out}/r.html"]  # fmt: skip
    one, two = _plain_and_parallel(tmp_path, kinds, argv, capsys)
    assert one[0] == two[0] == 2
    assert sorted(one[3]) == sorted(two[3]) == sorted(
        ["r.xml", "r.html", *(f"p-c{k:02d}.png" for k in (0, 1, 3, 5)),
         *(f"g-c{k:02d}.gtkw" for k in (0, 1, 3, 5))]
    )  # fmt: skip
    assert one[3] == two[3]


def test_each_report_equals_the_single_capture_report(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    paths = _runs(tmp_path, 4)
    main(["check", str(tmp_path / "*.vcd"), *ARGS, "--format", "json", "-j", "2"])
    several = json.loads(capsys.readouterr().out)["reports"]
    for path, report in zip(paths, several, strict=True):
        main(["check", str(path), *ARGS, "--format", "json"])
        assert json.loads(capsys.readouterr().out) == report


def test_summary_lines_stream_to_stdout_with_o(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """With ``-o`` every capture's summary line is printed (in the order they finish), then
    where the report went; the file lists the captures in input order."""
    _runs(tmp_path, 5)
    out_file = tmp_path / "r.json"
    code = main(["check", str(tmp_path / "*.vcd"), *ARGS, "--format", "json", "-o", str(out_file),
                 "-j", "2"])  # fmt: skip
    out = capsys.readouterr().out.splitlines()
    assert code == 1 and out[-1] == f"report written to {out_file}"
    assert (
        sorted(out[:-1]) == sorted(line for line in out[:-1] if line.startswith(("PASS ", "FAIL ")))
        and len(out) == 6
    )
    data = json.loads(out_file.read_text())
    assert [r["capture"]["path"] for r in data["reports"]] == [
        str(tmp_path / f"r{k}.vcd") for k in range(5)
    ]


def test_workers_send_back_no_reports(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """What comes back from a worker is the summary and the document's piece, not the Report
    (whose capture holds every edge): memory does not grow with the number of captures."""
    from wavecheck.cli.check import build_report

    paths = [str(p) for p in _runs(tmp_path, 4)]
    args = _parse(["check", *paths, *ARGS, "--format", "json"])
    outcomes = list(_batch._outcomes(args, asked(args), build_report, paths, 2))
    assert sorted(o.index for o in outcomes) == [0, 1, 2, 3]
    assert all(isinstance(o.piece, str) for o in outcomes)
    assert [f.name for f in dataclasses.fields(_batch._Outcome)] == [
        "index", "path", "summary", "code", "verdict", "piece", "counts", "error",
    ]  # fmt: skip


@pytest.mark.parametrize("side", [[], ["--plot", "p.png", "--gtkw", "g.gtkw", "--html", "r.html"]])
def test_no_report_outlives_its_capture(
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
    side: list[str],
) -> None:
    """In this process too (``-j 1``, and the side outputs, which run here): when a capture is
    checked, no report of an earlier one is still alive: memory stays flat in the captures."""
    from wavecheck.cli import check

    monkeypatch.setattr(plot, "render_png", lambda r: b"\x89PNG " + r.capture.path.encode())
    alive: list[weakref.ref[Any]] = []
    build = check.build_report

    def watched(args: argparse.Namespace, what: Asked, path: str) -> Any:
        gc.collect()
        assert [r for r in alive if r() is not None] == []
        checked = build(args, what, path)
        alive.append(weakref.ref(checked))
        return checked

    monkeypatch.setattr(check, "build_report", watched)
    _runs(tmp_path, 4)
    monkeypatch.chdir(tmp_path)
    code = main(["check", str(tmp_path / "*.vcd"), *ARGS, "-j", "1", *side])
    capsys.readouterr()
    assert code == 1 and len(alive) == 4
    if side:
        assert sorted(f.name for f in tmp_path.glob("p-*.png")) == [f"p-r{k}.png" for k in range(4)]
        assert len(list(tmp_path.glob("g-r*.gtkw"))) == 4


def test_several_documents_equal_the_renderers_of_all_reports(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """The JUnit document and the HTML page of several captures, joined capture by capture from
    pieces, are what the renderers give for all the reports at once."""
    monkeypatch.setattr(plot, "render_png", lambda r: b"\x89PNG " + r.capture.path.encode())
    paths = [str(p) for p in _runs(tmp_path, 3)]
    (tmp_path / "r9.vcd").write_text("")
    page = tmp_path / "r.html"
    argv = ["check", str(tmp_path / "r*.vcd"), *ARGS, "--format", "junit", "--html", str(page)]
    assert main(argv) == 2
    junit_doc = capsys.readouterr().out
    args = _parse(["check", *paths, *ARGS])
    from wavecheck.cli.check import build_report

    reports = [build_report(args, asked(args), p) for p in paths]
    bad = str(tmp_path / "r9.vcd")
    assert junit_doc == render_junit(reports, [Unreadable(bad, f"{bad}: the file is empty")])
    pngs = [plot.render_png(r) for r in reports]
    want = render_html(reports, errors=[f"{bad}: the file is empty"], pngs=pngs)
    assert page.read_text() == want


def test_the_parent_keeps_no_piece_of_the_document(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """Each capture's piece of the document goes to the spool (a file) as it arrives: when the
    document is written, the outcomes held in memory carry only their summary line."""
    seen: list[list[_batch._Outcome]] = []
    write = _batch._write_many

    def watched(args: argparse.Namespace, outcomes: list[Any], spool: Any, code: int) -> None:
        seen.append(list(outcomes))
        write(args, outcomes, spool, code)

    monkeypatch.setattr(_batch, "_write_many", watched)
    _runs(tmp_path, 5)
    for jobs in ("1", "2"):
        main(["check", str(tmp_path / "*.vcd"), *ARGS, "--format", "json", "-j", jobs])
        assert len(json.loads(capsys.readouterr().out)["reports"]) == 5  # the pieces came back
    assert [[o.piece for o in outcomes] for outcomes in seen] == [[""] * 5] * 2


def _parse(argv: list[str]) -> argparse.Namespace:
    from wavecheck.cli import check

    parser = argparse.ArgumentParser()
    check.register(parser.add_subparsers())
    return parser.parse_args(argv)


def test_jobs_must_be_positive(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    _runs(tmp_path, 2)
    assert main(["check", str(tmp_path / "*.vcd"), *ARGS, "-j", "0"]) == 2
    assert "-j/--jobs must be 1 or more" in capsys.readouterr().err


def test_drive_file_parsed_once_while_unchanged(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    calls: list[Path] = []
    parse = library._parse_file

    def counting(path: Path, user: bool, raw: bytes | None = None) -> library.Drive:
        calls.append(path)
        return parse(path, user, raw)

    monkeypatch.setattr(library, "_parse_file", counting)
    monkeypatch.setattr(library, "_DRIVES", {})
    _runs(tmp_path, 5)
    main(["check", str(tmp_path / "*.vcd"), *ARGS, "-j", "1"])
    capsys.readouterr()
    assert len(calls) == 1  # five captures, one parse
    user = tmp_path / "mine.toml"
    text = library.rules_dir().joinpath("gecko-g202.toml").read_text()
    user.write_text(text)
    first = library.load_drive(str(user))
    assert library.load_drive(str(user)) is first and len(calls) == 2
    user.write_text(text.replace("Gecko G202", "Gecko G203"))  # same size, maybe same mtime
    assert library.load_drive(str(user)) is not first and len(calls) == 3
