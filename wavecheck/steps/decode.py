"""Decode a step interface into step events: tick, direction and running position.

All times are integer ticks of the capture's :class:`~wavecheck.timebase.Timebase`; levels are at
the drive's input (after ``--invert``).

- Type 0 (step/dir): one step per active STEP edge (the drive's ``active_edge``: rising, falling
  or both). The direction is the DIR level just before the active edge; ``forward_level`` says
  which DIR level is forward (default 0, LinuxCNC's and grbl's convention: DIR = 1 when moving
  negative). A DIR change at the same tick as an active edge makes that step's direction
  ambiguous: its direction is 0 and it is listed in :attr:`StepEvents.ambiguous` (the checks
  report it as both a ``dir_setup`` and a ``dir_hold`` interval of 0). Steps inside an unknown
  stretch of DIR (``x`` at the start of a VCD up to the tick its level becomes known, or a later
  ``x``/``z`` up to the tick a known value comes back), or of STEP itself (the edge ending such a
  stretch may be a hidden one), or with no DIR mapped, also have direction 0 ("unknown").
- Type 1 (up/down): one forward step per active UP edge, one reverse step per active DOWN edge.
  Active edges of UP and DOWN at the same tick are ambiguous.
- Types 2–15 (state tables of :mod:`wavecheck.steptypes`): the phase outputs form a state at every
  tick where any phase changes; a move to the next state in the table is a forward step, to the
  previous one a reverse step. Any other move (a non-neighbour, or a state not in the table) is a
  ``state_sequence`` error, listed in :attr:`StepEvents.sequence_errors`, not a crash. Moving
  from a state not in the table back into it re-synchronises without a step or a second error.
  While a phase is not known (``x``/``z``, up to and including the tick a known value comes
  back), the state is not known: state changes inside a phase's unknown stretch are not decoded.

Everything is vectorised over the whole edge arrays (numpy ``searchsorted`` / ``diff``).
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import TYPE_CHECKING

import numpy as np

from wavecheck.capture.edges import EdgeArray
from wavecheck.drives.datasheet import ActiveEdge
from wavecheck.errors import UsageError
from wavecheck.record import field, record
from wavecheck.steps.interface import RoleSignal, StepInterface
from wavecheck.steptypes import StepType, step_type

if TYPE_CHECKING:
    import numpy.typing as npt

__all__ = [
    "StepEvents",
    "active_edges",
    "decode",
    "in_stretches",
    "level_before",
    "phase_states",
    "touches_stretches",
    "unknown_stretches",
]

_EMPTY = np.zeros(0, dtype=np.int64)


def _empty() -> EdgeArray:
    return _EMPTY.copy()


@record
class StepEvents:
    """The steps of one interface.

    Attributes:
        ticks: tick of each step (the active edge, or the state change), increasing.
        direction: ``+1`` forward, ``-1`` reverse, ``0`` unknown or ambiguous (int8, one per step).
        position: running position after each step (int64; unknown steps count 0).
        ambiguous: ticks of steps whose direction is ambiguous (DIR changed at the same tick, or
            UP and DOWN pulsed together).
        sequence_errors: ticks of state-table moves that are not to a neighbour state.
        sequence_from: the state value before each sequence error.
        sequence_to: the state value after each sequence error.
        transitions: number of state changes examined (types 2–15; 0 otherwise).
    """

    ticks: EdgeArray
    direction: npt.NDArray[np.int8]
    position: EdgeArray
    ambiguous: EdgeArray = field(default_factory=_empty)
    sequence_errors: EdgeArray = field(default_factory=_empty)
    sequence_from: EdgeArray = field(default_factory=_empty)
    sequence_to: EdgeArray = field(default_factory=_empty)
    transitions: int = 0

    @property
    def count(self) -> int:
        """Number of steps."""
        return int(len(self.ticks))

    @property
    def ambiguous_count(self) -> int:
        """Number of steps of ambiguous direction."""
        return int(len(self.ambiguous))

    @property
    def forward(self) -> int:
        """Number of forward steps."""
        return int(np.count_nonzero(self.direction > 0))

    @property
    def reverse(self) -> int:
        """Number of reverse steps."""
        return int(np.count_nonzero(self.direction < 0))

    @property
    def unknown(self) -> int:
        """Number of steps of unknown or ambiguous direction."""
        return self.count - self.forward - self.reverse

    @property
    def final_position(self) -> int | None:
        """forward − reverse, or None when any step's direction is unknown."""
        if self.unknown:
            return None
        return self.forward - self.reverse


def active_edges(sig: RoleSignal, edge: ActiveEdge) -> EdgeArray:
    """Ticks of ``sig``'s active edges (a view into its edge array where possible)."""
    if edge == "both":
        return sig.edges
    first_rising = 0 if sig.initial == 0 else 1
    start = first_rising if edge == "rising" else 1 - first_rising
    return sig.edges[start::2]


def level_before(
    sig: RoleSignal, ticks: EdgeArray
) -> tuple[npt.NDArray[np.int8], npt.NDArray[np.bool_]]:
    """The level of ``sig`` just before each tick, and whether it changes exactly at that tick."""
    edges = sig.edges
    if len(edges) == 0:
        return np.full(len(ticks), sig.initial, dtype=np.int8), np.zeros(len(ticks), dtype=np.bool_)
    if len(ticks) > 8 * len(edges):
        # Few signal edges, many ticks: place each edge among the ticks instead (O(n) cumsum).
        after = np.searchsorted(ticks, edges, side="right")  # first tick strictly after the edge
        n = np.cumsum(np.bincount(after, minlength=len(ticks) + 1)[: len(ticks)])
        at = np.searchsorted(ticks, edges, side="left")
        hit = at < len(ticks)
        hit[hit] = ticks[at[hit]] == edges[hit]
        same = np.zeros(len(ticks), dtype=np.bool_)
        same[at[hit]] = True
    else:
        # here, not at the top: the checks package imports this module
        from wavecheck.steps.primitives import sorted_search

        n = sorted_search(edges, ticks, "left")  # dense edges: counted, not searched
        clipped = np.minimum(n, len(edges) - 1)
        same = (n < len(edges)) & (edges[clipped] == ticks)
    level = (sig.initial ^ (n & 1)).astype(np.int8)
    return level, same


def unknown_stretches(iface: StepInterface, roles: Iterable[str]) -> tuple[EdgeArray, EdgeArray]:
    """The union of the unknown stretches of the mapped ``roles``: disjoint closed tick ranges
    ``[starts[i], ends[i]]`` in time order (:meth:`wavecheck.capture.edges.Channel.unknown_stretches`)."""
    parts = [s.unknown for s in (iface.get(r) for r in roles) if s is not None]
    starts = np.concatenate([p[0] for p in parts]) if parts else _empty()
    ends = np.concatenate([p[1] for p in parts]) if parts else _empty()
    if len(starts) <= 1:
        return starts.astype(np.int64), ends.astype(np.int64)
    order = np.argsort(starts, kind="stable")
    starts, ends = starts[order], ends[order]
    reach = np.maximum.accumulate(ends)
    new = np.ones(len(starts), dtype=np.bool_)
    new[1:] = starts[1:] > reach[:-1]
    first = np.flatnonzero(new)
    last = np.concatenate([first[1:], [len(starts)]]) - 1
    return starts[first], reach[last]


def in_stretches(ticks: EdgeArray, starts: EdgeArray, ends: EdgeArray) -> npt.NDArray[np.bool_]:
    """Whether each tick lies in one of the disjoint closed ranges ``[starts[i], ends[i]]``."""
    return touches_stretches(ticks, ticks, starts, ends)


def touches_stretches(
    a: EdgeArray, b: EdgeArray, starts: EdgeArray, ends: EdgeArray
) -> npt.NDArray[np.bool_]:
    """Whether each closed interval ``[a[j], b[j]]`` overlaps one of the disjoint closed ranges
    ``[starts[i], ends[i]]`` (in time order)."""
    if len(starts) == 0:
        return np.zeros(len(a), dtype=np.bool_)
    k = np.searchsorted(ends, a, side="left")  # the first range not ending before a
    hit = k < len(ends)
    hit[hit] = starts[k[hit]] <= b[hit]
    return hit


def _positions(direction: npt.NDArray[np.int8]) -> EdgeArray:
    return np.cumsum(direction, dtype=np.int64)


def _decode_step_dir(iface: StepInterface, edge: ActiveEdge, forward_level: int) -> StepEvents:
    step = iface.require("step")
    ticks = active_edges(step, edge)
    dir_sig = iface.get("dir")
    if dir_sig is None:
        direction = np.zeros(len(ticks), dtype=np.int8)
        return StepEvents(ticks, direction, _positions(direction))
    level, same = level_before(dir_sig, ticks)
    direction = np.where(level == forward_level, 1, -1).astype(np.int8)
    unknown = same | in_stretches(ticks, *unknown_stretches(iface, ("step", "dir")))
    direction[unknown] = 0
    return StepEvents(ticks, direction, _positions(direction), ambiguous=ticks[same])


def _decode_up_down(iface: StepInterface, edge: ActiveEdge) -> StepEvents:
    up = active_edges(iface.require("up"), edge)
    down = active_edges(iface.require("down"), edge)
    ticks = np.concatenate([up, down])
    sign = np.concatenate([np.ones(len(up), np.int8), -np.ones(len(down), np.int8)])
    order = np.argsort(ticks, kind="stable")
    ticks, direction = ticks[order], sign[order]
    # UP and DOWN active at the same tick: one event of ambiguous direction.
    dup = np.flatnonzero(ticks[1:] == ticks[:-1])
    ambiguous = ticks[dup]
    if len(dup):
        direction[dup] = 0
        keep = np.ones(len(ticks), dtype=np.bool_)
        keep[dup + 1] = False
        ticks, direction = ticks[keep], direction[keep]
    return StepEvents(ticks, direction, _positions(direction), ambiguous=ambiguous)


def phase_states(
    iface: StepInterface, outputs: tuple[str, ...]
) -> tuple[EdgeArray, EdgeArray, int]:
    """The combined phase state (phase A = bit 0) after every tick where any phase changes.

    Returns:
        (ticks, states, initial_state): ``states[i]`` holds from ``ticks[i]`` on; edges of
        several phases at the same tick make one change.
    """
    sigs = [iface.require(role) for role in outputs]
    ticks = np.unique(np.concatenate([s.edges for s in sigs])) if sigs else _empty()
    states = np.zeros(len(ticks), dtype=np.int64)
    initial = 0
    for bit, sig in enumerate(sigs):
        n = np.searchsorted(sig.edges, ticks, side="right")
        states |= ((sig.initial ^ (n & 1)) & 1).astype(np.int64) << bit
        initial |= (sig.initial & 1) << bit
    return ticks, states, initial


def _decode_table(iface: StepInterface, st: StepType) -> StepEvents:
    ticks, states, initial = phase_states(iface, st.outputs)
    prev_states = np.concatenate([[initial], states[:-1]]).astype(np.int64)
    unknown = unknown_stretches(iface, st.outputs)
    if len(unknown[0]):  # the state is known only where every phase is
        known = ~in_stretches(ticks, *unknown)
        ticks, states, prev_states = ticks[known], states[known], prev_states[known]
    cycle = st.cycle
    lookup = np.full(32, -1, dtype=np.int64)
    lookup[np.asarray(st.states, dtype=np.int64)] = np.arange(cycle, dtype=np.int64)
    a = lookup[prev_states]
    b = lookup[states]
    delta = np.mod(b - a, cycle)
    both = (a >= 0) & (b >= 0)
    fwd = both & (delta == 1)
    rev = both & (delta == cycle - 1) & ~fwd
    if cycle == 2:  # a two-state user table cannot tell forward from reverse
        amb = both & (delta == 1)
        fwd = rev = np.zeros_like(fwd)
    else:
        amb = np.zeros_like(fwd)
    bad = (b < 0) | (both & ~fwd & ~rev & ~amb)
    is_step = fwd | rev | amb
    direction = np.where(fwd, 1, np.where(rev, -1, 0)).astype(np.int8)[is_step]
    return StepEvents(
        ticks=ticks[is_step],
        direction=direction,
        position=_positions(direction),
        ambiguous=ticks[amb],
        sequence_errors=ticks[bad],
        sequence_from=prev_states[bad],
        sequence_to=states[bad],
        transitions=int(len(ticks)),
    )


def decode(
    iface: StepInterface,
    type_number: int = 0,
    *,
    active_edge: ActiveEdge = "rising",
    forward_level: int = 0,
    user_table: tuple[int, ...] | None = None,
) -> StepEvents:
    """Decode ``iface`` as LinuxCNC step type ``type_number`` (0–15).

    Args:
        iface: the mapped signals, levels at the drive's input.
        type_number: 0 step/dir, 1 up/down, 2–14 built-in state tables, 15 ``user_table``.
        active_edge: the STEP (or UP/DOWN) edge on which the drive counts a step.
        forward_level: the DIR level (0 or 1) that means forward (type 0 only).
        user_table: state values for type 15 (phase A = bit 0).

    Raises:
        UsageError: a role the type needs is not mapped, or ``forward_level`` is not 0 or 1.
        ConfigError: an unknown type or a bad user table.
    """
    if forward_level not in (0, 1):
        raise UsageError(f"DIR forward level must be 0 or 1, got {forward_level!r}")
    st = step_type(type_number, user_table)
    if st.kind == "step-dir":
        return _decode_step_dir(iface, active_edge, forward_level)
    if st.kind == "up-down":
        return _decode_up_down(iface, active_edge)
    return _decode_table(iface, st)
