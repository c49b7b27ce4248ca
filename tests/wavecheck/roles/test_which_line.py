"""Issue 26, "Which line is checked": what ``check`` and ``info`` say without ``--map`` on
captures nobody labelled, as a user sees it (exit codes, the error lines, the ``--map`` to copy).
Each test failed on the code before the issue."""

from __future__ import annotations

import json
import shlex
import shutil
import subprocess
from pathlib import Path

import pytest

from tests.conftest import shared_capture, write_vcd
from wavecheck.cli import main

from ..waves import move, pulses

SIM = Path(__file__).parent / "sim"
US = 1000  # ticks (ns) per µs


def _run(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str, str]:
    code = main(list(args))
    out, err = capsys.readouterr()
    return code, out, err


def test_an_enable_around_like_moves_is_no_axis(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """grbl_cnc_3: ENABLE high around each of 7 like moves (7 "steps" at 0.43 Hz, each as long as
    the others); all the real steps happen while it is high, as in grbl_cnc_1: it is the ENABLE,
    never an axis of its own."""
    steps: list[int] = []
    en: list[int] = []
    t = 1000 * US
    for _ in range(7):
        starts = move(t + 30_000 * US, 800, 250 * US)
        steps += starts
        en += [t, starts[-1] + 25_000 * US]
        t = starts[-1] + 2_300_000 * US
    path = write_vcd(
        tmp_path / "grbl-like.vcd",
        {"EN": (0, en), "STEP (Y axis)": (0, pulses(steps, 10 * US))},
    )
    code, out, err = _run(capsys, "check", str(path), "--drive", "drv8825", "--format", "json")
    assert code == 0, err
    report = json.loads(out)
    assert report["steps"]["count"] == len(steps)
    code, out, _ = _run(capsys, "info", str(path), "--format", "json")
    roles = json.loads(out)["roles"]
    assert roles["map_args"] == "--map 'step=STEP (Y axis),enable=EN'"


def test_grbl_cnc_1_maps_as_its_readme_says(
    grbl_sr: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code, out, _ = _run(capsys, "info", str(grbl_sr), "--format", "json")
    assert json.loads(out)["roles"]["map_args"] == "--map 'step=STEP (Y axis),enable=EN'"


def test_spi_capture_has_no_step_signal(capsys: pytest.CaptureFixture[str]) -> None:
    """sigrok's SPI capture: check invented two axes and failed with 1,836 violations; now it
    says there is no step signal and what the lines are, in one line, exit 2."""
    spi = shared_capture(
        "sigrok-dumps/spi/spiflash_read16/chronovu_la8/chronovu_la8_spiflash_read16.vcd"
    )
    code, out, err = _run(capsys, "check", str(spi), "--drive", "drv8825")
    assert code == 2 and not out and err.count("\n") == 1, err
    assert "no step signal found: the lines look like SPI-like bus (clock Channel_3; " in err
    assert "data Channel_1; chip select Channel_7)" in err


def _clock_and_uart() -> dict[str, tuple[int, list[int]]]:
    """A free-running 1 MHz clock and a UART line (104 us bits)."""
    bits = (0, 1, 3, 4, 5, 9, 10, 13, 14, 18, 19, 20, 24, 26, 27, 29, 30, 34, 35, 37, 38, 39)
    uart = [1000 * US + 104 * US * k + 5_000 * US * frame for frame in range(4) for k in bits]
    return {"c0": (0, list(range(500, 10_000_000, 500))), "c1": (1, uart)}


def _pwm() -> dict[str, tuple[int, list[int]]]:
    """A 20 kHz PWM whose pulse width sweeps from 5 to 45 us."""
    return {
        "p": (0, [t for k in range(1, 200) for t in (50 * US * k, 50 * US * k + 5 * US + 200 * k)])
    }


@pytest.mark.parametrize(
    ("signals", "words"),
    [(_clock_and_uart(), "clock (c0)"), (_pwm(), "PWM (p)")],
    ids=["clock", "pwm"],
)
def test_no_step_signal_says_what_the_lines_look_like(
    tmp_path: Path,
    signals: dict[str, tuple[int, list[int]]],
    words: str,
    capsys: pytest.CaptureFixture[str],
) -> None:
    path = write_vcd(tmp_path / "lines.vcd", signals)
    code, out, err = _run(capsys, "check", str(path), "--drive", "drv8825")
    assert code == 2 and err.count("\n") == 1 and words in err, err


def _icarus(tmp: Path, name: str, *defines: str) -> Path:
    if shutil.which("iverilog") is None or shutil.which("vvp") is None:
        pytest.skip("needs Debian's iverilog (make system-deps)")
    dump = tmp / f"{name}.vcd"
    exe = tmp / f"{name}.vvp"
    flags = [f"-D{d}" for d in defines]
    subprocess.run(
        ["iverilog", "-g2012", *flags, f'-DDUMPFILE="{dump}"', "-o", str(exe), str(SIM / "tb.v")],
        check=True,
        cwd=tmp,
    )
    subprocess.run(["vvp", "-n", str(exe)], check=True, cwd=tmp, capture_output=True)
    return dump


def test_info_and_check_agree_on_an_icarus_dump(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """An Icarus dump of a 50 MHz ``clk``, ``step`` and ``dir``: info proposed the clock as STEP
    and left ``step`` out, while check used the names; a user copying info's --map checked the
    clock. Now info gives check's mapping, and the clock is never a STEP candidate."""
    dump = _icarus(tmp_path, "tb")
    code, out, _ = _run(capsys, "info", str(dump), "--format", "json")
    roles = json.loads(out)["roles"]
    assert roles["map_args"] == "--map step=step,dir=dir"
    looks = {line["channel"]: line["look"] for line in roles["lines"]}
    assert looks["clk"] == "clock"
    code, out, _ = _run(capsys, "check", str(dump), "--drive", "drv8825", "--format", "json")
    by_names = json.loads(out)
    copied = shlex.split(roles["map_args"])
    code, out, _ = _run(
        capsys, "check", str(dump), "--drive", "drv8825", "--format", "json", *copied
    )
    assert json.loads(out)["steps"] == by_names["steps"]
    # the same lines under neutral names: the waveforms alone find step and dir, not the clock
    neutral = _icarus(tmp_path, "neutral", "NEUTRAL")
    code, out, _ = _run(capsys, "info", str(neutral), "--format", "json")
    # the reset, low through every step, is no ENABLE: it changes once, before the first step,
    # and is never seen off between steps (issue 33: it was taken as the ENABLE)
    assert json.loads(out)["roles"]["map_args"] == "--map step=s,dir=d"


def test_the_map_hint_names_the_best_candidate(
    tmp_path: Path, grbl_sr: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The hint suggested channel 0 (step='EN', step='clk'); now the channel most like the role
    (by name: a check with --map streams the capture, its edges not yet read)."""
    code, _, err = _run(capsys, "check", str(grbl_sr), "--drive", "drv8825", "--map", "step=STP")
    assert code == 2 and "e.g. --map 'step=STEP (Y axis)')" in err, err
    clk = list(range(10, 400_000, 10))
    steps = pulses(move(5000, 40, 4000), 2000)
    path = write_vcd(
        tmp_path / "t.vcd", {"clk": (0, clk), "x_step": (0, steps), "x_dir": (0, [3000])}
    )
    code, _, err = _run(capsys, "check", str(path), "--drive", "drv8825", "--map", "step=STEP")
    assert code == 2 and "e.g. --map step=x_step)" in err, err


def test_an_ambiguity_is_a_short_line_with_the_candidates_below(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Two STEP lines that pause at the same time, and one DIR change in that pause: which STEP
    it belongs to the waveform cannot tell. The error was one line of 700-2,000 characters."""
    s = move(0, 12, 100 * US) + move(3000 * US, 12, 100 * US)
    t = move(50 * US, 11, 100 * US) + move(3050 * US, 12, 100 * US)
    change = s[11] + 400 * US
    path = write_vcd(
        tmp_path / "two.vcd",
        {"a": (0, pulses(s, 5 * US)), "b": (0, pulses(t, 5 * US)), "c": (0, [change])},
    )
    code, _, err = _run(capsys, "check", str(path), "--drive", "drv8825")
    first, *below = err.splitlines()
    assert code == 2 and len(first) - len(str(path)) < 160, first
    assert "cannot be told from the waveforms (1 question below); give --map (e.g." in first
    assert below == [
        "  2='c' fits as the DIR of several STEP lines:",
        "    - 2='c' as DIR of 0='a': " + below[1].split(": ", 1)[1],
        "    - 2='c' as DIR of 1='b': " + below[2].split(": ", 1)[1],
    ]
    assert all(line.split(": ", 1)[1].startswith("toggles 1 time") for line in below[1:])


def test_map_names_match_in_any_case(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The README's ``--map step=STEP,dir=DIR`` on a VCD whose channels are ``step``/``dir``."""
    steps = move(10 * US, 30, 20 * US)
    path = write_vcd(
        tmp_path / "run.vcd", {"step": (0, pulses(steps, 2 * US)), "dir": (0, [5 * US])}
    )
    code, out, err = _run(
        capsys, "check", str(path), "--drive", "drv8825", "--map", "step=STEP,dir=DIR"
    )
    assert code in (0, 1) and "map:     step='step', dir='dir'" in out, err
    both = write_vcd(
        tmp_path / "both.vcd", {"Step": (0, [1, 2]), "STEP": (0, [3, 4]), "d": (0, [])}
    )
    code, _, err = _run(capsys, "check", str(both), "--drive", "drv8825", "--map", "step=step")
    assert code == 2 and "is ambiguous: it names 0='Step', 1='STEP' in other cases" in err, err
