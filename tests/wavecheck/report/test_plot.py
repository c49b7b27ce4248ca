"""PNG plots: which places are drawn, and that a real PNG is written atomically."""

from __future__ import annotations

import struct
from fractions import Fraction
from pathlib import Path

import pytest

from wavecheck.engine.outcome import Report
from wavecheck.errors import UsageError
from wavecheck.report.plot import choose_places, render_png, write_plot


def _png_size(data: bytes) -> tuple[int, int]:
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    w, h = struct.unpack(">II", data[16:24])
    return w, h


def test_places_are_the_violations(failing_report: Report) -> None:
    places = choose_places(failing_report, 4)
    assert [p.rule for p in places] == ["dir_hold"] * 3  # three reversals, three places
    assert all(p.failed for p in places)
    assert {p.measured_ns for p in places} == {Fraction(9000)}
    assert places[0].margin_ns == -11000
    assert len(choose_places(failing_report, 2)) == 2


def test_places_without_violations_are_the_smallest_margins(passing_report: Report) -> None:
    places = choose_places(passing_report, 4)
    assert places and not any(p.failed for p in places)
    # dir_hold: 25 µs against 20 µs is the smallest margin relative to its limit
    assert places[0].rule == "dir_hold"
    assert places[0].measured_ns == 25000


def test_render_png(failing_report: Report, tmp_path: Path) -> None:
    out = tmp_path / "plot.png"
    write_plot(failing_report, out)
    w, h = _png_size(out.read_bytes())
    assert w > 800 and h > 800  # three diagrams and five histograms
    assert list(tmp_path.iterdir()) == [out]  # no temporary file left


def test_passing_plot_is_smaller(passing_report: Report) -> None:
    _, h = _png_size(render_png(passing_report, max_places=1))
    assert 400 < h < 1700  # one diagram, position and step rate, the histograms


def test_missing_folder_is_a_usage_error(failing_report: Report, tmp_path: Path) -> None:
    with pytest.raises(UsageError, match="does not exist"):
        write_plot(failing_report, tmp_path / "no" / "plot.png")
