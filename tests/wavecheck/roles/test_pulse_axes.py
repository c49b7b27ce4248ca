"""Step/dir axes and up/down pairs of pulse lines (wavecheck.roles.pulse_axes)."""

from __future__ import annotations

from wavecheck.roles import propose

from ..waves import capture, pulses
from .moves import US, move


def test_up_down_pair_refused_when_unchanging_lines_could_be_dirs() -> None:
    up = pulses(move(0, 10), 5 * US)
    down = pulses(move(3000 * US, 10), 5 * US)
    clean = propose(capture({"p": (0, up), "q": (0, down)}))
    assert clean.unambiguous and clean.axes[0].kind == "up-down"
    assert clean.map_args() == "--map up=p,down=q" and clean.type_args() == "--type 1"
    one = propose(capture({"p": (0, up), "q": (0, down), "r": (0, [])}))
    assert one.unambiguous and one.axes[0].kind == "up-down"  # one DIR cannot serve two axes
    spare = propose(capture({"p": (0, up), "q": (0, down), "r": (0, []), "s": (1, [])}))
    assert not spare.unambiguous and not spare.axes
    assert "take turns" in spare.ambiguous[0].question
    named = propose(capture({"X_STEP": (0, up), "Y_STEP": (0, down), "r": (0, []), "s": (0, [])}))
    assert [a.kind for a in named.axes] == ["step-dir", "step-dir"]
