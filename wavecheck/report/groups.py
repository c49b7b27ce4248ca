"""Identical violations grouped for the human reports (text and HTML).

A capture with one systematic fault repeats the same violation many times (every pulse 3.5 µs
against 4.5 µs): listed one per line it hides everything else. The text and HTML reports group
the violations they list by (rule, measured, limit) — for a ``state_sequence`` error by its
detail — keeping the worst-first order of each group's first member. The JSON report keeps every
violation (its contract); only the human reports group.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from fractions import Fraction

from wavecheck.engine import Violation

__all__ = ["ViolationGroup", "group_violations"]


@dataclass(frozen=True)
class ViolationGroup:
    """Violations identical in rule, measured length and limit, in time order.

    Attributes:
        members: the violations (at least one), earliest first.
    """

    members: tuple[Violation, ...]

    @property
    def first(self) -> Violation:
        """The earliest member (its time is the group's "first at")."""
        return self.members[0]

    @property
    def last(self) -> Violation:
        """The latest member."""
        return self.members[-1]

    @property
    def count(self) -> int:
        """How many identical violations the group holds."""
        return len(self.members)

    @property
    def rule(self) -> str:
        """The rule id shared by every member."""
        return self.first.rule


def _key(v: Violation) -> tuple[str, Fraction | None, Fraction | None, str]:
    if v.margin_ns is None:
        return (v.rule, None, None, v.detail)
    return (v.rule, v.measured_ns, v.limit_ns, "")


def group_violations(violations: Sequence[Violation]) -> list[ViolationGroup]:
    """Group ``violations`` (worst first) by (rule, measured, limit); a group takes the place of
    its worst member, so the groups stay worst first. Members are in time order."""
    by_key: dict[tuple[str, Fraction | None, Fraction | None, str], list[Violation]] = {}
    for v in violations:
        by_key.setdefault(_key(v), []).append(v)
    return [
        ViolationGroup(tuple(sorted(members, key=lambda v: (v.start_tick, v.end_tick))))
        for members in by_key.values()
    ]
