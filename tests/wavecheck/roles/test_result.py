"""The proposal (wavecheck.roles.result, wavecheck.roles.proposal): the --map text, quoted,
with channel indices where names cannot be written."""

from __future__ import annotations

from wavecheck.roles import propose

from ..waves import capture, pulses
from .moves import US, move


def test_map_args_quote_and_fall_back_to_indices() -> None:
    step = pulses(move(0, 19), 5 * US)
    assert propose(capture({"S,1": (0, step)})).map_args() == "--map step=0"
    named = propose(capture({"STEP (Y axis)": (0, step), "Y DIR": (0, [])}))
    assert named.map_args() == "--map 'step=STEP (Y axis),dir=Y DIR'"
    assert named.axis("y").role("dir").basis == "name"
