"""Saleae CSV exports of a time range (issue 34): Logic 2 writes the range's start as the first
row and its end as the last, at times that need not be samples. They are read at the true rate,
as the sample before them, and named; Logic 1.x's ``Time[s], Channel 0`` exports are read too."""

from __future__ import annotations

import random
from fractions import Fraction
from pathlib import Path

import numpy as np
import numpy.typing as npt
import pytest

from wavecheck.capture.edges import Capture
from wavecheck.capture.open import detect_format, open_capture
from wavecheck.cli import main
from wavecheck.errors import CaptureError


def _decimal(t: Fraction, digits: int) -> str:
    q = round(t * 10**digits)
    sign = "-" if q < 0 else ""
    return f"{sign}{abs(q) // 10**digits}.{abs(q) % 10**digits:0{digits}d}"


def _logic2(
    path: Path,
    rate: Fraction,
    changes: list[tuple[int, list[int]]],
    start: Fraction,
    end: Fraction,
    initial: list[int],
) -> Path:
    """A Logic 2 CSV export of the range [start, end] s: a row at ``start`` with the levels
    then, one per change (sample k at k/rate s, printed to 9 decimals, as Logic 2 does), and a
    row at ``end`` with the levels then."""
    names = ",".join(f"Channel {i}" for i in range(len(initial)))
    lines = [f"Time [s],{names}", f"{_decimal(start, 9)},{','.join(map(str, initial))}"]
    levels = initial
    for k, levels in changes:
        lines.append(f"{_decimal(Fraction(k) / rate, 9)},{','.join(map(str, levels))}")
    lines.append(f"{_decimal(end, 9)},{','.join(map(str, levels))}")
    path.write_text("\r\n".join(lines) + "\r\n")
    return path


def _step_train(first: int, n: int, period: int, high: int) -> list[tuple[int, list[int]]]:
    """STEP (channel 0) pulses of ``high`` samples every ``period`` samples from ``first``,
    DIR (channel 1) low."""
    out = []
    for i in range(n):
        out += [(first + i * period, [1, 0]), (first + i * period + high, [0, 0])]
    return out


RATE_500K = Fraction(500_000)
START = Fraction("9.893632465")  # the row: not on the 2 us grid
FIRST = 4_946_817  # the first sample after START (9.893634 s)


@pytest.fixture
def export_500k(tmp_path: Path) -> Path:
    changes = _step_train(FIRST + 3, 40, 37, 5)
    end = Fraction(changes[-1][0] + 11) / RATE_500K + Fraction(777, 10**9)
    return _logic2(tmp_path / "steps.csv", RATE_500K, changes, START, end, [0, 0])


def _seconds(cap: Capture, ticks: npt.NDArray[np.int64]) -> list[Fraction]:
    """Times of ``ticks`` from the capture's start, exact."""
    return [cap.timebase.seconds(int(t) - cap.start) for t in ticks]


def test_500_khz_export_is_read_at_500_khz(export_500k: Path) -> None:
    """Read as 200 MHz before (the 5 ns gcd the start row makes): resolution 400x overstated."""
    assert detect_format(export_500k) == "saleae-csv"
    cap = open_capture(export_500k)
    assert cap.samplerate_hz == RATE_500K and cap.resolution_ns == 2000
    off = [n for n in cap.notes if "off the 2 us sample grid" in n]
    assert len(off) == 2
    assert off[0].startswith("line 2 (time 9.893632465 s, the export's start)")
    assert "line 83 " in off[1] and "the export's end" in off[1] and "kept exact (1 ns" in off[1]
    # the times are exact: the first STEP rise 7.535 us after the export's start, pulses 10 us
    # high every 74 us, the end 22.777 us after the last fall
    rises = _seconds(cap, cap.channel("Channel 0").edges[0::2])
    falls = _seconds(cap, cap.channel("Channel 0").edges[1::2])
    assert rises[0] == Fraction(7535, 10**9)
    assert {b - a for a, b in zip(rises, rises[1:], strict=False)} == {Fraction(74, 10**6)}
    assert {f - r for r, f in zip(rises, falls, strict=True)} == {Fraction(10, 10**6)}
    assert cap.timebase.seconds(cap.end - cap.start) - falls[-1] == Fraction(22777, 10**9)


def test_500_khz_export_with_the_sample_rate(export_500k: Path) -> None:
    """Refused before: "time 9.893632465 s is not on the grid"."""
    given = open_capture(export_500k, samplerate=RATE_500K)
    found = open_capture(export_500k)
    edges = given.channel("Channel 0").edges
    assert _seconds(given, edges) == _seconds(found, found.channel("Channel 0").edges)
    assert given.duration_s == found.duration_s and given.resolution_ns == 2000
    assert sum("off the 2 us sample grid" in n for n in given.notes) == 2


def test_a_change_off_the_grid_is_still_refused(tmp_path: Path) -> None:
    changes = _step_train(FIRST + 3, 10, 37, 5)
    path = _logic2(tmp_path / "bad.csv", RATE_500K, changes, START, Fraction(10), [0, 0])
    text = path.read_text().splitlines()
    t = Fraction(text[5].split(",")[0]) + Fraction(1, 10**6)  # line 6 moved by 1 us
    text[5] = f"{_decimal(t, 9)},{text[5].split(',', 1)[1]}"
    path.write_text("\n".join(text) + "\n")
    with pytest.raises(CaptureError, match=r"line 6: time .* is not on the grid of 500000 Hz"):
        open_capture(path, samplerate=RATE_500K)


def test_a_last_row_that_changes_is_no_range_end(tmp_path: Path) -> None:
    """A last row whose levels differ from the row before is a change: on the grid or refused."""
    changes = _step_train(FIRST + 3, 10, 37, 5)
    end = Fraction("10.000000301")
    path = _logic2(tmp_path / "end.csv", RATE_500K, changes, START, end, [0, 0])
    lines = path.read_text().splitlines()
    lines[-1] = lines[-1].rsplit(",", 2)[0] + ",1,1"
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(
        CaptureError, match=f"line {len(lines)}: time 10.000000301 s is not on the grid"
    ):
        open_capture(path, samplerate=RATE_500K)


def test_an_export_of_the_whole_capture_has_no_note(tmp_path: Path) -> None:
    """From time 0 (a sample) to a sample: nothing is off the grid, and nothing is said."""
    changes = _step_train(3, 10, 37, 5)
    path = _logic2(tmp_path / "whole.csv", RATE_500K, changes, Fraction(0),
                   Fraction(500, RATE_500K), [0, 0])  # fmt: skip
    cap = open_capture(path)
    assert cap.samplerate_hz == RATE_500K
    assert not [n for n in cap.notes if "off the" in n]
    assert cap.channel("Channel 0").edges[0] == 3 and cap.end == 500


def test_eight_channels_on_a_160_ns_grid(tmp_path: Path) -> None:
    """6.25 MHz (160 ns), 8 channels, random changes; the range starts and ends between samples.
    Unreadable before, even with --samplerate 6.25MHz."""
    rng = random.Random(34)
    rate = Fraction(6_250_000)
    k, levels, changes = 1_000_003, [0] * 8, []
    for _ in range(300):
        k += rng.randint(1, 40)
        levels = levels.copy()
        levels[rng.randrange(8)] ^= 1
        changes.append((k, levels))
    start = Fraction(1_000_000) / rate + Fraction(37, 10**9)
    end = Fraction(k + 5) / rate + Fraction(101, 10**9)
    path = _logic2(tmp_path / "eight.csv", rate, changes, start, end, [0] * 8)
    for given in (None, rate):
        cap = open_capture(path, samplerate=given)
        assert cap.samplerate_hz == rate and len(cap.channels) == 8 and cap.resolution_ns == 160
        times = sorted(t for c in cap.channels for t in _seconds(cap, c.edges))
        assert times == [(c - 1_000_000) / rate - Fraction(37, 10**9) for c, _ in changes]
        assert cap.duration_s == end - start
        assert sum("off the 160 ns sample grid" in n for n in cap.notes) == 2


def test_the_cli_checks_the_500_khz_export(
    export_500k: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code = main(
        [
            "check",
            str(export_500k),
            "--drive",
            "gecko-g202",
            "--map",
            "step=Channel 0,dir=Channel 1",
        ]
    )
    out = capsys.readouterr().out
    assert code in (0, 1, 3), out
    assert "line 2 (time 9.893632465 s, the export's start) is off the 2 us sample grid" in out


# -- Logic 1.x ---------------------------------------------------------------------------------


def _logic1(
    path: Path, rate: float, changes: list[tuple[int, list[int]]], initial: list[int]
) -> Path:
    """A Logic 1.x CSV export: ``Time[s], Channel 0, …``, ", " between cells, the time of sample
    k printed as the float k/rate to 15 decimals (as in '0.000882958333333' at 24 MHz)."""
    names = ", ".join(f"Channel {i}" for i in range(len(initial)))
    lines = [f"Time[s], {names}", f"{0.0:.15f}, {', '.join(map(str, initial))}"]
    for k, levels in changes:
        lines.append(f"{k / rate:.15f}, {', '.join(map(str, levels))}")
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.mark.parametrize("rate", [24_000_000, 16_000_000, 1_000_000])
def test_logic_1x_export_is_read(tmp_path: Path, rate: int) -> None:
    changes = _step_train(1_000, 50, 2_001, 48)
    path = _logic1(tmp_path / "l1.csv", float(rate), changes, [0, 0])
    assert detect_format(path) == "saleae1-csv"
    cap = open_capture(path, samplerate=Fraction(rate))
    assert cap.format == "saleae1-csv"
    ticks = sorted(int(t) for c in cap.channels for t in c.edges)
    assert ticks == [k for k, _ in changes]
    assert any("Logic 1.x" in n for n in cap.notes)


def test_logic_1x_at_24_mhz_needs_the_rate(tmp_path: Path) -> None:
    """41.667 ns is no whole number of ns: the rate cannot be told from the times."""
    path = _logic1(tmp_path / "l1.csv", 24e6, _step_train(1_000, 50, 2_001, 47), [0, 0])
    with pytest.raises(CaptureError, match="give --samplerate, the rate set in Logic"):
        open_capture(path)
    with pytest.raises(CaptureError, match="not on the grid of 16000000 Hz"):
        open_capture(path, samplerate=Fraction(16_000_000))


def test_logic_1x_at_1_mhz_needs_no_rate(tmp_path: Path) -> None:
    changes = _step_train(1_000, 50, 2_001, 48)
    cap = open_capture(_logic1(tmp_path / "l1.csv", 1e6, changes, [0, 0]))
    # every change lies on a 3 us grid (gcd of 48 and 2001 samples): the rate found is a third
    # of the true one, a note says to give it, and the start row is named off that grid
    assert cap.samplerate_hz == Fraction(1_000_000, 3)
    assert any("give --samplerate if Logic sampled faster" in n for n in cap.notes)
    assert _seconds(cap, cap.channel("Channel 0").edges[:1]) == [Fraction(1, 1000)]
    assert open_capture(tmp_path / "l1.csv", samplerate=Fraction(10**6)).resolution_ns == 1000
