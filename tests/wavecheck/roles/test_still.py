"""Lines that hold still while the axes move (wavecheck.roles.still): DIRs that never change,
ENABLEs (one shared by several axes, active low)."""

from __future__ import annotations

from wavecheck.roles import propose

from ..waves import capture, pulses
from .moves import US, reversing_axis


def test_shared_enable_and_active_low() -> None:
    xs, xd = reversing_axis(1000 * US, [10, 12])
    ys, yd = reversing_axis(1037 * US, [7, 8])
    last = max(xs[-1], ys[-1]) + 500 * US
    cap = capture(
        {
            "x": (0, pulses(xs, 5 * US)),
            "xd": (0, xd),
            "y": (0, pulses(ys, 5 * US)),
            "yd": (1, yd),
            "en": (1, [500 * US, last]),
        }
    )
    p = propose(cap)
    assert p.unambiguous, p.text()
    assert [s.channel for s in p.shared] == ["en"] and p.shared[0].axes == ("a", "b")
    for a in p.axes:
        assert a.role("enable").active_level == 0 and a.inverted == ("enable",)
