"""``-q/--quiet`` has one meaning in both tools (issue 26): no progress bar and no summary line;
the requested outputs, warnings and errors still come. It meant "no progress bar" in
``wavecheck check`` (whose ``-o`` summary line still printed) and "no output" in ``stepgen
simulate``."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.reliability.helpers import cli

SIM = ["simulate", "--position-scale", "1000", "--maxvel", "15", "--maxaccel", "200",
       "--move", "0.05", "--seed", "1"]  # fmt: skip


def _runs(tmp: Path) -> dict[str, tuple[str, list[str], list[Path]]]:
    """(program, argv, files the run must write) of each command that takes -q."""
    run, other = tmp / "run.vcd", tmp / "other.vcd"
    check = ["check", "--drive", "gecko-g202", "--map", "step=step,dir=dir"]
    return {
        "stepgen simulate": ("stepgen", [*SIM, "-o", str(other)], [other]),
        "wavecheck check -o": ("wavecheck", [*check, str(run), "-o", str(tmp / "r.json"),
                                             "--format", "json"], [tmp / "r.json"]),
        "wavecheck check, two captures": ("wavecheck", [*check, str(run), str(run), "-j", "1",
                                                        "-o", str(tmp / "r2.txt")], [tmp / "r2.txt"]),
        "wavecheck measure -o": ("wavecheck", ["measure", str(run), "-o", str(tmp / "m.txt")],
                                 [tmp / "m.txt"]),
    }  # fmt: skip


@pytest.fixture
def capture(tmp_path: Path) -> Path:
    path = tmp_path / "run.vcd"
    assert cli("stepgen", [*SIM, "-o", str(path), "-q"])[0] == 0
    return path


@pytest.mark.parametrize("name", list(_runs(Path())))
def test_quiet_prints_nothing_but_writes_everything(
    tmp_path: Path, capture: Path, name: str
) -> None:
    prog, argv, files = _runs(tmp_path)[name]
    code, out, err = cli(prog, argv)
    assert code in (0, 1) and out.strip(), (out, err)  # a summary line without -q
    for f in files:
        f.unlink()
    code_q, out_q, err_q = cli(prog, [*argv, "-q"])
    assert code_q == code
    assert (out_q, err_q) == ("", "")
    assert all(f.exists() and f.stat().st_size for f in files)


def test_quiet_keeps_warnings(tmp_path: Path) -> None:
    argv = ["simulate", "--latency", "worst:11us:step_high", "--periods", "100"]
    code, out, err = cli("stepgen", [*argv, "-o", str(tmp_path / "w.vcd"), "-q"])
    assert code == 0 and out == "" and "worst-case motion drives velocity-cmd" in err
