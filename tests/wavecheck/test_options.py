"""Every check option round-trips (issue 37): its command-line spelling gives the options object
its Python keyword gives, and that object, handed whole to :func:`wavecheck.check`
(``options=``), gives the report ``wavecheck check`` prints. One row per option of
:data:`wavecheck.options.OPTIONS`: an option added there fails here until it has a row."""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

import pytest

import wavecheck
from tests.conftest import REPO
from wavecheck.cli import main
from wavecheck.cli._axis_args import check_options
from wavecheck.drives.library import load_drive
from wavecheck.engine import CheckOptions
from wavecheck.errors import UsageError
from wavecheck.options import OPTIONS, options_from_keywords
from wavecheck.report.json import DEFAULT_VIOLATION_CAP, report_dict

CAPTURE = str(REPO / "captures" / "golden" / "g202-p20-worst-dirhold.vcd")
DRIVE = "gecko-g202"
#: A LinuxCNC machine: BASE_PERIOD 16 us, dirhold 32 us (tests/wavecheck/cli/test_check_reports.py).
INI = "[EMCMOT]\nBASE_PERIOD = 16000\nSERVO_PERIOD = 1000000\n"
HAL = "loadrt stepgen step_type=0\nsetp stepgen.0.dirhold 32000\n"

#: option → (its command-line words, its Python keywords; None: it has no keyword). ``{ini}``,
#: ``{hal}`` and ``{tmp}`` name files of the test's own folder.
ROWS: dict[str, tuple[list[str], dict[str, Any] | None]] = {
    "drive": (["--drive", "leadshine-dm542"], {"drive": "leadshine-dm542"}),
    "map": (["--map", "step=dir,dir=step"], {"map": {"step": "dir", "dir": "step"}}),
    "invert": (["--invert", "dir"], {"invert": ["dir"]}),
    "step_type": (["--type", "0"], {"step_type": 0}),
    "forward_level": (["--dir-forward", "high"], {"forward_level": 1}),
    "user_table": (["--user-step-type", "1,3,2,0"], {"user_table": (1, 3, 2, 0)}),
    "pulse_level": (["--pulse-level", "low"], {"pulse_level": 0}),
    "active_edge": (["--active-edge", "rising"], {"active_edge": "rising"}),
    "resolution": (["--resolution", "500ns"], {"resolution": "500ns"}),
    "samplerate": (["--samplerate", "1MHz"], {"samplerate": "1MHz"}),
    "input_format": (["--input-format", "vcd"], {"input_format": "vcd"}),
    "limit": (["--limit", "dir_hold=10us"], {"limit": ["dir_hold=10us"]}),
    "margin": (["--margin", "2x"], {"margin": "2x"}),
    "ini": (["--ini", "{ini}"], {"ini": "{ini}"}),
    "hal": (["--ini", "{ini}", "--hal", "{hal}"], {"ini": "{ini}", "hal": "{hal}"}),
    "channel": (
        ["--ini", "{ini}", "--hal", "{hal}", "--channel", "0"],
        {"ini": "{ini}", "hal": "{hal}", "channel": 0},
    ),
    "base_period": (["--base-period", "25us"], None),
    "steplen": (["--ini", "{ini}", "--steplen", "5us"], None),
    "stepspace": (["--ini", "{ini}", "--stepspace", "5us"], None),
    "dirsetup": (["--ini", "{ini}", "--dirsetup", "20us"], None),
    "dirhold": (["--ini", "{ini}", "--dirhold", "20us"], None),
    "latency": (
        ["--ini", "{ini}", "--hal", "{hal}", "--latency", "11us"],
        {"ini": "{ini}", "hal": "{hal}", "latency": "11us"},
    ),
    "pictures": (["--gtkw", "{tmp}/run.gtkw"], {"pictures": True}),
    "keep_violations": (["--max-violations", "5000"], {"keep_violations": 5000}),
    "block_edges": (["--block-edges", "3"], {"block_edges": 3}),
    "require": (["--require", "dir_hold"], {"require": "dir_hold"}),
}
#: The options that say how the capture is read (no field of the options object).
READING = ("samplerate", "input_format")


def test_every_option_has_a_row() -> None:
    assert set(ROWS) == {o.name for o in OPTIONS}


def test_every_keyword_is_converted() -> None:
    from wavecheck.options import _CONVERT, _STEPGEN, CheckKeywords

    assert set(_CONVERT) | set(_STEPGEN) == set(CheckKeywords.__annotations__)


def _files(tmp: Path, words: Any) -> Any:
    (tmp / "m.ini").write_text(INI)
    (tmp / "m.hal").write_text(HAL)
    names = {"ini": str(tmp / "m.ini"), "hal": str(tmp / "m.hal"), "tmp": str(tmp)}
    if isinstance(words, list):
        return [w.format(**names) for w in words]
    return {k: v.format(**names) if isinstance(v, str) else v for k, v in words.items()}


def _args(words: list[str]) -> argparse.Namespace:
    from wavecheck.cli import check

    parser = argparse.ArgumentParser()
    check.register(parser.add_subparsers())
    drive = [] if "--drive" in words else ["--drive", DRIVE]
    return parser.parse_args(["check", CAPTURE, *drive, *words])


def _cli_json(capsys: pytest.CaptureFixture[str], words: list[str]) -> dict[str, Any]:
    drive = [] if "--drive" in words else ["--drive", DRIVE]
    main(["check", CAPTURE, *drive, *words, "--format", "json"])
    doc: dict[str, Any] = json.loads(capsys.readouterr().out)
    return doc


def _json(report: wavecheck.Report, options: CheckOptions) -> dict[str, Any]:
    doc: dict[str, Any] = json.loads(
        json.dumps(report_dict(report, DEFAULT_VIOLATION_CAP, options.require))
    )
    return doc


def _at(doc: Any, path: str) -> Any:
    """The value at ``a.b`` (``rules[].c``: every rule's) of a JSON document."""
    for part in path.split("."):
        if part.endswith("[]"):
            doc = doc[part[:-2]]
        elif isinstance(doc, list):
            doc = [d[part] for d in doc]
        else:
            doc = doc[part]
    return doc


@pytest.mark.parametrize("option", OPTIONS, ids=lambda o: o.name)
def test_cli_options_check_round_trip(
    option: Any, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    words, keywords = ROWS[option.name]
    words = _files(tmp_path, words)
    args = _args(words)
    from_cli = check_options(args)
    default = check_options(_args([]))
    if option.field:  # the row sets what the option says it sets
        assert getattr(from_cli, option.field) != getattr(default, option.field)
    shown = _cli_json(capsys, words)
    reading = {k: getattr(args, k) for k in READING if getattr(args, k) is not None}
    # the CLI's options object, handed whole to wavecheck.check, gives the CLI's report
    report = wavecheck.check(CAPTURE, options=from_cli, **reading)
    assert _json(report, from_cli) == shown
    if option.report:  # where the report shows it is there
        assert _at(shown, option.report) is not None
    if keywords is None:  # a command-line option only (the stepgen figures of the files)
        assert option.keyword == ""
        return
    keywords = _files(tmp_path, keywords)
    drive = load_drive(keywords.pop("drive", DRIVE))
    mapping = keywords.pop("map", None)
    for key in READING:
        keywords.pop(key, None)
    from_python = options_from_keywords(
        {None: drive}, None if mapping is None else from_cli.axes, keywords
    )
    if option.field:  # the keyword gives the field the flags give
        assert getattr(from_python, option.field) == getattr(from_cli, option.field)
    by_keywords = wavecheck.check(
        CAPTURE, drive, **({} if mapping is None else {"map": mapping}), **reading, **keywords
    )
    mine = {"keep_violations", "pictures"}  # the CLI keeps what its outputs list and draw
    same = from_python if option.name in mine else from_cli
    assert _json(by_keywords, same) == shown


def test_options_and_keywords_together() -> None:
    """Keywords replace what they give of the options object; the rest stays."""
    base = check_options(_args(["--invert", "dir", "--margin", "2x"]))
    report = wavecheck.check(CAPTURE, options=base, margin="+1us")
    assert report.inverted == ("dir",)
    assert options_from_keywords(keywords={"margin": "+1us"}, base=base).margin == "+1us"


def test_an_unknown_keyword_is_refused() -> None:
    with pytest.raises(UsageError, match=r"unknown check option\(s\) margn"):
        options_from_keywords(keywords={"margn": "2x"})
    with pytest.raises(UsageError, match="check needs a drive"):
        wavecheck.check(CAPTURE)
