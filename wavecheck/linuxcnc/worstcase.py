"""LinuxCNC's worst case for one timing rule: which make-pulses invocations run on time.

``stepgen simulate --latency worst:J:RULE`` (:mod:`stepgen.lateness`) runs every invocation J late
except those that make an *end* event of RULE's intervals, so that each interval lasts n·P − J
(the Stepper Tuning chapter's reasoning, ``stepgen-linuxcnc.md`` §9). ``wavecheck latency``
(:mod:`wavecheck.lattice`) reads such a capture back by recognising that the on-time edges are
exactly these events. Both call :func:`end_events`, on invocation indices or on edge times.

End events by rule: ``step_high`` the falling edges of the pulse lines (STEP; UP and DOWN),
``step_low`` their rising edges, ``step_period`` every second active edge (the interval starts
and ends with one), ``dir_setup`` the first active edge at or after each DIR change,
``dir_hold`` the DIR changes (type 0), ``dir_delay`` the first active edge on the other line at
each switch between UP and DOWN (type 1), ``state_hold`` (and ``step_period``) every second
state change of a phase type.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import numpy.typing as npt

from wavecheck.rules import RULES as TABLE
from wavecheck.rules import rule as rule_of
from wavecheck.steptypes import StepKind

__all__ = ["PHASE_RULES", "WORST_RULES", "end_events", "union"]

Ints = npt.NDArray[np.int64]

#: The rules ``worst:J:RULE`` can target: every interval rule whose intervals stepgen's own
#: invocations end (not state_sequence, which has none, nor enable_setup: stepgen has no ENABLE).
WORST_RULES: tuple[str, ...] = tuple(
    r.id for r in TABLE if r.check != "sequence" and "enable" not in (r.ref, r.data)
)
#: The rules whose worst case a phase type has (its steps are its state changes).
PHASE_RULES: tuple[str, ...] = tuple(
    r.id for r in TABLE if r.id in WORST_RULES and "phases" in r.kinds
)


def union(*arrays: Ints) -> Ints:
    """The sorted distinct values of ``arrays`` (sort-based: numpy's hashing ``unique`` is far
    slower on a million sorted integers)."""
    a = np.sort(np.concatenate(arrays)) if arrays else np.zeros(0, np.int64)
    return a[np.concatenate([[True], a[1:] != a[:-1]])] if len(a) else a


def _alternate(events: Ints, parity: int) -> Ints:
    return union(events)[1 - parity :: 2]


def end_events(
    rule: str,
    kind: StepKind,
    pulses: Sequence[tuple[Ints, Ints]],
    dir_changes: Ints,
    active_rising: bool = True,
    parity: int = 0,
) -> Ints | None:
    """The end events of ``rule``'s intervals (sorted, unique), or None when the rule does not
    apply to ``kind``.

    Args:
        pulses: (rising, falling) events of each pulse line: STEP; UP then DOWN; for a phase
            type, one entry per phase output (only their union, the state changes, counts).
        dir_changes: the DIR changes (type 0; empty otherwise).
        active_rising: the drive's active STEP edge is the rising one (else the falling one).
        parity: for the rules that take every second event, 0 takes the second, fourth, …
            (as the model does), 1 the first, third, … (a capture that starts mid-run).
    """
    r = rule_of(rule) if rule in WORST_RULES else None
    if r is None or kind not in r.kinds:
        return None
    # The table says which event closes each interval (wavecheck.rules): a width ends at the edge
    # leaving its level; a period at every second one of its events; a hold at its data event;
    # a setup at the first data event at or after each reference event; a switch at the first
    # active edge on the other line.
    if kind == "phases":  # the steps are the state changes (step_period and state_hold alike)
        changes = [e for up, down in pulses for e in (up, down)]
        return _alternate(np.concatenate(changes) if changes else np.zeros(0, np.int64), parity)
    rises = union(*[up for up, _ in pulses])
    falls = union(*[down for _, down in pulses])
    active = rises if active_rising else falls
    if r.check == "width":
        return falls if r.level == 1 else rises
    if r.check == "period":
        return _alternate(active, parity)
    if r.check == "hold":
        return union(dir_changes)
    if r.check == "setup":
        pos = np.searchsorted(active, dir_changes, side="left")  # first active edge at/after
        return union(active[pos[pos < len(active)]])
    up, down = (r_ if active_rising else f for r_, f in pulses[:2])  # switch
    lab = np.concatenate([np.zeros(len(up), np.int8), np.ones(len(down), np.int8)])
    at = np.concatenate([up, down])
    order = np.argsort(at, kind="stable")
    at, lab = at[order], lab[order]
    return at[np.flatnonzero(lab[1:] != lab[:-1]) + 1]
