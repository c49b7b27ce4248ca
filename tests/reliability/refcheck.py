"""A deliberately simple reference checker, written from DESIGN.md alone (issue 8).

Plain Python loops over plain lists of edge ticks; no numpy, nothing shared with the engine.
From DESIGN.md's rule table and "Resolution and verdicts":

- ``step_high`` / ``step_low``: every complete high / low time of STEP;
- ``step_period``: between successive active edges, limit 1 / max rate;
- ``dir_setup``: a DIR change → the next active STEP edge (at the same instant: 0);
- ``dir_hold``: the active STEP edge → the next DIR change. Read as Verilog's ``$hold``, each DIR
  change is paired with the last active edge at or before it (an earlier edge only gives a longer
  interval, so the verdict and the minimum margin are the same under either pairing);
- a measured W is really in (W − T, W + T): pass if W − T ≥ limit, fail if W + T ≤ limit, else
  indeterminate; a rule fails if any interval fails, else is indeterminate if any is;
- the overall verdict: fail if any rule fails, else indeterminate if any is, else pass;
- decoding: one step per active STEP edge, its direction the DIR level just before the edge
  (``forward_level`` = forward); a DIR change at the same instant makes it ambiguous (0).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from fractions import Fraction


@dataclass
class RefRule:
    rule: str
    limit_ns: Fraction
    intervals: list[tuple[int, int]] = field(default_factory=list)  # (start tick, end tick)
    outcomes: list[str] = field(default_factory=list)

    @property
    def checked(self) -> int:
        return len(self.intervals)

    @property
    def violation_ticks(self) -> list[int]:
        return [s for (s, _), o in zip(self.intervals, self.outcomes, strict=True) if o == "fail"]

    @property
    def indeterminate(self) -> int:
        return self.outcomes.count("indeterminate")

    @property
    def verdict(self) -> str:
        if not self.intervals:
            return "unchecked"
        if "fail" in self.outcomes:
            return "fail"
        if "indeterminate" in self.outcomes:
            return "indeterminate"
        return "pass"


@dataclass
class RefResult:
    rules: dict[str, RefRule]
    step_ticks: list[int]
    directions: list[int]
    ambiguous: list[int]

    @property
    def verdict(self) -> str:
        verdicts = [r.verdict for r in self.rules.values()]
        if "fail" in verdicts:
            return "fail"
        if "indeterminate" in verdicts:
            return "indeterminate"
        # DESIGN.md says "else pass"; the report model documents one refinement, taken here:
        # when no rule had a single interval to measure, nothing was checked ("unchecked").
        return "pass" if "pass" in verdicts else "unchecked"


def _level_after(initial: int, i: int) -> int:
    """Level after edge number ``i`` (each edge toggles)."""
    level = initial
    for _ in range(i + 1):
        level = 1 - level
    return level


def reference_check(
    step: tuple[int, list[int]],
    dir_: tuple[int, list[int]],
    *,
    tick_ns: Fraction,
    resolution_ns: Fraction,
    limits_ns: dict[str, Fraction],
    max_rate_hz: Fraction | None,
    active_edge: str,
    forward_level: int,
) -> RefResult:
    step_init, step_edges = step
    dir_init, dir_edges = dir_
    active: list[int] = []
    for i, t in enumerate(step_edges):
        after = _level_after(step_init, i)
        if active_edge == "both" or (active_edge == "rising") == (after == 1):
            active.append(t)

    measured: dict[str, list[tuple[int, int]]] = {}
    for rule, level in (("step_high", 1), ("step_low", 0)):
        spans = []
        for i in range(len(step_edges) - 1):
            if _level_after(step_init, i) == level:
                spans.append((step_edges[i], step_edges[i + 1]))
        measured[rule] = spans
    measured["step_period"] = [(active[i], active[i + 1]) for i in range(len(active) - 1)]
    setup = []
    hold = []
    for d in dir_edges:
        nxt = [a for a in active if a >= d]
        if nxt:
            setup.append((d, nxt[0]))
        prev = [a for a in active if a <= d]
        if prev:
            hold.append((prev[-1], d))
    measured["dir_setup"] = setup
    measured["dir_hold"] = hold

    limits = dict(limits_ns)
    if max_rate_hz is not None:
        limits["step_period"] = Fraction(10**9) / max_rate_hz
    rules: dict[str, RefRule] = {}
    for rule, limit in limits.items():
        r = RefRule(rule, limit)
        for start, end in measured[rule]:
            w = (end - start) * tick_ns
            if w - resolution_ns >= limit:
                outcome = "pass"
            elif w + resolution_ns <= limit:
                outcome = "fail"
            else:
                outcome = "indeterminate"
            r.intervals.append((start, end))
            r.outcomes.append(outcome)
        rules[rule] = r

    directions = []
    ambiguous = []
    for t in active:
        before = sum(1 for d in dir_edges if d < t)
        level = dir_init if before % 2 == 0 else 1 - dir_init
        if t in dir_edges:
            directions.append(0)
            ambiguous.append(t)
        else:
            directions.append(1 if level == forward_level else -1)
    return RefResult(rules, active, directions, ambiguous)


def min_margin(rule: RefRule, tick_ns: Fraction) -> tuple[Fraction, int] | None:
    """(minimum of measured − limit in ns, start tick of the first interval that has it)."""
    best: tuple[Fraction, int] | None = None
    for start, end in rule.intervals:
        margin = (end - start) * tick_ns - rule.limit_ns
        if best is None or margin < best[0]:
            best = (margin, start)
    return best
