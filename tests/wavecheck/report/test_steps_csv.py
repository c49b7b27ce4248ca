"""``--steps-csv``: one row per decoded step, times exact, rows summing to the final position."""

from __future__ import annotations

import csv
import io
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from tests.engine_probe import run_check
from wavecheck.capture.open import open_capture
from wavecheck.cli import main
from wavecheck.drives.library import load_drive
from wavecheck.report.steps_csv import (
    StepsCsvWriter,
    decimal_digits,
    format_times,
)
from wavecheck.timebase import Timebase

REPO = Path(__file__).resolve().parents[3]
G202 = REPO / "captures" / "golden" / "g202-p20-worst-dirhold.vcd"
UPDOWN = REPO / "captures" / "golden" / "updown-uniform.vcd"
SMOOTHIE_MAP = ["--map", "x.step=5,x.dir=6", "--map", "y.step=3,y.dir=4"]


def _rows(path: Path) -> list[dict[str, str]]:
    with open(path, newline="", encoding="utf-8") as f:
        return list(csv.DictReader(f))


@pytest.mark.parametrize(("vcd", "drive"), [(G202, "gecko-g202"), (UPDOWN, "leadshine-dm542")])
@pytest.mark.parametrize("command", ["check", "measure"])
def test_rows_are_the_decoded_steps_exactly(
    vcd: Path, drive: str, command: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "steps.csv"
    cap = open_capture(vcd)
    typ = "1" if vcd == UPDOWN else "0"
    report = run_check(cap, load_drive(drive), step_type_number=int(typ))
    extra = ["--drive", drive] if command == "check" else ["--active-edge", report.active_edge]
    main([command, str(vcd), *extra, "--type", typ, "--steps-csv", str(out)])
    capsys.readouterr()
    rows = _rows(out)
    steps = report.steps
    assert len(rows) == steps.count > 0
    # times read back as Fractions equal the decoded tick × the exact tick, with no rounding
    times = [Fraction(r["time_s"]) for r in rows]
    assert times == [int(t) * cap.timebase.tick_s for t in steps.ticks]
    assert [int(r["tick"]) for r in rows] == steps.ticks.tolist()
    # the directions sum to the final position, which is the last row's position
    directions = [int(r["direction"]) for r in rows]
    assert sum(directions) == int(rows[-1]["position"]) == steps.final_position
    assert directions == steps.direction.tolist()
    # the rate is from the previous step: 1 / the gap, rounded to the mHz
    for prev, row in zip(times, rows[1:], strict=False):
        gap = Fraction(row["time_s"]) - prev
        assert abs(Fraction(row["rate_hz"]) - 1 / gap) <= Fraction(1, 2000)
    assert rows[0]["rate_hz"] == ""


def test_two_axes_in_time_order_with_units(
    smoothie_sr: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """12 MHz: the tick (83.3… ns) has no decimal; the tick column is exact and the time within
    a twentieth of a tick of it."""
    out = tmp_path / "s.csv"
    code = main(
        [
            "measure",
            str(smoothie_sr),
            *SMOOTHIE_MAP,
            "--steps-csv",
            str(out),
            "--steps-per-unit",
            "x=80",
        ]
    )
    capsys.readouterr()
    assert code == 0
    rows = _rows(out)
    tick = Fraction(1, 12_000_000)
    assert len(rows) == 739 * 2
    assert [int(r["tick"]) for r in rows] == sorted(int(r["tick"]) for r in rows)
    for r in rows:
        assert abs(Fraction(r["time_s"]) - int(r["tick"]) * tick) <= tick / 20
    for axis in ("x", "y"):
        mine = [r for r in rows if r["axis"] == axis]
        assert sum(int(r["direction"]) for r in mine) == int(mine[-1]["position"]) == 739
    x = [r for r in rows if r["axis"] == "x"]
    assert Fraction(x[-1]["position_units"]) == Fraction(739, 80)
    assert float(x[1]["velocity_units_per_s"]) == pytest.approx(float(x[1]["rate_hz"]) / 80)
    assert all(r["position_units"] == "" for r in rows if r["axis"] == "y")


@given(st.lists(st.integers(0, 2**50), max_size=30), st.integers(1, 10**6), st.integers(1, 10**12))
def test_times_exact_or_within_a_twentieth_of_a_tick(ticks: list[int], num: int, den: int) -> None:
    tick = Fraction(num, den)
    text = format_times(np.asarray(ticks, dtype=np.int64), tick)
    places, exact = decimal_digits(tick)
    for t, s in zip(ticks, text, strict=True):
        got = Fraction(s)
        assert got == t * tick if exact else abs(got - t * tick) <= tick / 20
        assert len(s.partition(".")[2]) == places


def _written(path: Path, cuts: list[int]) -> str:
    """Two axes' steps through the streaming writer, handed over in pieces: the steps before
    each cut, then ``settled(cut)``."""
    d = np.array([1, 1, -1, 1, 0], dtype=np.int8)
    x_ticks, y_ticks = np.array([0, 10, 25, 25, 40]), np.array([5, 25])
    writer = StepsCsvWriter(path, Timebase(Fraction(1, 10**6)), units=True, named={"x"})
    x, y = writer.sink("x", Fraction(2)), writer.sink("y")
    done_x = done_y = 0
    for cut in [*cuts, 1 << 40]:
        kx, ky = int(np.searchsorted(x_ticks, cut)), int(np.searchsorted(y_ticks, cut))
        x.add(x_ticks[done_x:kx], d[done_x:kx])
        y.add(y_ticks[done_y:ky], d[done_y:ky])
        done_x, done_y = kx, ky
        writer.settled(cut)
    writer.close()
    return path.read_text(encoding="utf-8")


def test_pieces_do_not_change_the_text(tmp_path: Path) -> None:
    whole = _written(tmp_path / "whole.csv", [])
    for cuts in ([11], [5, 25, 26], [1, 6, 11, 25, 40]):
        assert _written(tmp_path / "pieces.csv", cuts) == whole, cuts
    rows = list(csv.DictReader(io.StringIO(whole)))
    assert [(r["axis"], r["tick"]) for r in rows] == [
        ("x", "0"),
        ("y", "5"),
        ("x", "10"),
        ("x", "25"),
        ("x", "25"),
        ("y", "25"),
        ("x", "40"),
    ]
    # a step at the same tick as the previous one of its axis has no rate; unknown: no velocity
    assert [r["rate_hz"] for r in rows if r["axis"] == "x"] == [
        "",
        "100000.000",
        "66666.667",
        "",
        "66666.667",
    ]
    assert rows[-1]["velocity_units_per_s"] == "" and rows[-1]["position_units"] == "1.000000"


def test_several_captures_one_file_each(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    golden = REPO / "captures" / "golden"
    out = tmp_path / "steps.csv"
    main(
        [
            "check",
            str(golden / "g202-p16-dirhold2-worst.vcd"),
            str(G202),
            "--drive",
            "gecko-g202",
            "--steps-csv",
            str(out),
        ]
    )
    capsys.readouterr()
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "steps-g202-p16-dirhold2-worst.csv",
        "steps-g202-p20-worst-dirhold.csv",
    ]


@pytest.mark.parametrize(
    ("argv", "words"),
    [
        (["--steps-per-unit", "80"], "give --steps-csv FILE too"),
        (["--steps-csv", "{out}", "--steps-per-unit", "-3"], "must be positive"),
        (
            ["--steps-csv", "{out}", "--steps-per-unit", "eighty"],
            "is not a number of steps per unit",
        ),
        (["--steps-csv", "{out}", "--steps-per-unit", "z=80"], "no axis 'z' is mapped"),
    ],
)
def test_steps_per_unit_refused(
    argv: list[str], words: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    argv = [a.format(out=tmp_path / "s.csv") for a in argv]
    assert main(["measure", str(G202), *argv]) == 2
    assert words in capsys.readouterr().err
    assert not (tmp_path / "s.csv").exists()
