"""Every output option of ``wavecheck check`` (``-o``, ``--html``, ``--plot``, ``--gtkw``) on
every kind of path: FIFOs and devices written in place, symlinks followed, folders and inputs
refused before any work (the table is in :mod:`tests.wavecheck.cli.output_paths`)."""

from __future__ import annotations

import os
import shutil
from collections.abc import Callable
from pathlib import Path

import pytest

from tests.conftest import write_vcd
from tests.wavecheck.cli.output_paths import CASES, LooksRight, run_case
from tests.wavecheck.waves import pulses
from wavecheck.cli import main

US = 1000  # 1 ns timescale

#: option, file name, what its content starts with
OPTIONS: list[tuple[str, str, LooksRight]] = [
    ("-o", "report.txt", lambda b: b.startswith(b"verdict: PASS")),
    ("--html", "report.html", lambda b: b.startswith(b"<!DOCTYPE html>")),
    ("--plot", "plot.png", lambda b: b.startswith(b"\x89PNG")),
    ("--gtkw", "view.gtkw", lambda b: b"[dumpfile]" in b),
]


def _capture(folder: Path) -> Path:
    # A4988: high/low >= 1 us, DIR setup/hold >= 200 ns; every interval passes
    step = pulses([10 * US, 20 * US, 30 * US], 1 * US)
    return write_vcd(folder / "w.vcd", {"STEP": (0, step), "DIR": (0, [15 * US])})


@pytest.mark.parametrize(
    ("option", "name", "looks_right", "case"),
    [
        pytest.param(opt, name, ok, case, id=f"{opt}-{case.id}")
        for opt, name, ok in OPTIONS
        for case in CASES
        if opt == "-o" or not case.stdout  # other options leave stdout to the text report
    ],
)
def test_check_output_paths(
    option: str, name: str, looks_right: LooksRight, case, tmp_path: Path, capfd
) -> None:
    capture = _capture(tmp_path)
    (tmp_path / "o").mkdir()

    def argv(path: str) -> list[str]:
        return ["check", str(capture), "--drive", "a4988", option, path]

    run_case(case, tmp_path / "o", name, argv, option, looks_right, main, capfd)


def _same(capture: Path, _tmp: Path) -> tuple[list[str], str]:
    return [], str(capture)


def _respelled(capture: Path, tmp: Path) -> tuple[list[str], str]:
    (tmp / "sub").mkdir()
    return [], str(tmp / "sub" / ".." / capture.name)


def _symlink_to_capture(capture: Path, tmp: Path) -> tuple[list[str], str]:
    (tmp / "link.txt").symlink_to(capture)
    return [], str(tmp / "link.txt")


def _hard_link(capture: Path, tmp: Path) -> tuple[list[str], str]:
    os.link(capture, tmp / "hard.txt")
    return [], str(tmp / "hard.txt")


def _rule_file(capture: Path, tmp: Path) -> tuple[list[str], str]:
    rules = Path(__file__).resolve().parents[3] / "rules" / "a4988.toml"
    shutil.copy(rules, tmp / "mine.toml")
    return ["--drive", str(tmp / "mine.toml")], str(tmp / "mine.toml")


def _ini_file(capture: Path, tmp: Path) -> tuple[list[str], str]:
    (tmp / "m.ini").write_text("[EMCMOT]\nBASE_PERIOD = 25000\nSERVO_PERIOD = 1000000\n")
    return ["--ini", str(tmp / "m.ini")], str(tmp / "m.ini")


def _hal_file(capture: Path, tmp: Path) -> tuple[list[str], str]:
    (tmp / "m.hal").write_text("loadrt stepgen step_type=0\nsetp stepgen.0.steplen 1\n")
    return ["--base-period", "25us", "--hal", str(tmp / "m.hal")], str(tmp / "m.hal")


INPUTS: list[tuple[str, Callable[[Path, Path], tuple[list[str], str]]]] = [
    ("capture", _same),
    ("capture-respelled", _respelled),
    ("symlink-to-capture", _symlink_to_capture),
    ("hard-link-to-capture", _hard_link),
    ("rule-file", _rule_file),
    ("ini-file", _ini_file),
    ("hal-file", _hal_file),
]


@pytest.mark.parametrize("option", ["-o", "--html"])
@pytest.mark.parametrize(("what", "arrange"), INPUTS, ids=[i for i, _ in INPUTS])
def test_writing_over_an_input_is_refused(
    option: str, what: str, arrange, tmp_path: Path, capfd
) -> None:
    capture = _capture(tmp_path)
    extra, target = arrange(capture, tmp_path)
    argv = ["check", str(capture), "--drive", "a4988", *extra, option, target]
    if "--drive" in extra:
        argv[3:5] = []  # the rule file replaces --drive a4988
    snapshot = {p: p.read_bytes() for p in tmp_path.rglob("*") if p.is_file()}
    code = main(argv)
    out, err = capfd.readouterr()
    assert code == 2 and out == "", err
    assert len(err.strip().splitlines()) == 1
    assert f"{option} {target}:" in err and "an input of this run" in err, err
    assert {p: p.read_bytes() for p in tmp_path.rglob("*") if p.is_file()} == snapshot
    if what == "symlink-to-capture":
        assert (tmp_path / "link.txt").is_symlink()


def test_capture_given_through_a_symlink_is_protected(tmp_path: Path, capfd) -> None:
    capture = _capture(tmp_path)
    (tmp_path / "cap.vcd").symlink_to(capture)
    before = capture.read_bytes()
    code = main(["check", str(tmp_path / "cap.vcd"), "--drive", "a4988", "-o", str(capture)])
    _, err = capfd.readouterr()
    assert code == 2 and "an input of this run" in err
    assert capture.read_bytes() == before


def test_output_checked_before_the_capture_is_read(tmp_path: Path, capfd) -> None:
    (tmp_path / "bad.vcd").write_text("not a VCD at all\n")
    (tmp_path / "out.html").mkdir()
    code = main(
        [
            "check",
            str(tmp_path / "bad.vcd"),
            "--drive",
            "a4988",
            "--html",
            str(tmp_path / "out.html"),
        ]
    )
    _, err = capfd.readouterr()
    assert code == 2 and err.startswith(f"wavecheck: error: --html {tmp_path / 'out.html'}: ")


def test_two_outputs_naming_one_file_are_refused(tmp_path: Path, capfd) -> None:
    capture = _capture(tmp_path)
    target = str(tmp_path / "r.html")
    code = main(["check", str(capture), "--drive", "a4988", "-o", target, "--html", target])
    out, err = capfd.readouterr()
    assert code == 2 and out == "" and "--html" in err and "also given to -o" in err
    assert not (tmp_path / "r.html").exists()


def test_per_capture_outputs_are_written_through_the_same_mechanism(tmp_path: Path, capfd) -> None:
    """Several captures: ``--plot p.png`` writes ``p-<stem>.png``; a symlink there is followed."""
    a = _capture(tmp_path)
    b = write_vcd(tmp_path / "v.vcd", {"STEP": (0, pulses([10 * US], 1 * US))})
    (tmp_path / "real.png").write_bytes(b"old")
    (tmp_path / "p-w.png").symlink_to("real.png")
    code = main(["check", str(a), str(b), "--drive", "a4988", "--plot", str(tmp_path / "p.png")])
    capfd.readouterr()
    assert code == 0
    assert (tmp_path / "p-w.png").is_symlink()
    assert (tmp_path / "real.png").read_bytes().startswith(b"\x89PNG")


def test_gtkw_companion_vcd_does_not_overwrite_an_input(tmp_path: Path, capfd) -> None:
    """A ``.sr`` capture's ``--gtkw view.gtkw`` writes ``view.vcd`` beside it: never over an
    input (nor any other file wavecheck did not write)."""
    from stepgen.cli import main as stepgen

    assert (
        stepgen(
            [
                "simulate",
                "--mode",
                "velocity",
                "--velocity",
                "100",
                "--periods",
                "1000",
                "-q",
                "-o",
                str(tmp_path / "cap.sr"),
            ]
        )
        == 0
    )
    ini = tmp_path / "view.vcd"  # an INI file whose name the companion VCD would take
    ini.write_text("[EMCMOT]\nBASE_PERIOD = 25000\nSERVO_PERIOD = 1000000\n")
    before = ini.read_bytes()
    code = main(
        [
            "check",
            str(tmp_path / "cap.sr"),
            "--drive",
            "a4988",
            "--ini",
            str(ini),
            "--gtkw",
            str(tmp_path / "view.gtkw"),
        ]
    )
    _, err = capfd.readouterr()
    # issue 27: not wavecheck's own companion, so not replaced: the next free name is taken
    assert code == 0 and f"its signals are in {tmp_path / 'view-2.vcd'}" in err
    assert ini.read_bytes() == before
    assert f'"{tmp_path / "view-2.vcd"}"' in (tmp_path / "view.gtkw").read_text()
