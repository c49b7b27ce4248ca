"""The motion panels (measure's --plot and check's --plot): position and step rate, reversals marked."""

from __future__ import annotations

from fractions import Fraction

import numpy as np

from wavecheck.engine.trace import StepTrace
from wavecheck.report.measured_plot import draw_motion
from wavecheck.timebase import Timebase


def test_reversals_are_marked_on_both_panels() -> None:
    from matplotlib.figure import Figure

    d = np.array([1, 1, 1, -1, -1, 0, 1, 1], dtype=np.int8)
    trace = StepTrace()
    trace.add(np.arange(8, dtype=np.int64) * 1000, d)
    fig = Figure()
    pos, rate = fig.add_subplot(1, 2, 1), fig.add_subplot(1, 2, 2)
    draw_motion(pos, rate, trace, Timebase(Fraction(1, 10**6)), "x")
    assert pos.get_title(loc="left") == "x: position, 2 reversal(s)"
    for ax in (pos, rate):
        marks = [ln for ln in ax.get_lines() if ln.get_linestyle() == "--"]
        assert sorted(float(m.get_xdata()[0]) for m in marks) == [0.003, 0.006]
    # 1 ms between steps: 1 kHz everywhere
    (points,) = [ln for ln in rate.get_lines() if ln.get_linestyle() != "--"]
    assert np.allclose(points.get_ydata(), 1000.0)
    (line,) = [ln for ln in pos.get_lines() if ln.get_linestyle() != "--"]
    assert list(line.get_ydata()) == [1, 2, 3, 2, 1, 1, 2, 3]
