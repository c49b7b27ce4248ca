"""Role inference over every capture of ``../shared/captures/sigrok-dumps`` (all protocols):
no stepper axis on a capture that carries none, the stepper captures mapped as their READMEs
say, quadrature (graycode, a mouse sensor's XA/XB) as phase axes only
(:mod:`tools.roles_corpus` prints the same, with the totals)."""

from __future__ import annotations

import os
from fractions import Fraction

import pytest

from tests.conftest import SHARED_CAPTURES
from tools.roles_corpus import _expected, judge
from wavecheck.capture.open import open_capture
from wavecheck.errors import WavecheckError
from wavecheck.roles import propose

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
