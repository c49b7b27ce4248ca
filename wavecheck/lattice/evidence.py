"""Positive evidence that a lattice is a step generator's base thread, not another periodic clock.

A lattice alone says only that some periodic clock times the edges: a sensor's frame clock (an
optical mouse's quadrature outputs change once per frame) fits one as well as a base thread. What
a base thread running a step generator adds: its steps follow a motion. Software stepgen's
commanded frequency changes by at most max_ac·dt per servo period and its DDS rate ramps toward
it by ``deltalim`` per base period (``stepgen-linuxcnc.md`` §4 steps 7–9 and §2.1 step 2), and at
a DDS rate v (steps per period) it steps every ⌊1/v⌋ or ⌈1/v⌉ invocations (§2.1 step 3). So the interval between successive edges of
one kind (a channel rising, or falling), counted in invocations, changes gradually: successive
intervals differ by at most one invocation, or an eighth of the interval at low speed, except
where the motion starts, stops or reverses. A sensor's outputs follow a hand's motion, noisier:
the ADNS-2051 mouse capture in sigrok-dumps has 79 % of its intervals change gradually, stepgen's
sweep 88 % or more, but a short stepgen move that is all ramp (``captures/golden/updown-uniform``)
only 81 %: the share alone separates them by little. Step types 0 and 1 show more: their pulses
last exactly ``steplen`` periods at every rate (:func:`steady_pulse`). A lattice counts as a step
generator's thread with such pulses, or else (a quadrature pair) with the gradual share.
"""

from __future__ import annotations

import numpy as np

from wavecheck.lattice.reading import Ints

__all__ = ["MIN_MOTION_SHARE", "MIN_PAIRS", "motion_share", "steady_pulse"]

#: Share of successive intervals (per edge kind, in invocations) that must change gradually.
MIN_MOTION_SHARE = 0.85


#: Fewest pairs of successive intervals from which the share counts.
MIN_PAIRS = 32


def motion_share(invocation: Ints, bits: Ints, kinds: int) -> tuple[float, int]:
    """(share of gradual changes, pairs counted) of the intervals between successive edges of
    each kind (bit c of ``bits`` set: kind c changed at that edge; ``kinds`` kinds), counted in
    invocations ``invocation``. A change is gradual when successive intervals differ by at most
    max(1, the shorter / 8) invocations."""
    gradual = pairs = 0
    for c in range(kinds):  # a few kinds (two per channel)
        k = invocation[((bits >> c) & 1) == 1]
        if len(k) < 3:
            continue
        gap = np.diff(k)
        shorter = np.minimum(gap[1:], gap[:-1])
        gradual += int(np.count_nonzero(np.abs(np.diff(gap)) <= np.maximum(1, shorter // 8)))
        pairs += len(gap) - 1
    return (gradual / pairs if pairs else 0.0), pairs


def steady_pulse(invocation: Ints, bits: Ints, channels: int) -> tuple[int, int, int] | None:
    """(channel, level, length) of the first channel whose pulses at one level (1 high, 0 low)
    all last one whole number of invocations (99 % of at least :data:`MIN_PAIRS`) while the
    spaces between them vary, else None. Step types 0 and 1 hold STEP (UP, DOWN) for exactly
    ``steplen`` periods whatever the step rate (``stepgen-linuxcnc.md`` §2.1 steps 5–6: timer1 =
    steplen, the pin high while it counts down), so their pulses are one length in
    invocations; a sensor's outputs or a quadrature pair have no such level."""
    for c in range(channels):  # a few channels
        fell = ((bits >> (2 * c)) & 1) == 1
        rose = ((bits >> (2 * c + 1)) & 1) == 1
        sel = fell | rose
        k, up = invocation[sel], rose[sel]
        gaps = np.diff(k)
        for level, pulse, space in (
            (1, gaps[up[:-1]], gaps[~up[:-1]]),
            (0, gaps[~up[:-1]], gaps[up[:-1]]),
        ):
            if len(pulse) < MIN_PAIRS or not len(space) or space.min() == space.max():
                continue
            counts = np.bincount(pulse - pulse.min())
            if counts.max() >= 0.99 * len(pulse):
                return c, level, int(pulse.min() + np.argmax(counts))
    return None
