"""Saleae Logic 2's digital CSV export: exact sample times from decimal text, or a refusal."""

from __future__ import annotations

from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from wavecheck.capture.open import detect_format, open_capture
from wavecheck.errors import CaptureError


def _export(path: Path, rate: Fraction, rows: list[tuple[int, int, int]], digits: int) -> None:
    """Rows (sample, ch0, ch1) written as Logic 2 does: time = sample / rate to ``digits``
    decimals, trigger at sample 100 (earlier times are negative)."""
    lines = ["Time [s],Channel 0,Channel 1"]
    for k, a, b in rows:
        t = Fraction(k - 100) / rate
        q = round(t * 10**digits)
        sign = "-" if q < 0 else ""
        q = abs(q)
        lines.append(f"{sign}{q // 10**digits}.{q % 10**digits:0{digits}d},{a},{b}")
    path.write_text("\n".join(lines) + "\n")


def _rows(changes: list[int]) -> list[tuple[int, int, int]]:
    rows, a, b = [(0, 0, 1)], 0, 1
    for i, k in enumerate(changes):
        if i % 3 == 2:
            b ^= 1
        else:
            a ^= 1
        rows.append((k, a, b))
    return rows


@settings(max_examples=40, deadline=None)
@given(
    gaps=st.lists(st.integers(1, 5000), min_size=3, max_size=40),
    rate=st.sampled_from([Fraction(12_500_000), Fraction(100_000_000), Fraction(500_000_000)]),
)
def test_decimal_times_on_a_decimal_grid_are_exact(
    tmp_path_factory: pytest.TempPathFactory, gaps: list[int], rate: Fraction
) -> None:
    path = tmp_path_factory.mktemp("saleae") / "export.csv"
    changes = list(np.cumsum(gaps).tolist())
    _export(path, rate, _rows(changes), 9)
    assert detect_format(path) == "saleae-csv"
    given_rate = open_capture(path, samplerate=rate)
    edges = np.concatenate([given_rate.channels[0].edges, given_rate.channels[1].edges])
    assert sorted(edges.tolist()) == changes
    assert given_rate.timebase.tick_s == 1 / rate and given_rate.resolution_ticks == 1
    # without --samplerate the period is the times' common grid: a multiple of the true one
    found = open_capture(path)
    period = found.timebase.tick_s
    assert (period * rate).denominator == 1
    assert [found.timebase.seconds(int(e)) for e in found.channels[0].edges] == [
        given_rate.timebase.seconds(int(e)) for e in given_rate.channels[0].edges
    ]


def test_rounded_times_need_the_sample_rate(tmp_path: Path) -> None:
    """6 MHz printed to 1 ns (the issue's '0.000016167'): the grid cannot be told from the text."""
    path = tmp_path / "six.csv"
    changes = [97, 150, 151, 400, 777]
    _export(path, Fraction(6_000_000), _rows(changes), 9)
    with pytest.raises(CaptureError, match="give --samplerate"):
        open_capture(path)
    cap = open_capture(path, samplerate=Fraction(6_000_000))
    edges = sorted(np.concatenate([c.edges for c in cap.channels]).tolist())
    assert edges == changes
    # a wrong rate is refused, not rounded into place
    with pytest.raises(CaptureError, match="not on the grid"):
        open_capture(path, samplerate=Fraction(4_000_000))


def test_a_bad_row_names_its_line(tmp_path: Path) -> None:
    path = tmp_path / "bad.csv"
    path.write_text("Time [s],Channel 0\n0.000000000,0\n0.000000080,x\n")
    with pytest.raises(CaptureError, match="line 3"):
        open_capture(path)
