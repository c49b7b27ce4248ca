"""The rule table: every rule id, declared once, as data.

Each rule is a generic timing check in the spirit of Verilog's ``$width``, ``$period``,
``$setup`` and ``$hold``: a *reference* event starts each interval and a *data* event ends it,
and the interval must be at least the drive's figure. The checks compiler
(:mod:`wavecheck.engine.intervals`), the reports, the drive library (which keys a rule file may
give) and ``wavecheck drives`` all read this table; adding a rule is one entry here plus its
measurement, if it needs a new kind, and its tests.

Events (levels at the drive's input, after ``--invert``):

==============  ====================================================================
``pulse``       the edges of the pulse lines (STEP, or UP and DOWN)
``active``      the active edges of STEP (the drive's ``active_edge``)
``step``        the decoded steps (active edges; state changes for phase types)
``dir``         every DIR change
``line``        a step on the other up/down line than the step before it
``state``       every change of the combined phase state
``enable``      ENABLE becoming active
==============  ====================================================================
"""

from __future__ import annotations

from fractions import Fraction
from typing import Literal

from wavecheck.record import record
from wavecheck.steptypes import StepKind, StepType

__all__ = [
    "RULES",
    "RULE_IDS",
    "PLAN_RULES",
    "TIME_RULES",
    "Check",
    "Figure",
    "Hold",
    "Rule",
    "applicable",
    "rate_rule",
    "rule",
    "width_rule",
]

Check = Literal["width", "period", "setup", "hold", "switch", "sequence"]
"""How intervals are built: ``width`` every complete stretch at ``level`` of the pulse lines;
``period`` successive ``ref`` events; ``setup`` each ``ref`` event → the first ``data`` event at
or after it; ``hold`` the last ``ref`` event at or before each ``data`` event → that event;
``switch`` the end of the last pulse on one up/down line → the first active edge on the other;
``sequence`` moves to a state that is not a neighbour in the table (no interval, no limit)."""

Hold = Literal["edges", "step", "unstepped_dir"]
"""What a rule's intervals need kept between the engine's windows (:attr:`Rule.holds`)."""

Figure = Literal["time", "max_rate", "none"]
"""Where a rule's limit comes from: the drive file's time figure of the same id (ns), the
drive's maximum step rate (limit = 1 / max_rate), or nowhere (``state_sequence``)."""

_ALL: tuple[StepKind, ...] = ("step-dir", "up-down", "phases")


@record(frozen=True)
class Rule:
    """One rule: what it measures, where its limit comes from, which step types it applies to."""

    id: str
    """The rule id of reports and JSON."""
    what: str
    """What is measured, in words (for reports and ``wavecheck drives``)."""
    check: Check
    figure: Figure
    kinds: tuple[StepKind, ...]
    """The step-type kinds the rule applies to."""
    ref: str = ""
    """The event that starts each interval (see the module doc)."""
    data: str = ""
    """The event that ends each interval."""
    level: int | None = None
    """For ``width``: the level measured (1 high, 0 low)."""
    roles: tuple[str, ...] = ()
    """Roles whose unknown (``x``/``z``) stretch an interval must not touch to be judged (it is
    counted as unknown instead); ``"pulse"`` stands for the step type's pulse roles, ``"phases"``
    for its phase outputs."""

    listed_by_end: bool = False
    """Equal intervals are listed in the order of their end event, not their start (the worst
    violations, the place of the smallest margin): a DIR hold by its DIR change, a dir delay by
    the pulse after the switch."""
    holds: tuple[Hold, ...] = ()
    """What the engine must keep from one window for the next so that an interval begun there
    is measured whole (:mod:`wavecheck.engine.axis`): ``edges`` the last edge of each signal,
    ``step`` the last step, ``unstepped_dir`` every DIR change while no step came yet."""
    ends_by_level: bool = False
    """Where its intervals start depends on the pulse level (an up/down pulse's end): not
    stated nor seen, both levels are read (:mod:`wavecheck.engine.axis`)."""
    plan: bool = False
    """A figure a stepgen plan needs (``stepgen plan``: steplen, stepspace, dirsetup, dirhold
    are chosen from it; ``wavecheck drives`` marks a drive without it as not plannable)."""

    def limit_ns(self, value: Fraction) -> Fraction:
        """The interval minimum in exact ns of a drive figure ``value`` (ns for a time figure;
        for ``max_rate``, Hz: the shortest period 1/value)."""
        return Fraction(10**9) / value if self.figure == "max_rate" else Fraction(value)

    def event_roles(self, event: str, st: StepType) -> tuple[str, ...]:
        """The roles whose edges make ``event`` (``"dir"``: dir; ``"active"``: step; the
        others: every role of :attr:`roles`)."""
        if event == "dir":
            return ("dir",)
        if event == "active":
            return ("step",)
        return self.roles_for(st)

    def roles_for(self, st: StepType) -> tuple[str, ...]:
        """:attr:`roles` with ``"pulse"``/``"phases"`` expanded for step type ``st``."""
        out: list[str] = []
        for role in self.roles:
            if role == "pulse":
                out += st.pulse_roles
            elif role == "phases":
                out += st.outputs
            else:
                out.append(role)
        return tuple(dict.fromkeys(out))


RULES: tuple[Rule, ...] = (
    Rule(
        "step_high",
        "every high time of STEP (or of UP and DOWN)",
        "width",
        "time",
        ("step-dir", "up-down"),
        ref="pulse",
        data="pulse",
        level=1,
        roles=("pulse",),
        holds=("edges",),
        plan=True,
    ),
    Rule(
        "step_low",
        "every low time of STEP (or of UP and DOWN) between two pulses",
        "width",
        "time",
        ("step-dir", "up-down"),
        ref="pulse",
        data="pulse",
        level=0,
        roles=("pulse",),
        holds=("edges",),
        plan=True,
    ),
    Rule(
        "step_period",
        "successive steps (1 / the maximum step rate)",
        "period",
        "max_rate",
        _ALL,
        ref="step",
        data="step",
        roles=("pulse",),
        holds=("step",),
    ),
    Rule(
        "dir_setup",
        "DIR change → the next active STEP edge",
        "setup",
        "time",
        ("step-dir",),
        ref="dir",
        data="active",
        roles=("step", "dir"),
        holds=("step", "unstepped_dir"),
        plan=True,
    ),
    Rule(
        "dir_hold",
        "active STEP edge → the next DIR change (from the active edge, not "
        "LinuxCNC's dirhold, which counts from the end of the pulse)",
        "hold",
        "time",
        ("step-dir",),
        ref="active",
        data="dir",
        roles=("step", "dir"),
        listed_by_end=True,
        holds=("step",),
        plan=True,
    ),
    Rule(
        "dir_delay",
        "up/down: end of the last pulse on one line → the first pulse on the other",
        "switch",
        "time",
        ("up-down",),
        ref="line",
        data="line",
        roles=("up", "down"),
        listed_by_end=True,
        holds=("edges", "step"),
        ends_by_level=True,
    ),
    Rule(
        "state_hold",
        "phase types: the time each output state is held",
        "period",
        "time",
        ("phases",),
        ref="state",
        data="state",
        roles=("phases",),
        holds=("edges",),
    ),
    Rule(
        "state_sequence",
        "phase types: moves to a state that is not a neighbour in the table",
        "sequence",
        "none",
        ("phases",),
        holds=("edges",),
    ),
    Rule(
        "enable_setup",
        "ENABLE active → the first step while it stays active",
        "setup",
        "time",
        _ALL,
        ref="enable",
        data="step",
        roles=("pulse", "enable"),
        holds=("edges", "step"),
    ),
)

#: Rule ids in report order.
RULE_IDS: tuple[str, ...] = tuple(r.id for r in RULES)
#: The rules a drive file gives as a time figure (ns), in report order.
TIME_RULES: tuple[str, ...] = tuple(r.id for r in RULES if r.figure == "time")
#: The figures a stepgen plan needs (:attr:`Rule.plan`), in report order.
PLAN_RULES: tuple[str, ...] = tuple(r.id for r in RULES if r.plan)

_BY_ID = {r.id: r for r in RULES}


def rule(rule_id: str) -> Rule:
    """The rule ``rule_id`` (KeyError for an unknown id)."""
    return _BY_ID[rule_id]


def width_rule(level: int) -> str:
    """The id of the rule measuring every stretch of the pulse lines at ``level`` (1:
    ``step_high``, 0: ``step_low``): a generator's pulses at ``level``, or the gaps between
    pulses at the other level."""
    return next(r.id for r in RULES if r.check == "width" and r.level == level)


def rate_rule() -> str:
    """The id of the rule whose limit is 1 / the drive's maximum step rate."""
    return next(r.id for r in RULES if r.figure == "max_rate")


def applicable(kind: StepKind) -> tuple[Rule, ...]:
    """The rules that apply to step types of ``kind``, in report order."""
    return tuple(r for r in RULES if kind in r.kinds)
