"""One block or many: the engine gives the same report, field for field, at any block size.

The oracle is the engine fed the whole capture as one block and checking it as one window
(every interval in memory at once); against it, the same capture cut into blocks
(:class:`wavecheck.capture.blocks.MemorySource`) from one event per block up, each window checked
as it gathers. Compared: the whole JSON report (every rule's counts, margins and where, unknown
places, the violations list, steps, rates, notes) plus each rule's histogram — nothing is left
out as "a summary". (:mod:`tests.reliability.test_reference_agreement` holds the one-window
figures against a plain per-interval reference.)
"""

from __future__ import annotations

from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tests.wavecheck.engine.corpus import GOLDEN, GOLDEN_CASES, SHARED, engine_check
from wavecheck.capture.blocks import WHOLE, MemorySource
from wavecheck.capture.edges import NEVER, Capture, Channel
from wavecheck.capture.open import open_capture
from wavecheck.drives.datasheet import Drive, Figure
from wavecheck.drives.library import load_drive
from wavecheck.engine.outcome import MachineReport
from wavecheck.report.machine import machine_dict
from wavecheck.steps.mapping import AxisMap
from wavecheck.timebase import Timebase


def _drive(
    limits: dict[str, int], max_rate_hz: Fraction | None, interface: str = "step-dir"
) -> Drive:
    fig = {k: Figure(Fraction(v), "test", "datasheet") for k, v in limits.items()}
    rate = Figure(max_rate_hz, "test", "datasheet") if max_rate_hz else None
    return Drive("t", "test drive", Path("t.toml"), "user", interface, "rising", fig, rate)  # type: ignore[arg-type]


def _check(
    capture: Capture, axes: list[AxisMap], drives: dict, block: int, **kw: object
) -> MachineReport:
    """The engine on ``capture`` cut into blocks of about ``block`` edges, a window each."""
    return engine_check(MemorySource(capture, block), axes, drives, block, **kw)


def _same(capture: Capture, axes: list[AxisMap], drives: dict, block: int, **kw: object) -> None:
    whole = _check(capture, axes, drives, WHOLE, **kw)
    streamed = _check(capture, axes, drives, block, **kw)
    assert machine_dict(streamed, 10**6) == machine_dict(whole, 10**6)
    for a, b in zip(whole.axes, streamed.axes, strict=True):
        assert all(r.histogram() is not None for r in a.rules)  # pictures: kept
        assert [r.histogram() for r in a.rules] == [r.histogram() for r in b.rules]
        for ra, rb in zip(a.rules, b.rules, strict=True):
            assert ra.max_measured_ns == rb.max_measured_ns
            assert ra.decide_samplerate_hz == rb.decide_samplerate_hz


# -- the corpus -------------------------------------------------------------------------------


@pytest.mark.parametrize("block", [1, 2, 7, 64, 10**9])
@pytest.mark.parametrize(("name", "drive", "typ"), GOLDEN_CASES)
def test_golden_traces(name: str, drive: str, typ: int | None, block: int) -> None:
    cap = open_capture(GOLDEN / name)
    _same(cap, [AxisMap(None, {})], {None: load_drive(drive)}, block,
          step_types={None: typ} if typ is not None else None)  # fmt: skip


def test_type15_and_every_phase_rule() -> None:
    cap = open_capture(GOLDEN / "user-type15-velocity.vcd")
    drive = _drive({"state_hold": 120_000}, Fraction(3000))
    for block in (1, 3, 50, 10**9):
        _same(cap, [AxisMap(None, {})], {None: drive}, block,
              step_types={None: 15}, user_table=(1, 3, 2, 6, 4, 5))  # fmt: skip


def test_updown_dir_delay() -> None:
    cap = open_capture(GOLDEN / "updown-uniform.vcd")
    drive = _drive(
        {"step_high": 30_000, "step_low": 20_000, "dir_delay": 200_000}, Fraction(9000), "up-down"
    )
    for block in (1, 2, 5, 10**9):
        _same(cap, [AxisMap(None, {})], {None: drive}, block, step_types={None: 1})


GRBL = SHARED / "sigrok-dumps" / "stepper_motor" / "grbl_cnc" / "grbl_cnc_1.sr"


@pytest.mark.skipif(not GRBL.exists(), reason="shared captures not present")
def test_real_grbl_capture_two_axes() -> None:
    cap = open_capture(GRBL)
    names = [c.name for c in cap.channels]
    assert len(names) >= 4
    axes = [
        AxisMap("x", {"step": names[0], "dir": names[1]}),
        AxisMap("y", {"step": names[2], "dir": names[3]}),
    ]
    drive = load_drive("gecko-g202")
    for block in (997, 1 << 16):
        _same(cap, axes, {"x": drive, "y": drive}, block)


# -- hypothesis captures -----------------------------------------------------------------------------
@st.composite
def captures(draw: st.DrawFn) -> tuple[Capture, str, dict]:
    kind = draw(st.sampled_from(["step-dir", "up-down", "phases"]))
    horizon = draw(st.integers(5, 60))
    names = {"step-dir": ["step", "dir", "enable"], "up-down": ["up", "down", "enable"],
             "phases": ["phase-A", "phase-B"]}[kind]  # fmt: skip
    chans = []
    for i, name in enumerate(names):
        edges = sorted(
            set(draw(st.lists(st.integers(0, horizon), max_size=draw(st.sampled_from([3, 8, 30])))))
        )
        known_from = 0
        xz_t: list[int] = []
        xz_e: list[int] = []
        if draw(st.integers(0, 4)) == 0:  # unknown at the start, or an x/z stretch later
            known_from = draw(st.integers(0, horizon))
            edges = [e for e in edges if e > known_from]
        if edges and draw(st.integers(0, 4)) == 0:
            a = draw(st.integers(known_from, horizon))
            b = draw(st.one_of(st.just(NEVER), st.integers(a + 1, horizon + 2)))
            xz_t, xz_e = [a], [b]
            edges = [e for e in edges if not a <= e < (b if b != NEVER else NEVER)]
        chans.append(Channel(name, i, draw(st.integers(0, 1)), np.array(edges, np.int64), known_from,
                             np.array(xz_t, np.int64), np.array(xz_e, np.int64)))  # fmt: skip
    cap = Capture("hyp", "vcd", Timebase(Fraction(1, 10**7)), draw(st.sampled_from([0, 1, 2])),
                  None, 0, horizon + 3, chans)  # fmt: skip
    limits = {r: 100 * draw(st.integers(0, 12)) for r in
              ("step_high", "step_low", "dir_setup", "dir_hold", "dir_delay", "state_hold", "enable_setup")
              if draw(st.integers(0, 4))}  # fmt: skip
    rate = Fraction(10**9, 100 * draw(st.integers(1, 20))) if draw(st.booleans()) else None
    opts = {
        "drive": _drive(limits, rate, kind),
        "type": {"step-dir": 0, "up-down": 1, "phases": draw(st.sampled_from([2, 15]))}[kind],
        "edge": draw(st.sampled_from(["rising", "falling", "both"])),
        "invert": draw(st.lists(st.sampled_from(names), max_size=2, unique=True)),
        "pulse_level": draw(st.integers(0, 1)),
        "forward": draw(st.integers(0, 1)),
        "block": draw(st.integers(1, 12)),
    }
    return cap, kind, opts


@settings(max_examples=400, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(captures())
def test_hypothesis_captures(case: tuple[Capture, str, dict]) -> None:
    cap, kind, o = case
    user = (1, 3, 2, 0) if o["type"] == 15 else None
    roles = {c.name: c.name for c in cap.channels}
    _same(cap, [AxisMap(None, roles)], {None: o["drive"]}, o["block"],
          step_types={None: o["type"]}, forward_levels={None: o["forward"]},
          invert={None: o["invert"]}, active_edge=o["edge"], pulse_level=o["pulse_level"],
          user_table=user)  # fmt: skip


def _ch(name: str, index: int, initial: int, edges: list[int]) -> Channel:
    return Channel(name, index, initial, np.array(edges, np.int64))


#: Each case needs one context rule of the engine (:meth:`wavecheck.engine.axis.AxisCheck._context`):
#: dropping that rule makes one fail (checked by mutating the engine when it was written).
CONTEXT_CASES = [
    # dir_setup: DIR changes before the first step all wait for it
    ("step-dir", [("step", 0, [10, 12]), ("dir", 0, [1, 5])], {"dir_setup": 300}, 0),
    # enable_setup: ENABLE rose long before the first step
    (
        "step-dir",
        [("step", 0, [20, 22]), ("dir", 0, [3, 6, 9]), ("enable", 0, [2])],
        {"enable_setup": 100},
        0,
    ),
    # dir_delay: a DOWN pulse still open while UP pulses; it ends later
    ("up-down", [("up", 0, [5, 6, 8, 9, 11, 12]), ("down", 0, [2, 20])], {"dir_delay": 100}, 1),
    # dir_delay: the last pulse ended long before the next one on the other line
    ("up-down", [("up", 0, [10, 11]), ("down", 0, [2, 4])], {"dir_delay": 100}, 1),
]


@pytest.mark.parametrize("block", [1, 2, 3])
@pytest.mark.parametrize(("kind", "chans", "limits", "typ"), CONTEXT_CASES)
def test_context_cases(kind: str, chans: list, limits: dict, typ: int, block: int) -> None:
    cap = Capture("c", "vcd", Timebase(Fraction(1, 10**7)), 0, None, 0, 30,
                  [_ch(n, i, lv, e) for i, (n, lv, e) in enumerate(chans)])  # fmt: skip
    roles = {n: n for n, _, _ in chans}
    _same(cap, [AxisMap(None, roles)], {None: _drive(limits, None, kind)}, block,
          step_types={None: typ})  # fmt: skip


def test_dir_changes_piling_up_without_steps_are_gone_over_log_n_times(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A DIR line that toggles 60,000 times before any step (a clock mapped as DIR): every change
    waits for the next step (dir_setup), so the context holds them all; windows then wait for as
    many new edges as are held, so they are few, and the figures still equal the whole path's."""
    from wavecheck.engine import axis as engine

    calls = 0
    original = engine.AxisCheck.window

    def counted(self: engine.AxisCheck, t1: int) -> None:
        nonlocal calls
        calls += 1
        original(self, t1)

    monkeypatch.setattr(engine.AxisCheck, "window", counted)
    dir_edges = np.arange(1, 60_001, dtype=np.int64) * 10
    steps = 600_100 + np.arange(0, 40, dtype=np.int64) * 100  # then 20 pulses, 50 ticks high
    cap = Capture(
        path="pile-up", format="vcd", timebase=Timebase(Fraction(1, 10**9)), resolution_ticks=0,
        samplerate_hz=None, start=0, end=700_000,
        channels=[Channel("step", 0, 0, steps.copy()), Channel("dir", 1, 0, dir_edges)],
    )  # fmt: skip
    drive = _drive({"step_high": 10, "step_low": 10, "dir_setup": 5, "dir_hold": 5}, None)
    axes = [AxisMap(None, {"step": "step", "dir": "dir"})]
    _same(cap, axes, {None: drive}, 500)
    assert calls <= 2 * 20 + 1  # the one-window run once, the blocks ~log2(60000/500) + a few
