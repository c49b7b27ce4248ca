"""``stepgen simulate -o`` and ``stepgen plan -o`` on every kind of path: FIFOs and devices
written in place, symlinks followed, folders and inputs refused before any work (the table is in
:mod:`tests.wavecheck.cli.output_paths`, shared with ``wavecheck check``)."""

from __future__ import annotations

import shutil
from collections.abc import Callable
from pathlib import Path

import pytest

from stepgen.cli import main
from tests.wavecheck.cli.output_paths import CASES, LooksRight, run_case

RULES = Path(__file__).resolve().parents[3] / "rules"

SIMULATE = ["simulate", "--mode", "velocity", "--velocity", "100", "--periods", "1000", "-q"]
PLAN = ["plan", "--drive", "a4988", "--latency", "11us"]

#: command argv (without -o), file name, what the output starts with
COMMANDS: list[tuple[str, list[str], str, LooksRight]] = [
    ("simulate-vcd", SIMULATE, "out.vcd", lambda b: b.startswith(b"$comment")),
    ("simulate-sr", SIMULATE, "out.sr", lambda b: b.startswith(b"PK")),
    ("plan", PLAN, "plan.txt", lambda b: b.startswith(b"stepgen plan")),
]


def _applies(command: str, case_id: str) -> bool:
    # simulate picks its format from the name: /dev/null and /dev/stdout have none (the
    # link-to-dev-null case gives /dev/null a .vcd/.sr name)
    return not (
        command.startswith("simulate") and case_id in ("dev-null", "dev-stdout", "link-to-stdout")
    )


@pytest.mark.parametrize(
    ("base", "name", "looks_right", "case"),
    [
        pytest.param(base, name, ok, case, id=f"{cmd}-{case.id}")
        for cmd, base, name, ok in COMMANDS
        for case in CASES
        if _applies(cmd, case.id)
    ],
)
def test_output_paths(
    base: list[str], name: str, looks_right: LooksRight, case, tmp_path: Path, capfd
) -> None:
    def argv(path: str) -> list[str]:
        return [*base, "-o", path]

    run_case(case, tmp_path, name, argv, "-o", looks_right, main, capfd)


def _command_csv(tmp: Path) -> tuple[list[str], Path]:
    # a motion file whose name a careless -o repeats (it has the extension simulate writes)
    (tmp / "motion.vcd").write_text("time_s,position\n0,0\n0.001,2\n")
    return [
        "simulate",
        "--command",
        str(tmp / "motion.vcd"),
        "--duration",
        "5ms",
    ], tmp / "motion.vcd"


def _ini(tmp: Path) -> tuple[list[str], Path]:
    (tmp / "machine.sr").write_text("[EMCMOT]\nBASE_PERIOD = 25000\nSERVO_PERIOD = 1000000\n")
    return [*SIMULATE, "--ini", str(tmp / "machine.sr")], tmp / "machine.sr"


def _rule_file(tmp: Path) -> tuple[list[str], Path]:
    shutil.copy(RULES / "a4988.toml", tmp / "mine.toml")
    return ["plan", "--drive", str(tmp / "mine.toml"), "--latency", "11us"], tmp / "mine.toml"


def _latency_file(tmp: Path) -> tuple[list[str], Path]:
    (tmp / "latency.txt").write_text("11000\n")  # latency-test's ~/.latency: ns
    return ["plan", "--drive", "a4988", "--latency", str(tmp / "latency.txt")], tmp / "latency.txt"


INPUTS: list[tuple[str, Callable[[Path], tuple[list[str], Path]]]] = [
    ("simulate-command-csv", _command_csv),
    ("simulate-ini", _ini),
    ("plan-rule-file", _rule_file),
    ("plan-latency-file", _latency_file),
]


@pytest.mark.parametrize("via", ["same", "symlink"])
@pytest.mark.parametrize(("what", "arrange"), INPUTS, ids=[i for i, _ in INPUTS])
def test_writing_over_an_input_is_refused(
    what: str, arrange, via: str, tmp_path: Path, capfd
) -> None:
    base, source = arrange(tmp_path)
    target = source
    if via == "symlink":
        target = tmp_path / f"link{source.suffix}"
        target.symlink_to(source.name)
    before = source.read_bytes()
    code = main([*base, "-o", str(target)])
    out, err = capfd.readouterr()
    assert code == 2 and out == "", err
    assert len(err.strip().splitlines()) == 1
    assert f"-o {target}:" in err and "an input of this run" in err, err
    assert source.read_bytes() == before
    assert via == "same" or target.is_symlink()


@pytest.mark.parametrize(
    "argv",
    [
        ["simulate", "--type", "99", "--periods", "10"],  # a bad setting, found later
        ["plan", "--drive", "no-such-drive", "--latency", "11us"],
    ],
    ids=["simulate", "plan"],
)
def test_output_checked_before_any_work(argv: list[str], tmp_path: Path, capfd) -> None:
    (tmp_path / "out.vcd").mkdir()
    code = main([*argv, "-o", str(tmp_path / "out.vcd")])
    _, err = capfd.readouterr()
    assert (
        code == 2
        and err == f"stepgen: error: -o {tmp_path / 'out.vcd'}: is a directory (give a file name)\n"
    )
