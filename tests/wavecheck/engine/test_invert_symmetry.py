"""An inverted capture checked with its roles inverted gives the plain capture's answer.

``--invert ROLE`` says the drive sees the other level of a channel: a capture whose every level is
flipped (taken after an inverting buffer, or on an active-low input) and checked with every role
inverted shows the drive the same waveform, so every rule, violation, step and rate must be the
same (issue 27: an up/down capture inverted measured ``dir_delay`` from the wrong edges). Where the
pulse level is stated (``--pulse-level``, the level at the generator's output) the mirrored
statement goes with it; where it is not, the waveform shows it (every pulse shorter than every gap).
"""

from __future__ import annotations

from dataclasses import replace
from fractions import Fraction
from typing import Any

import numpy as np
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from tests.wavecheck.engine.test_block_oracle import _drive, captures
from wavecheck.capture.blocks import MemorySource
from wavecheck.capture.edges import Capture, Channel
from wavecheck.engine.options import CheckOptions
from wavecheck.engine.run import check_source
from wavecheck.report.machine import machine_dict
from wavecheck.steps.mapping import AxisMap
from wavecheck.timebase import Timebase


def _flipped(capture: Capture) -> Capture:
    """Every channel's levels flipped (the same edges)."""
    return replace(capture, channels=[replace(c, initial=1 - c.initial) for c in capture.channels])


def _answer(
    capture: Capture, drive: Any, kind: str, o: dict, invert: list[str], level: int | None
) -> dict:
    roles = {c.name: c.name for c in capture.channels}
    options = CheckOptions(
        drive={None: drive}, axes=(AxisMap(None, roles),), step_type={None: o["type"]},
        invert=tuple(invert), active_edge=o["edge"], pulse_level=level,
        forward_level={None: o["forward"]}, user_table=(1, 3, 2, 0) if o["type"] == 15 else None,
    )  # fmt: skip
    (axis,) = machine_dict(check_source(MemorySource(capture), options), 10**6)["axes"]
    return {k: axis[k] for k in ("steps", "rules", "violations", "max_step_rate_hz", "verdict")}


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(captures(), st.integers(0, 1))
def test_a_flipped_capture_with_its_roles_inverted_gives_the_same_answer(
    case: tuple[Capture, str, dict], level: int
) -> None:
    cap, kind, o = case
    # one generator drives the pulse lines alike: both UP and DOWN inverted, or neither (the
    # pulse level is the axis's, not a line's)
    assume(len({"up", "down"} & set(o["invert"])) != 1)
    names = [c.name for c in cap.channels]
    mirror = sorted(set(names) ^ set(o["invert"]))  # every role's inversion the other way
    plain = _answer(cap, o["drive"], kind, o, o["invert"], level)
    assert _answer(_flipped(cap), o["drive"], kind, o, mirror, 1 - level) == plain


def _train(starts: list[int], width: int) -> np.ndarray:
    return np.array([t for s in starts for t in (s, s + width)], dtype=np.int64)


@settings(max_examples=100, deadline=None)
@given(
    st.sampled_from(["rising", "falling"]),
    st.lists(st.integers(3, 40), min_size=3, max_size=12),
    st.lists(st.integers(3, 40), min_size=3, max_size=12),
    st.integers(1, 2),
    st.integers(0, 60),
)
def test_up_down_dir_delay_without_a_stated_pulse_level(
    edge: str, up_gaps: list[int], down_gaps: list[int], width: int, pause: int
) -> None:
    """Pulses of one width, gaps that vary: the waveform shows the pulses' level, so the flipped
    capture with both lines inverted measures dir_delay from the same edges (issue 27's case)."""
    up_gaps, down_gaps = [*up_gaps, 60], [*down_gaps, 60]  # the gaps vary
    up = np.cumsum([5, *up_gaps]) * 10
    down = up[-1] + 10 * pause + 30 + np.cumsum([0, *down_gaps]) * 10
    chans = [Channel("up", 0, 0, _train(up.tolist(), width)),
             Channel("down", 1, 0, _train(down.tolist(), width))]  # fmt: skip
    cap = Capture("ud", "vcd", Timebase(Fraction(1, 10**7)), 0, None, 0, int(down[-1]) + 100, chans)
    drive = _drive({"dir_delay": 300, "step_high": 5, "step_low": 5}, None, "up-down")
    o = {"type": 1, "edge": edge, "forward": 0}
    plain = _answer(cap, drive, "up-down", o, [], None)
    flipped = _answer(_flipped(cap), drive, "up-down", o, ["up", "down"], None)
    assert flipped == plain
    assert plain["rules"][[r["id"] for r in plain["rules"]].index("dir_delay")]["checked"] == 1


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(captures())
def test_a_flipped_capture_gives_the_same_verdicts_without_a_stated_pulse_level(
    case: tuple[Capture, str, dict],
) -> None:
    """Issue 33: no --pulse-level and a waveform that may not show it (one speed): the verdicts
    depend on the signal at the drive's input only (an inverted up/down capture checked with
    --invert up --invert down PASSed with dir_delay unchecked where the plain one FAILed)."""
    cap, kind, o = case
    assume(len({"up", "down"} & set(o["invert"])) != 1)
    names = [c.name for c in cap.channels]
    mirror = sorted(set(names) ^ set(o["invert"]))
    plain = _answer(cap, o["drive"], kind, o, o["invert"], None)
    flipped = _answer(_flipped(cap), o["drive"], kind, o, mirror, None)
    for key in ("steps", "rules", "violations", "verdict"):
        assert flipped[key] == plain[key], key
