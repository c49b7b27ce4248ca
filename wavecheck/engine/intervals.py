"""Compile a drive's figures and the rule table (:mod:`wavecheck.rules`) into measured, judged rules.

A rule of the table is evaluated when it applies to the step type's kind and the drive states its
figure (``step_period`` from the drive's maximum step rate: limit = 1/max_rate). A rule the drive
states whose signals are not mapped (e.g. no DIR channel captured) has no interval: its verdict
is ``unchecked``.

This module turns the table's events (``pulse``, ``active``, ``step``, ``dir``, ``line``,
``state``, ``enable``) and checks (``width``, ``period``, ``setup``, ``hold``, ``switch``,
``sequence``) into intervals. Two details of the events:

- ``dir_delay`` (``switch``): where the pulses switch line, from the end of the last pulse on one
  line (the edge that ends it) to the active edge of the first pulse on the other; overlapping
  pulses measure negative.
- ``enable_setup``: ENABLE becoming active (high after inversion; use ``--invert enable`` for an
  active-low input) → the first step while it stays active.

A DIR change at the same tick as an active edge is a 0 interval of both ``dir_setup`` and
``dir_hold``. An interval that touches an unknown stretch of a signal it involves (``x`` at the
start of a VCD up to its ``known_from``, or a later ``x``/``z`` up to the tick a known value
comes back) is not judged: an event may be hidden there. It is counted as unknown
(:attr:`RuleResult.unknown_ticks`).
"""

from __future__ import annotations

from fractions import Fraction
from typing import TYPE_CHECKING

import numpy as np

from wavecheck.capture.edges import EdgeArray
from wavecheck.drives.datasheet import ActiveEdge, Drive, Figure
from wavecheck.rules import Rule, applicable
from wavecheck.steps.decode import (
    StepEvents,
    active_edges,
    phase_states,
    touches_stretches,
)
from wavecheck.steps.interface import RoleSignal, StepInterface
from wavecheck.steps.primitives import Intervals, holds, periods, setups, widths
from wavecheck.steptypes import StepType

if TYPE_CHECKING:
    import numpy.typing as npt

__all__ = [
    "either_level",
    "figure_of",
    "planned_rules",
    "rule_intervals",
    "split_unknown",
]


def _figure(drive: Drive, r: Rule) -> tuple[Fraction, Figure] | None:
    if r.figure == "max_rate":
        fig = drive.max_rate
        if fig is None or fig.value <= 0:
            return None
        return Fraction(10**9) / fig.value, fig
    if r.figure == "none":
        return None
    f = drive.limits.get(r.id)
    return None if f is None else (f.value, f)


def planned_rules(drive: Drive, st: StepType) -> tuple[tuple[Rule, ...], tuple[str, ...]]:
    """The rules a check of step type ``st`` against ``drive`` evaluates, in report order (those
    that apply and whose figure the drive states, and ``state_sequence``, which needs none), and
    the ids of the rules that apply but have no figure."""
    run: list[Rule] = []
    missing: list[str] = []
    for r in applicable(st.kind):
        if r.figure == "none" or _figure(drive, r) is not None:
            run.append(r)
        else:
            missing.append(r.id)
    return tuple(run), tuple(missing)


def _pulse_ends(sig: RoleSignal, edge: ActiveEdge) -> tuple[EdgeArray, EdgeArray]:
    """Active edges of ``sig`` and the edge ending each pulse (−1 where the capture ends first)."""
    act = active_edges(sig, edge)
    if edge == "both":
        idx = np.arange(len(sig.edges))
    else:
        start = 0 if (sig.initial == 0) == (edge == "rising") else 1
        idx = np.arange(start, len(sig.edges), 2)
    nxt = idx + 1
    ends = np.full(len(act), -1, dtype=np.int64)
    ok = nxt < len(sig.edges)
    ends[ok] = sig.edges[nxt[ok]]
    return act, ends


def _dir_delay(iface: StepInterface, edge: ActiveEdge, level: int) -> Intervals:
    """End of the last pulse on one line → the active edge of the first pulse on the other.

    A pulse ends at the edge after its active edge — unless the generator's pulses (at ``level``)
    end at the active edge (high pulses into a falling-edge drive, as in LinuxCNC's stepper-tuning
    chapter's Gecko G202 example), where the active edge itself ends the pulse.
    """
    up, down = iface.require("up"), iface.require("down")
    up_t, up_end = _pulse_ends(up, edge)
    dn_t, dn_end = _pulse_ends(down, edge)
    if edge != "both" and level != (edge == "rising"):
        up_end, dn_end = up_t, dn_t
    ticks = np.concatenate([up_t, dn_t])
    ends = np.concatenate([up_end, dn_end])
    line = np.concatenate([np.zeros(len(up_t), np.int8), np.ones(len(dn_t), np.int8)])
    order = np.argsort(ticks, kind="stable")
    ticks, ends, line = ticks[order], ends[order], line[order]
    k = np.flatnonzero(line[1:] != line[:-1]) + 1
    prev_end = ends[k - 1]
    ok = prev_end >= 0
    return Intervals(prev_end[ok], ticks[k[ok]])


def either_level(a: Intervals, b: Intervals) -> tuple[Intervals, Intervals, npt.NDArray[np.bool_]]:
    """Two readings of the same intervals (the same end events; ``dir_delay`` with the pulses at
    either level): (the shorter, the longer, whether both readings have it) for every end event
    either has, in time order. An interval only one reading has (the other's pulse had not
    ended) is both the shorter and the longer, and undecided."""
    ends = np.union1d(a.end, b.end)
    ia = np.minimum(np.searchsorted(a.end, ends), max(len(a.end) - 1, 0))
    ib = np.minimum(np.searchsorted(b.end, ends), max(len(b.end) - 1, 0))
    in_a = (a.end[ia] == ends) if len(a.end) else np.zeros(len(ends), bool)
    in_b = (b.end[ib] == ends) if len(b.end) else np.zeros(len(ends), bool)
    sa = np.where(in_a, a.start[ia] if len(a.end) else 0, -1)
    sb = np.where(in_b, b.start[ib] if len(b.end) else 0, -1)
    late = np.where(in_a & in_b, np.maximum(sa, sb), np.where(in_a, sa, sb))
    early = np.where(in_a & in_b, np.minimum(sa, sb), late)
    return Intervals(late, ends), Intervals(early, ends), in_a & in_b


def _enable_setup(enable: RoleSignal, steps: EdgeArray) -> Intervals:
    rises, falls = _pulse_ends(enable, "rising")
    falls = np.where(falls < 0, np.iinfo(np.int64).max, falls)
    if len(steps) == 0:
        return Intervals.empty()
    k = np.searchsorted(steps, rises, side="left")
    ok = k < len(steps)
    first = steps[np.minimum(k, len(steps) - 1)]
    ok &= first < falls  # a step only counts while ENABLE stays active
    return Intervals(rises[ok], first[ok])


def _events(
    name: str, iface: StepInterface, st: StepType, steps: StepEvents, edge: ActiveEdge
) -> EdgeArray | None:
    """The ticks of one of the table's events; None when its role is not mapped."""
    if name == "step":
        return steps.ticks
    if name == "active":
        return active_edges(iface.require("step"), edge)
    if name == "dir":
        d = iface.get("dir")
        return None if d is None else d.edges
    if name == "state":
        return phase_states(iface, st.outputs)[0]
    raise ValueError(f"no event {name!r} in the rule table's vocabulary")


def _intervals(
    r: Rule, iface: StepInterface, st: StepType, steps: StepEvents, edge: ActiveEdge, level: int
) -> Intervals:
    if r.check == "width":
        assert r.level is not None
        sigs = (iface.require(role) for role in st.pulse_roles)
        return Intervals.concat([widths(s.initial, s.edges, r.level) for s in sigs])
    if r.check == "switch":
        return _dir_delay(iface, edge, level)
    if r.ref == "enable":
        en = iface.get("enable")
        return Intervals.empty() if en is None else _enable_setup(en, steps.ticks)
    ref = _events(r.ref, iface, st, steps, edge)
    if r.check == "period":
        return Intervals.empty() if ref is None else periods(ref)
    data = _events(r.data, iface, st, steps, edge)
    if ref is None or data is None:
        return Intervals.empty()
    if r.check == "setup":
        return setups(ref, data)
    if r.check == "hold":
        return holds(ref, data)
    raise ValueError(f"rule {r.id!r}: no measurement for check {r.check!r}")


def split_unknown(
    intervals: Intervals, starts: EdgeArray, ends: EdgeArray
) -> tuple[npt.NDArray[np.bool_], npt.NDArray[np.bool_]]:
    """Which ``intervals`` touch none of the disjoint unknown stretches ``[starts[i], ends[i]]``
    (kept), and which stretches an interval left out overlaps (the others may hide a whole
    interval: they count as unknown places of their own)."""
    lo = np.minimum(intervals.start, intervals.end)
    hi = np.maximum(intervals.start, intervals.end)
    out = touches_stretches(lo, hi, starts, ends)
    # stretches that an interval left out overlaps (by the running max of their ends)
    order = np.argsort(lo[out], kind="stable")
    olo, ohi = lo[out][order], np.maximum.accumulate(hi[out][order])
    last = np.searchsorted(olo, ends, side="right") - 1
    covered = np.zeros(len(starts), dtype=np.bool_)
    has = last >= 0
    covered[has] = ohi[last[has]] >= starts[has]
    return ~out, covered


#: The limit (exact ns) and figure of a rule for a drive (None: the drive states none).
figure_of = _figure
#: Every interval of a rule (unknown stretches not yet split off): what the engine judges.
rule_intervals = _intervals
