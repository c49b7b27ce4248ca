"""Changing DIRs given to STEP lines (wavecheck.roles.dir_choice, wavecheck.roles.dirs): a DIR
changes between its STEP's pulses, at its reversals; what no matching settles is asked."""

from __future__ import annotations

import numpy as np

from wavecheck.capture.edges import Channel
from wavecheck.roles import propose
from wavecheck.roles.dirs import DirFit, assign

from ..waves import capture, pulses
from .moves import US, move, reversing_axis, roles_of


def test_dir_toggling_inside_a_pulse_is_not_a_dir() -> None:
    starts = move(0, 19)
    step = pulses(starts, 5 * US)
    # toggles 2 µs into the fifth pulse, and between the 12th and 13th
    p = propose(capture({"s": (0, step), "d": (0, [starts[4] + 2 * US, starts[11] + 50 * US])}))
    assert roles_of(p) == {"a": {"step": "s"}}
    assert [u.channel for u in p.unassigned] == ["d"]


def test_two_dirs_and_two_steps_are_paired_by_reversals() -> None:
    xs, xd = reversing_axis(0, [10, 12, 9])
    ys, yd = reversing_axis(37 * US, [7, 8, 15])
    cap = capture(
        {
            "0": (0, pulses(xs, 5 * US)),
            "1": (0, pulses(ys, 4 * US)),
            "2": (0, yd),
            "3": (0, xd),
        }
    )
    p = propose(cap)
    assert p.unambiguous, p.text()
    assert roles_of(p) == {"a": {"step": "0", "dir": "3"}, "b": {"step": "1", "dir": "2"}}
    assert "2 of 2 at reversals of its rate" in p.axis("a").role("dir").evidence


def test_a_change_where_two_steps_pause_is_ambiguous_however_near_to_one() -> None:
    # both lines pause from about 1.6 ms to 3 ms; the single change of "d" is 15 µs after the last
    # pulse of "s" and 1.5 ms before the next one of "t": nearness is no proof, so it is refused
    s_starts = move(0, 12) + move(3000 * US, 12)
    s = pulses(s_starts, 5 * US)
    t = pulses(move(50 * US, 11) + move(3050 * US, 12), 5 * US)
    change = s_starts[11] + 20 * US
    p = propose(capture({"s": (0, s), "t": (0, t), "d": (0, [change])}))
    assert not p.unambiguous
    assert "fits as the DIR of several STEP lines" in p.ambiguous[0].question
    assert all(a.role("dir") is None for a in p.axes)
    # when "t" runs steadily through the change, the change proves "d" is not its DIR
    t2 = pulses(move(50 * US, 44), 5 * US)
    p2 = propose(capture({"s": (0, s), "t": (0, t2), "d": (0, [change])}))
    assert p2.unambiguous, p2.text()
    assert roles_of(p2) == {"a": {"step": "s", "dir": "d"}, "b": {"step": "t"}}
    assert "'t' runs steadily through 1 of its changes" in p2.axis("a").role("dir").evidence


def _fit(d: int, s: int) -> DirFit:
    return DirFit(
        Channel(f"d{d}", d, 0, np.array([1])),
        Channel(f"s{s}", s, 0, np.array([1])),
        1,
        1,
        0,
        (1, 1),
    )


def test_dirs_are_given_only_where_every_matching_agrees() -> None:
    # d1 fits only s1, so d2 (s1 or s2) is s2's
    got = assign({1: [_fit(1, 11)], 2: [_fit(2, 11), _fit(2, 12)]})
    assert {s: f.d.index for s, f in got.chosen.items()} == {11: 1, 12: 2}
    assert not got.undecided and not got.crowded
    # d1 and d2 share s1/s2 in either order, so d3 must be s3's; d1 and d2 stay undecided
    got = assign(
        {
            1: [_fit(1, 11), _fit(1, 12)],
            2: [_fit(2, 11), _fit(2, 12)],
            3: [_fit(3, 11), _fit(3, 12), _fit(3, 13)],
        }
    )
    assert {s: f.d.index for s, f in got.chosen.items()} == {13: 3}
    assert {d: [f.s.index for f in fs] for d, fs in got.undecided.items()} == {
        1: [11, 12],
        2: [11, 12],
    }
    # two lines that can only be s1's: neither is decided; a separate pair still is
    got = assign({1: [_fit(1, 11)], 2: [_fit(2, 11)], 3: [_fit(3, 13)]})
    assert got.crowded == [(1, 2)] and {s: f.d.index for s, f in got.chosen.items()} == {13: 3}
