"""Role inference over every capture of ``../shared/captures/sigrok-dumps`` (all protocols):
no stepper axis on a capture that carries none, the stepper captures mapped as their READMEs
say, quadrature (graycode, a mouse sensor's XA/XB) as phase axes only
(:mod:`tools.roles_corpus` prints the same, with the totals)."""

from __future__ import annotations

import os
from fractions import Fraction

import pytest

from tests.conftest import SHARED_CAPTURES
from tools.roles_corpus import _expected, dirs_kept, judge
from wavecheck.capture.open import open_capture
from wavecheck.errors import WavecheckError
from wavecheck.roles import propose

from ..waves import renamed

ROOT = SHARED_CAPTURES / "sigrok-dumps"
CAPTURES = sorted(
    p.relative_to(ROOT).as_posix() for p in [*ROOT.rglob("*.sr"), *ROOT.rglob("*.vcd")]
)
STEPPERS = [c for c in CAPTURES if c.startswith("stepper_motor/") or "smoothieware" in c]


def test_the_corpus_is_there() -> None:
    if not CAPTURES and os.environ.get("CI") != "true":
        pytest.skip(f"no captures under {ROOT}")
    assert len(CAPTURES) >= 60 and len(STEPPERS) >= 3


@pytest.mark.parametrize("rel", CAPTURES)
def test_no_role_the_waveform_contradicts(rel: str) -> None:
    # the smoothieware snippet without a sample rate is the 12 MHz one (its README, metadata)
    rate = Fraction(12_000_000) if rel.endswith("smoothieware_snippet_no_samplerate.sr") else None
    try:
        cap = open_capture(ROOT / rel, samplerate=rate)
    except WavecheckError as err:  # refused with its reason (no sample rate, 32 probes in 8 bits)
        pytest.skip(f"unread: {err}")
    p = propose(cap)
    carries, verdict = judge(rel, p)
    assert verdict != "wrong"
    assert dirs_kept(rel, p) is not False, p.text()  # a (suggested) map drops no README DIR
    if carries == "quadrature":
        assert verdict == "right"
    if carries == "steps" and verdict != "right":
        # refused only where a STEP line has too few pulses to tell from a reset or interrupt
        # line (the full smoothieware trace: 3 and 7 pulses), naming them as candidates
        expected = _expected(rel)
        assert verdict == "refused" and expected is not None
        steps = {a["step"] for a in expected[0]}
        assert steps <= {cap.channel(c).index for c in p.candidates}, p.text()
        assert all(len(cap.channels[s].edges) < 2 * 9 for s in steps)


#: the two captures of the same Smoothieware machine: Y = STEP 3 / DIR 4, X = STEP 5 / DIR 6
SMOOTHIE = [
    "stepper_motor/smoothieware/smoothieware_snippet.sr",
    "arm_trace/lpc1769/smoothieware.sr",
]


@pytest.mark.parametrize("rel", SMOOTHIE)
def test_a_suggested_map_keeps_every_dir(rel: str) -> None:
    """Issue 33: a suggested map never drops a DIR the capture has. The snippet's axes are
    proposed (DIRs by layout: they never change); the full trace's STEP lines (3 and 7 pulses)
    are too few to tell from a reset or interrupt line, so it is refused, but its hint is the
    map of both axes with both DIRs, and that map checks."""
    path = ROOT / rel
    if not path.exists():
        pytest.skip(f"no capture {path}")
    p = propose(open_capture(path))
    axes = p.axes or p.suggested
    assert [a.mapping for a in axes] == [{"step": "3", "dir": "4"}, {"step": "5", "dir": "6"}]
    assert all(a.role("dir").basis == "layout" for a in axes)  # type: ignore[union-attr]
    if not p.axes:
        assert not p.ambiguous
        hint = p.hint()
        assert "3='3' (a few pulses: 3 pulses), 5='5' (a few pulses: 7 pulses)" in hint
        assert "no line changes between their pulses as a DIR would" in hint
        assert hint.endswith(
            "--map a.step=3,a.dir=4 --map b.step=5,b.dir=6; the DIR of each is the unchanging "
            "channel after it (layout only)"
        )


def test_the_full_smoothieware_trace_reads_with_named_lines() -> None:
    """Named after their roles by the user, the few-pulse STEP lines are read (a name breaks
    what the waveform cannot tell) and the DIRs named like each axis's are kept."""
    path = ROOT / SMOOTHIE[1]
    if not path.exists():
        pytest.skip(f"no capture {path}")
    cap = renamed(open_capture(path), ["SWO", "1", "2", "Y_STEP", "Y_DIR", "X_STEP", "X_DIR", "7"])
    p = propose(cap)
    assert p.unambiguous, p.text()
    assert {a.name: a.mapping for a in p.axes} == {
        "y": {"step": "Y_STEP", "dir": "Y_DIR"},
        "x": {"step": "X_STEP", "dir": "X_DIR"},
    }
