"""Which lines may be what (wavecheck.roles.candidates): a line named after another function
is never a STEP on its waveform."""

from __future__ import annotations

from wavecheck.roles import propose

from ..waves import capture, pulses
from .moves import US, move


def test_a_line_named_dir_is_never_a_step() -> None:
    """Issue 33: a generated machine's ``x_dir`` was made the STEP of its own axis. A step
    train named DIR is left out, and asked about when other axes were found."""
    step = pulses(move(0, 19), 5 * US)
    p = propose(capture({"X DIR": (0, step), "X STEP": (0, [1003 * US])}))
    assert not p.axes and "X DIR" in p.candidates
    other = pulses(move(50 * US, 30), 5 * US)
    p = propose(capture({"X DIR": (0, step), "Y STEP": (0, other)}))
    assert p.ambiguous and "named otherwise" in p.ambiguous[0].question
    assert [r.channel for a in p.axes for r in a.roles] == ["Y STEP"]
