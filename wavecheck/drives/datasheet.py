"""A drive's datasheet timing, as read from a rule file in ``rules/``.

Every figure keeps its source and how sure it is. Time limits are exact nanoseconds
(:class:`~fractions.Fraction`), the maximum step rate exact hertz.
"""

from __future__ import annotations

from collections.abc import Mapping
from fractions import Fraction
from pathlib import Path
from typing import Literal

from wavecheck.record import field, record
from wavecheck.rules import PLAN_RULES, TIME_RULES, rule, width_rule

__all__ = [
    "MARK_LEGEND",
    "STATUS_MARKS",
    "TIME_RULES",
    "ActiveEdge",
    "Drive",
    "Figure",
    "Interface",
    "Status",
    "status_mark",
]

Status = Literal["datasheet", "secondary", "firmware-default", "preset", "uncertain", "user"]
Interface = Literal["step-dir", "up-down", "phases"]
ActiveEdge = Literal["rising", "falling", "both"]

#: The mark a figure of this status carries wherever it is shown (``100 ns?``): the drive list,
#: ``wavecheck drives ID`` and every check report. Statuses not listed carry none.
STATUS_MARKS: Mapping[str, str] = {"uncertain": "?", "firmware-default": "*"}
#: What the marks mean, for a legend under a table that shows them.
MARK_LEGEND = "? = uncertain figure, * = firmware default (not a figure of the drive's own)"


def status_mark(status: str | None) -> str:
    """The mark of ``status`` (``"?"``, ``"*"`` or ``""``; ``""`` for None)."""
    return STATUS_MARKS.get(status, "") if status else ""


@record(frozen=True)
class Figure:
    """One datasheet figure: an exact value, where it comes from, how sure it is."""

    value: Fraction
    """ns for time rules, Hz for ``max_rate``."""
    source: str
    status: Status
    note: str = ""
    datasheet: Fraction | None = None
    """The figure before ``--limit``/``--margin`` changed it (None: not changed)."""
    applied: str = ""
    """How it was changed (``"--margin 2x"``, ``"--limit step_high=5us"``), "" when not."""

    @property
    def mark(self) -> str:
        """``"?"`` for an uncertain figure, ``"*"`` for a firmware default, else ``""``."""
        return status_mark(self.status)


@record(frozen=True)
class Drive:
    """A drive (or driver IC, or config-tool preset) and its STEP/DIR input timing."""

    id: str
    name: str
    path: Path
    kind: Literal["drive", "ic", "preset", "user"]
    interface: Interface
    active_edge: ActiveEdge
    limits: Mapping[str, Figure]
    """Time rules (keys from :data:`TIME_RULES`), values in ns."""
    max_rate: Figure | None
    """Maximum input step rate in Hz, if stated."""
    sources: Mapping[str, str] = field(default_factory=dict)
    """Citation key → full reference."""
    notes: tuple[str, ...] = ()
    edge_source: str = ""
    """Citation key for :attr:`active_edge` ("" when the file gives none)."""
    edge_status: Status | None = None
    """How sure :attr:`active_edge` is (None when the file gives a bare string)."""
    edge_note: str = ""
    step_type: int | None = None
    """LinuxCNC step type (0 step/dir, 1 up/down, 2–15 phase tables) when not implied by interface."""
    opto: bool | None = None
    """True for opto-isolated inputs (margins matter more), None when not known."""

    def figure(self, rule_id: str) -> Figure | None:
        """The figure ``rule_id``'s limit comes from (its time figure, or the maximum step rate
        for the rate rule), None when the drive states none."""
        return self.max_rate if rule(rule_id).figure == "max_rate" else self.limits.get(rule_id)

    def limit_ns(self, rule_id: str) -> Fraction | None:
        """The minimum of ``rule_id``'s intervals in exact ns, or None when the drive states
        none (the rate rule: 1 / the maximum step rate)."""
        fig = self.figure(rule_id)
        if fig is None or (rule(rule_id).figure == "max_rate" and fig.value <= 0):
            return None
        return rule(rule_id).limit_ns(fig.value)

    def step_rate(self) -> tuple[Fraction | None, str | None]:
        """The drive's own maximum step rate in exact Hz, min(the stated maximum rate, 1 /
        (shortest high + shortest low)), and which limits it (``"max_rate"``, ``"pulse"``);
        (None, None) when it states neither."""
        candidates: list[tuple[Fraction, str]] = []
        if self.max_rate is not None and self.max_rate.value > 0:
            candidates.append((self.max_rate.value, "max_rate"))
        hi, lo = self.limit_ns(width_rule(1)), self.limit_ns(width_rule(0))
        if hi is not None and lo is not None and hi + lo > 0:
            candidates.append((Fraction(10**9) / (hi + lo), "pulse"))
        if not candidates:
            return None, None
        return min(candidates, key=lambda c: c[0])

    @property
    def edge_mark(self) -> str:
        """The mark of :attr:`active_edge`'s status (``"?"`` when uncertain)."""
        return status_mark(self.edge_status)

    @property
    def complete(self) -> bool:
        """True when step high/low and DIR setup/hold are all given (enough to plan stepgen)."""
        return all(r in self.limits for r in PLAN_RULES)
