"""Identical violations grouped for the human reports (text and HTML).

A capture with one systematic fault repeats the same violation many times (every pulse 3.5 µs
against 4.5 µs): listed one per line it hides everything else. The text and HTML reports group
the violations they list by (rule, measured, limit) — for a ``state_sequence`` error by its
detail — keeping the worst-first order of each group's first member. The JSON report keeps every
violation (its contract); only the human reports group.

A group is formed from the violations listed (the worst ``--max-violations``), but it states its
count and its first and last time over the whole capture: the rule's results tally every
violation by measured length (:meth:`wavecheck.engine.results.RuleResult.tally`).
"""

from __future__ import annotations

from collections.abc import Sequence
from fractions import Fraction
from typing import Protocol, runtime_checkable

from wavecheck.engine import Violation
from wavecheck.record import record
from wavecheck.timebase import Timebase

__all__ = ["Tally", "ViolationGroup", "group_violations"]


@record(frozen=True)
class ViolationGroup:
    """Violations identical in rule, measured length and limit.

    Attributes:
        members: the violations listed (at least one), earliest first.
        whole: over the whole capture: (count, first time s, last time s) of every violation
            identical to these (None: not tallied; the members are all that is known).
    """

    members: tuple[Violation, ...]
    whole: tuple[int, Fraction, Fraction] | None = None

    @property
    def first(self) -> Violation:
        """The earliest member listed."""
        return self.members[0]

    @property
    def last(self) -> Violation:
        """The latest member listed."""
        return self.members[-1]

    @property
    def count(self) -> int:
        """How many identical violations the whole capture holds (the members, when not
        tallied)."""
        return self.whole[0] if self.whole is not None else len(self.members)

    @property
    def first_s(self) -> Fraction:
        """The time of the first identical violation in the whole capture."""
        return self.whole[1] if self.whole is not None else self.first.time_s

    @property
    def last_s(self) -> Fraction:
        """The time of the last identical violation in the whole capture."""
        return self.whole[2] if self.whole is not None else self.last.time_s

    @property
    def rule(self) -> str:
        """The rule id shared by every member."""
        return self.first.rule


@runtime_checkable
class Tally(Protocol):
    """What a rule's results tell of all its violations (:class:`~wavecheck.engine.results
    .RuleResult`)."""

    rule: str
    timebase: Timebase

    def tally(self, key: int | str) -> tuple[int, int, int] | None: ...


def _key(v: Violation) -> tuple[str, Fraction | None, Fraction | None, str]:
    if v.margin_ns is None:
        return (v.rule, None, None, v.detail)
    return (v.rule, v.measured_ns, v.limit_ns, "")


def _whole(v: Violation, results: dict[str, Tally]) -> tuple[int, Fraction, Fraction] | None:
    r = results.get(v.rule)
    if r is None:
        return None
    key: int | str = v.detail if v.margin_ns is None else v.end_tick - v.start_tick
    got = r.tally(key)
    if got is None:
        return None
    n, first, last = got
    return n, r.timebase.seconds(first), r.timebase.seconds(last)


def group_violations(
    violations: Sequence[Violation], results: Sequence[object] = ()
) -> list[ViolationGroup]:
    """Group ``violations`` (worst first) by (rule, measured, limit); a group takes the place of
    its worst member, so the groups stay worst first. Members are in time order. With the
    rules' ``results``, each group states its count and span over the whole capture."""
    by_rule = {r.rule: r for r in results if isinstance(r, Tally)}
    by_key: dict[tuple[str, Fraction | None, Fraction | None, str], list[Violation]] = {}
    for v in violations:
        by_key.setdefault(_key(v), []).append(v)
    groups = []
    for members in by_key.values():
        ordered = tuple(sorted(members, key=lambda v: (v.start_tick, v.end_tick)))
        whole = _whole(ordered[0], by_rule)
        if whole is not None and whole[0] < len(ordered):
            whole = None  # a tally that does not hold what is listed is no tally
        groups.append(ViolationGroup(ordered, whole))
    return groups
