"""Pulse trains that move as a motor does, for the role tests: each move speeds up and slows
down (a train at one rate is no step train to the waveform: :mod:`wavecheck.roles.periodic`)."""

from __future__ import annotations

import numpy as np

from wavecheck.roles import Proposal

US = 1000  # ticks (ns) per µs

# periods of the first (last) steps of a move, in units of its period: from rest at constant
# acceleration (steps at times proportional to the square roots of 1, 2, 3 …)
_RAMP = (3.7, 1.55, 1.2)


def roles_of(p: Proposal) -> dict[str, dict[str, str]]:
    """Axis name → role → channel of a proposal."""
    return {a.name: {r.role: r.channel for r in a.roles} for a in p.axes}


def move(t0: int, n: int, period: int = 100 * US) -> list[int]:
    """Pulse starts of one move of ``n`` steps after ``t0``: it speeds up over three steps and
    slows down over three (periods 3.7, 1.55, 1.2 × ``period``), as a motor does."""
    factors = [_RAMP[min(k, n - 1 - k)] if min(k, n - 1 - k) < 3 else 1.0 for k in range(n)]
    return [t0 + int(x) for x in np.cumsum(factors) * period]


def reversing_axis(
    t0: int, reversals: list[int], period: int = 100 * US
) -> tuple[list[int], list[int]]:
    """Starts of pulses and DIR toggles of an axis that reverses after the given pulse counts:
    each move speeds up and slows down (:func:`_move`), pauses, and DIR changes 10 µs before the
    next pulse."""
    starts: list[int] = []
    toggles: list[int] = []
    t = t0
    for n in reversals:
        starts += move(t, n, period)
        t = starts[-1] + 5 * period
        toggles.append(t + 3 * period - 10 * US)
    return starts, toggles[:-1]
