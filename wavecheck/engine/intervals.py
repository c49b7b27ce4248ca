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

from dataclasses import dataclass
from fractions import Fraction

import numpy as np
import numpy.typing as npt

from wavecheck.capture.edges import EdgeArray
from wavecheck.drives.model import ActiveEdge, Drive, Figure
from wavecheck.engine.decode import (
    StepEvents,
    active_edges,
    phase_states,
    touches_stretches,
    unknown_stretches,
)
from wavecheck.engine.interface import RoleSignal, StepInterface
from wavecheck.engine.primitives import Intervals, holds, periods, setups, widths
from wavecheck.engine.verdicts import RuleResult, evaluate, sequence_result
from wavecheck.linuxcnc.steptypes import StepType
from wavecheck.rules import RULE_IDS, Rule, applicable

__all__ = [
    "RuleSet",
    "applicable_rules",
    "figure_of",
    "measure_intervals",
    "planned_rules",
    "rule_intervals",
    "run_rules",
    "split_unknown",
]


def applicable_rules(st: StepType) -> tuple[str, ...]:
    """The rule ids that apply to step type ``st``, in report order."""
    return tuple(r.id for r in applicable(st.kind))


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


def _known(
    intervals: Intervals, iface: StepInterface, st: StepType, r: Rule
) -> tuple[Intervals, EdgeArray]:
    """Split off the intervals that touch an unknown stretch of a signal the rule involves (an
    event of that signal may be hidden there): the rest, and where the unknown ones are — the
    start tick of each interval left out, and the start of each stretch no measured interval
    touches (an interval hidden wholly inside it, such as a DIR change there before a step)."""
    starts, ends = unknown_stretches(iface, r.roles_for(st))
    if len(starts) == 0:
        return intervals, np.zeros(0, dtype=np.int64)
    keep, covered = split_unknown(intervals, starts, ends)
    where = np.sort(np.concatenate([intervals.start[~keep], starts[~covered]]))
    return Intervals(intervals.start[keep], intervals.end[keep]), where


def measure_intervals(
    rule: Rule,
    iface: StepInterface,
    st: StepType,
    steps: StepEvents,
    active_edge: ActiveEdge,
    pulse_level: int = 1,
) -> Intervals:
    """Every complete, known interval of ``rule`` (a rule with intervals: not ``sequence``), in
    ticks, with no limit and no verdict: what :func:`run_rules` judges and ``wavecheck measure``
    summarises. An interval whose role is not mapped (no DIR, no ENABLE) is simply absent.

    ``pulse_level`` is the level of the generator's pulses at the drive's input (only
    ``dir_delay`` depends on it; see :func:`_dir_delay`)."""
    return _known(_intervals(rule, iface, st, steps, active_edge, pulse_level), iface, st, rule)[0]


#: The limit (exact ns) and figure of a rule for a drive (None: the drive states none).
figure_of = _figure
#: Every interval of a rule (unknown stretches not yet split off): the streamed engine's input.
rule_intervals = _intervals


@dataclass(frozen=True)
class RuleSet:
    """What was evaluated and why the rest was not."""

    results: list[RuleResult]
    not_stated: tuple[str, ...]
    """Rules of this step type for which the drive gives no limit."""
    not_applicable: tuple[str, ...]
    """Rules the drive states that do not apply to this step type."""


def run_rules(
    iface: StepInterface,
    st: StepType,
    steps: StepEvents,
    drive: Drive,
    resolution_ns: Fraction,
    active_edge: ActiveEdge,
    pulse_level: int = 1,
) -> RuleSet:
    """Measure and judge every applicable rule the drive states, in the table's order.

    ``pulse_level`` is the level of the generator's pulses at the drive's input
    (:func:`wavecheck.engine.rates.pulse_level`)."""
    tb = iface.capture.timebase
    run, not_stated = planned_rules(drive, st)
    results: list[RuleResult] = []
    for r in run:
        if r.check == "sequence":
            details = [
                f"state {a} → {b}"
                for a, b in zip(
                    steps.sequence_from.tolist(), steps.sequence_to.tolist(), strict=True
                )
            ]
            results.append(
                sequence_result(
                    steps.sequence_errors, details, steps.transitions, tb, resolution_ns
                )
            )
            continue
        fig = _figure(drive, r)
        assert fig is not None
        limit, figure = fig
        known, unknown = _known(
            _intervals(r, iface, st, steps, active_edge, pulse_level), iface, st, r
        )
        results.append(evaluate(r.id, known, limit, tb, resolution_ns, figure, unknown))
    stated = set(drive.limits) | ({"step_period"} if drive.max_rate is not None else set())
    used = applicable_rules(st)
    not_applicable = tuple(r for r in RULE_IDS if r in stated and r not in used)
    return RuleSet(results, not_stated, not_applicable)
