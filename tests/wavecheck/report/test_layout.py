"""The fixed layout of the report figures (wavecheck.report.layout): every panel's texts (title,
tick labels, axis labels, role names) stay inside the figure and off every other panel, and the
figure title off all of them, for check's and measure's figures on real and generated captures."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from wavecheck.api import check
from wavecheck.engine import Report
from wavecheck.report.layout import Row, figure_height, place_rows
from wavecheck.report.plot import figure

ROOT = Path(__file__).resolve().parents[3]
SMOOTHIE = (
    ROOT.parent / "shared/captures/sigrok-dumps/stepper_motor/smoothieware/smoothieware_snippet.sr"
)


def _overlaps(a: Any, b: Any) -> bool:
    return a.x0 < b.x1 - 1 and b.x0 < a.x1 - 1 and a.y0 < b.y1 - 1 and b.y0 < a.y1 - 1


def _misplaced(fig: Any) -> list[str]:
    """What of ``fig``, drawn, lies outside the figure or on another panel."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    r = canvas.get_renderer()
    width, height = canvas.get_width_height()
    boxes = [(ax.get_title(loc="left") or ax.get_title() or f"panel {k}", ax.get_tightbbox(r))
             for k, ax in enumerate(fig.axes)]  # fmt: skip
    bad = [f"{name} outside the figure" for name, b in boxes
           if b.x0 < -1 or b.y0 < -1 or b.x1 > width + 1 or b.y1 > height + 1]  # fmt: skip
    bad += [f"{n1} on {n2}" for i, (n1, b1) in enumerate(boxes) for n2, b2 in boxes[i + 1 :]
            if _overlaps(b1, b2)]  # fmt: skip
    title = fig._suptitle.get_window_extent(r)
    bad += [f"the figure title on {n}" for n, b in boxes if _overlaps(title, b)]
    for name, ax in zip((n for n, _ in boxes), fig.axes, strict=True):  # inside a panel
        frame = ax.get_window_extent(r)
        for axis in (ax.xaxis, ax.yaxis):
            label = axis.label.get_window_extent(r)
            ticks = [t.get_window_extent(r) for t in axis.get_ticklabels() if t.get_text()]
            if axis.label.get_text() and any(_overlaps(label, t) for t in ticks):
                bad.append(f"{name}: its {axis.axis_name} label on its tick labels")
            if axis.label.get_text() and _overlaps(label, frame):
                bad.append(f"{name}: its {axis.axis_name} label on the panel")
        for t in (ax.title, ax._left_title, ax._right_title):
            box = t.get_window_extent(r)
            if t.get_text() and not frame.y1 - 1 <= box.y0 <= frame.y1 + 20:
                bad.append(f"{name}: title not just above the panel")
    return bad


def test_rows_fill_the_figure_height() -> None:
    from matplotlib.figure import Figure

    rows = [Row(1.4), Row(1.5, 2), Row(1.7, 2), Row(1.7)]
    fig = Figure(figsize=(11, figure_height(rows, 2)))
    panels = place_rows(fig, rows, 2)
    assert [len(p) for p in panels] == [1, 2, 2, 1]
    lowest = min(ax.get_position().y0 for ax in fig.axes)
    assert 0 < lowest * fig.get_size_inches()[1] < 0.7  # the last row's x labels below it


@pytest.mark.parametrize("fixture", ["failing_report", "passing_report"])
def test_check_figure_texts_in_place(fixture: str, request: pytest.FixtureRequest) -> None:
    report: Report = request.getfixturevalue(fixture)
    assert _misplaced(figure(report)) == []


@pytest.mark.skipif(not SMOOTHIE.exists(), reason="needs ../shared")
def test_real_capture_two_axes_texts_in_place() -> None:
    from matplotlib.figure import Figure

    report = check(SMOOTHIE, "gecko-g202", map={"step": "5", "dir": "6"}, pictures=True)
    fig = figure(report)
    assert isinstance(fig, Figure) and len(fig.axes) >= 4
    assert _misplaced(fig) == []


@pytest.mark.skipif(not SMOOTHIE.exists(), reason="needs ../shared")
def test_measure_figure_texts_in_place(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    from wavecheck.cli import main
    from wavecheck.report import layout

    drawn: list[Any] = []
    monkeypatch.setattr(layout, "figure_bytes", lambda fig, fmt: drawn.append(fig) or b"")
    args = ["measure", str(SMOOTHIE), "--map", "x.step=5,x.dir=6", "--map", "y.step=3,y.dir=4"]
    assert main([*args, "--plot", str(tmp_path / "m.png")]) == 0
    (fig,) = drawn
    assert len(fig.axes) == 4 + 6  # two motion rows, six histograms
    assert _misplaced(fig) == []
