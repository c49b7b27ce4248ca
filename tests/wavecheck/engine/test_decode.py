"""Decoding step types 0, 1 and 2–15 into steps with direction and position."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tests.wavecheck.waves import capture, pulses
from wavecheck.errors import ConfigError, UsageError
from wavecheck.steps.decode import active_edges, decode
from wavecheck.steps.interface import build_interface
from wavecheck.steptypes import STATE_TABLES, step_type


def _iface(signals, mapping, invert=()):
    return build_interface(capture(signals), mapping, invert)


def test_step_dir_counts_and_position() -> None:
    # 5 pulses with DIR low (forward), DIR goes high at 5000, then 3 pulses reverse.
    step = pulses([1000, 2000, 3000, 4000, 4500, 6000, 7000, 8000], 100)
    iface = _iface({"STEP": (0, step), "DIR": (0, [5000])}, {"step": "STEP", "dir": "DIR"})
    ev = decode(iface, 0, active_edge="rising")
    assert ev.count == 8
    assert (ev.forward, ev.reverse, ev.final_position) == (5, 3, 2)
    assert ev.position.tolist() == [1, 2, 3, 4, 5, 4, 3, 2]
    assert ev.ticks.tolist() == [1000, 2000, 3000, 4000, 4500, 6000, 7000, 8000]


def test_forward_level_is_configurable() -> None:
    iface = _iface({"S": (0, pulses([10, 30], 5)), "D": (1, [])}, {"step": "S", "dir": "D"})
    assert decode(iface, 0, forward_level=0).final_position == -2
    assert decode(iface, 0, forward_level=1).final_position == 2


def test_falling_active_edge_and_inversion() -> None:
    step = pulses([100, 200, 300], 20)  # falling edges at 120, 220, 320
    iface = _iface({"S": (0, step)}, {"step": "S"})
    assert decode(iface, 0, active_edge="falling").ticks.tolist() == [120, 220, 320]
    inv = _iface({"S": (0, step)}, {"step": "S"}, invert=["step"])
    assert decode(inv, 0, active_edge="falling").ticks.tolist() == [100, 200, 300]
    assert decode(iface, 0, active_edge="both").count == 6


def test_initially_high_step_rising_edges() -> None:
    iface = _iface({"S": (1, [10, 20, 30, 40, 50])}, {"step": "S"})
    assert active_edges(iface.require("step"), "rising").tolist() == [20, 40]
    assert active_edges(iface.require("step"), "falling").tolist() == [10, 30, 50]


def test_dir_change_at_active_edge_is_ambiguous_not_guessed() -> None:
    iface = _iface(
        {"S": (0, pulses([100, 200, 300], 10)), "D": (0, [200])}, {"step": "S", "dir": "D"}
    )
    ev = decode(iface, 0)
    assert ev.direction.tolist() == [1, 0, -1]
    assert ev.ambiguous.tolist() == [200]
    assert ev.unknown == 1
    assert ev.final_position is None


def test_no_dir_channel_means_unknown_direction() -> None:
    iface = _iface({"S": (0, pulses([100, 200], 10))}, {"step": "S"})
    ev = decode(iface, 0)
    assert ev.count == 2 and ev.unknown == 2 and ev.final_position is None


def test_up_down() -> None:
    up = pulses([100, 200, 300], 10)
    down = pulses([500, 600], 10)
    iface = _iface({"UP": (0, up), "DOWN": (0, down)}, {"up": "UP", "down": "DOWN"})
    ev = decode(iface, 1)
    assert ev.position.tolist() == [1, 2, 3, 2, 1]
    assert ev.final_position == 1


def test_up_down_at_the_same_tick_is_ambiguous() -> None:
    iface = _iface(
        {"UP": (0, pulses([100, 200], 10)), "DOWN": (0, pulses([200], 10))},
        {"up": "UP", "down": "DOWN"},
    )
    ev = decode(iface, 1)
    assert ev.count == 2 and ev.ambiguous.tolist() == [200] and ev.direction.tolist() == [1, 0]


def _phase_waveform(states: list[int], n_phases: int, initial: int, period: int = 100):
    """Phase signals that enter ``states[i]`` at tick (i+1)·period, starting from ``initial``."""
    signals = {}
    for bit in range(n_phases):
        init = (initial >> bit) & 1
        level, edges = init, []
        for i, s in enumerate(states):
            v = (s >> bit) & 1
            if v != level:
                edges.append((i + 1) * period)
                level = v
        signals[f"phase-{'ABCDE'[bit]}"] = (init, edges)
    return signals


def _walk(table: tuple[int, ...], moves: list[int]) -> tuple[int, list[int]]:
    idx, states = 0, []
    for m in moves:
        idx = (idx + m) % len(table)
        states.append(table[idx])
    return table[0], states


@pytest.mark.parametrize("number", sorted(STATE_TABLES))
def test_state_tables_decode_to_the_right_position(number: int) -> None:
    stype = step_type(number)
    moves = [1] * 13 + [-1] * 5 + [1, -1, -1]
    initial, states = _walk(stype.states, moves)
    signals = _phase_waveform(states, len(stype.outputs), initial)
    iface = _iface(signals, {r: r for r in stype.outputs})
    ev = decode(iface, number)
    assert ev.count == len(moves)
    assert ev.direction.tolist() == moves
    assert ev.final_position == sum(moves) == 7
    assert len(ev.sequence_errors) == 0
    assert ev.transitions == len(moves)


@settings(max_examples=60, deadline=None)
@given(
    number=st.sampled_from(sorted(STATE_TABLES)),
    moves=st.lists(st.sampled_from([1, -1]), min_size=0, max_size=60),
)
def test_state_tables_random_walks(number: int, moves: list[int]) -> None:
    stype = step_type(number)
    initial, states = _walk(stype.states, moves)
    iface = _iface(
        _phase_waveform(states, len(stype.outputs), initial), {r: r for r in stype.outputs}
    )
    ev = decode(iface, number)
    assert ev.direction.tolist() == moves
    assert ev.final_position == sum(moves)


def test_non_neighbour_state_is_a_sequence_error_not_a_crash() -> None:
    # type 5 (1, 2, 4, 8): 1 → 2 → 8 (skips 4) → 1 → 5 (not in the table) → 1
    signals = _phase_waveform([2, 8, 1, 5, 1], 4, 1)
    iface = _iface(signals, {r: r for r in step_type(5).outputs})
    ev = decode(iface, 5)
    assert ev.sequence_errors.tolist() == [200, 400]
    assert ev.sequence_from.tolist() == [2, 1] and ev.sequence_to.tolist() == [8, 5]
    # 1→2 forward, 8→1 forward (wrap), 5→1 re-synchronises without a step
    assert ev.direction.tolist() == [1, 1]


def test_user_table_type_15() -> None:
    table = (1, 3, 2, 0)
    initial, states = _walk(table, [1, 1, 1, 1, 1, -1])
    iface = _iface(
        _phase_waveform(states, 2, initial), {"phase-A": "phase-A", "phase-B": "phase-B"}
    )
    assert decode(iface, 15, user_table=table).final_position == 4


def test_simultaneous_phase_edges_are_one_transition() -> None:
    # type 6: 3 → 6 changes phase A and phase C at the same tick: one forward step
    signals = _phase_waveform([6, 12], 4, 3)
    iface = _iface(signals, {r: r for r in step_type(6).outputs})
    ev = decode(iface, 6)
    assert ev.count == 2 and ev.final_position == 2 and ev.transitions == 2


def test_errors() -> None:
    iface = _iface({"S": (0, [1, 2])}, {"step": "S"})
    with pytest.raises(ConfigError):
        decode(iface, 16)
    with pytest.raises(UsageError):
        decode(iface, 1)  # up/down not mapped
    with pytest.raises(UsageError):
        decode(iface, 0, forward_level=2)


def test_dir_level_unknown_before_known_from() -> None:
    cap = capture({"S": (0, pulses([100, 300], 10)), "D": (0, [])})
    cap.channels[1].known_from = 200
    iface = build_interface(cap, {"step": "S", "dir": "D"})
    ev = decode(iface, 0)
    assert ev.direction.tolist() == [0, 1]
    assert np.array_equal(ev.ambiguous, [])


@settings(max_examples=200, deadline=None)
@given(
    ticks=st.lists(st.integers(0, 300), unique=True, max_size=80),
    edges=st.lists(st.integers(0, 300), unique=True, max_size=12),
    initial=st.sampled_from([0, 1]),
)
def test_level_before_matches_brute_force_on_both_paths(ticks, edges, initial) -> None:
    from wavecheck.steps.decode import level_before
    from wavecheck.steps.interface import RoleSignal

    t = np.asarray(sorted(ticks), dtype=np.int64)
    e = np.asarray(sorted(edges), dtype=np.int64)
    sig = RoleSignal("dir", "D", initial, e, 0, False)
    level, same = level_before(sig, t)
    want_level = [initial ^ (sum(1 for x in edges if x < ti) & 1) for ti in t.tolist()]
    assert level.tolist() == want_level
    assert same.tolist() == [ti in edges for ti in t.tolist()]
