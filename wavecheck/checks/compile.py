"""Compile a drive's figures into the design's rule ids and measure them over a step interface.

Which rules apply depends on the step type:

====================  =================================================================
type 0 (step/dir)     step_high, step_low, step_period, dir_setup, dir_hold, enable_setup
type 1 (up/down)      step_high, step_low, step_period, dir_delay, enable_setup
types 2–15 (phases)   state_hold, step_period, state_sequence, enable_setup
====================  =================================================================

A rule is evaluated when the drive states a limit for it (``step_period`` from the drive's
maximum step rate: limit = 1/max_rate). A rule the drive states but whose signals are not
mapped (e.g. no DIR channel captured) has no interval and its verdict is ``unchecked``.

What each rule measures (levels at the drive's input, after inversion):

- ``step_high`` / ``step_low``: every complete high / low time of STEP (or of UP and DOWN).
- ``step_period``: successive steps (active edges; state changes for phase types).
- ``dir_setup``: each DIR change → the first active STEP edge at or after it.
- ``dir_hold``: the last active STEP edge at or before each DIR change → that change (datasheet
  meaning, from the active edge — not LinuxCNC's ``dirhold``, which counts from the pulse end).
  A DIR change at the same tick as an active edge is a 0 interval of both ``dir_setup`` and
  ``dir_hold``.
- ``dir_delay`` (up/down): where the pulses switch line, from the end of the last pulse on one
  line (the edge that ends it) to the active edge of the first pulse on the other; overlapping
  pulses measure negative.
- ``state_hold``: every complete time a phase state is held (between successive state changes).
- ``state_sequence``: each move to a state that is not a neighbour in the table.
- ``enable_setup``: ENABLE becoming active (high after inversion; use ``--invert enable`` for an
  active-low input) → the first step while it stays active.

An interval that starts while one of the signals it involves is not known yet (``x`` at the start
of a VCD, up to its ``known_from``) is partial and not measured.
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction

import numpy as np

from stepgen.steptypes import StepType
from wavecheck.capture.model import EdgeArray
from wavecheck.checks.primitives import Intervals, holds, periods, setups, widths
from wavecheck.checks.result import RuleResult, evaluate, sequence_result
from wavecheck.decode import ActiveEdge, StepEvents, active_edges, phase_states
from wavecheck.drives.model import Drive, Figure
from wavecheck.interface import RoleSignal, StepInterface
from wavecheck.rates import generator_pulses

__all__ = ["RULES_BY_KIND", "RULE_ORDER", "RuleSet", "applicable_rules", "run_rules"]

#: Rule ids in report order.
RULE_ORDER: tuple[str, ...] = (
    "step_high",
    "step_low",
    "step_period",
    "dir_setup",
    "dir_hold",
    "dir_delay",
    "state_hold",
    "state_sequence",
    "enable_setup",
)
RULES_BY_KIND: dict[str, tuple[str, ...]] = {
    "step-dir": ("step_high", "step_low", "step_period", "dir_setup", "dir_hold", "enable_setup"),
    "up-down": ("step_high", "step_low", "step_period", "dir_delay", "enable_setup"),
    "phases": ("step_period", "state_hold", "state_sequence", "enable_setup"),
}


def _kind(st: StepType) -> str:
    return "step-dir" if st.number == 0 else "up-down" if st.number == 1 else "phases"


def applicable_rules(st: StepType) -> tuple[str, ...]:
    """The rule ids that apply to step type ``st``."""
    return RULES_BY_KIND[_kind(st)]


def _figure(drive: Drive, rule: str) -> tuple[Fraction, Figure] | None:
    if rule == "step_period":
        fig = drive.max_rate
        if fig is None or fig.value <= 0:
            return None
        return Fraction(10**9) / fig.value, fig
    if rule == "state_sequence":
        return None
    f = drive.limits.get(rule)
    return None if f is None else (f.value, f)


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


def _dir_delay(iface: StepInterface, edge: ActiveEdge) -> Intervals:
    """End of the last pulse on one line → the active edge of the first pulse on the other.

    A pulse ends at the edge after its active edge — unless the generator's pulses are at the
    other level (high pulses into a falling-edge drive, the seed's G202 reading), where the
    active edge itself ends the pulse.
    """
    up, down = iface.require("up"), iface.require("down")
    up_t, up_end = _pulse_ends(up, edge)
    dn_t, dn_end = _pulse_ends(down, edge)
    found = generator_pulses([up, down])
    if edge != "both" and found is not None and found[0] != (edge == "rising"):
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


def _intervals(
    rule: str, iface: StepInterface, st: StepType, steps: StepEvents, edge: ActiveEdge
) -> Intervals:
    if rule in ("step_high", "step_low"):
        level = 1 if rule == "step_high" else 0
        roles = ("step",) if st.number == 0 else ("up", "down")
        parts = [widths(s.initial, s.edges, level) for s in (iface.require(r) for r in roles)]
        return Intervals.concat(parts)
    if rule == "step_period":
        return periods(steps.ticks)
    if rule in ("dir_setup", "dir_hold"):
        d = iface.get("dir")
        if d is None:
            return Intervals.empty()
        act = active_edges(iface.require("step"), edge)
        return setups(d.edges, act) if rule == "dir_setup" else holds(act, d.edges)
    if rule == "dir_delay":
        return _dir_delay(iface, edge)
    if rule == "state_hold":
        ticks, _, _ = phase_states(iface, st.outputs)
        return periods(ticks)
    if rule == "enable_setup":
        en = iface.get("enable")
        return Intervals.empty() if en is None else _enable_setup(en, steps.ticks)
    raise ValueError(f"no measurement for rule {rule!r}")


def _known(intervals: Intervals, iface: StepInterface, st: StepType, rule: str) -> Intervals:
    """Drop the intervals that start while a signal the rule involves is not known yet (``x`` at
    the start of a VCD): an event of that signal may be hidden there, so they are partial."""
    steps = ("step",) if st.number == 0 else ("up", "down") if st.number == 1 else st.outputs
    roles: tuple[str, ...] = {
        "step_period": steps,
        "dir_setup": ("step", "dir"),
        "dir_hold": ("step", "dir"),
        "dir_delay": ("up", "down"),
        "state_hold": st.outputs,
        "enable_setup": (*steps, "enable"),
    }.get(rule, ())  # step_high/low: one signal's own edges, all after its known_from
    until = iface.unknown_until(roles)
    if until is None or len(intervals) == 0:
        return intervals
    keep = intervals.start > until
    return Intervals(intervals.start[keep], intervals.end[keep])


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
) -> RuleSet:
    """Measure and judge every applicable rule the drive states, in :data:`RULE_ORDER`."""
    tb = iface.capture.timebase
    applicable = applicable_rules(st)
    results: list[RuleResult] = []
    not_stated: list[str] = []
    for rule in RULE_ORDER:
        if rule not in applicable:
            continue
        if rule == "state_sequence":
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
        fig = _figure(drive, rule)
        if fig is None:
            not_stated.append(rule)
            continue
        limit, figure = fig
        results.append(
            evaluate(
                rule,
                _known(_intervals(rule, iface, st, steps, active_edge), iface, st, rule),
                limit,
                tb,
                resolution_ns,
                figure,
            )
        )
    stated = set(drive.limits) | ({"step_period"} if drive.max_rate is not None else set())
    not_applicable = tuple(r for r in RULE_ORDER if r in stated and r not in applicable)
    return RuleSet(results, tuple(not_stated), not_applicable)
