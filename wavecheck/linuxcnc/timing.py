"""The n·P − J arithmetic of LinuxCNC's software stepgen (step types 0 and 1).

stepgen changes its pins only when the base thread runs, once every base period ``P``, and any
invocation may come up to ``J`` (the worst latency) late. So every interval stepgen makes ``n``
periods long is only guaranteed ``n·P − J`` long on the wire, and a requirement ``T`` needs
``n = ceil((T + J) / P)`` periods (LinuxCNC's stepper-tuning chapter).

Mapping a drive's datasheet figures onto stepgen's parameters:

* stepgen's pulse (``steplen`` periods) is the drive's *high* time when the STEP pin is not
  inverted, its *low* time when it is; ``stepspace`` is the other level.
* The drive's active edge is the start of stepgen's pulse for a rising-edge drive on a
  non-inverted pin (or a falling-edge drive on an inverted one), otherwise its end.
* The datasheet's DIR hold counts from the active edge, LinuxCNC's ``dirhold`` from the end of the
  pulse: the worst hold is ``dirhold·P − J`` when the active edge ends the pulse and
  ``(steplen + dirhold)·P − J`` when it starts it; DIR setup likewise.
* Across a reversal the idle level lasts only ``dirhold + dirsetup`` periods and the step period
  ``steplen + dirhold + dirsetup`` periods (LinuxCNC's hold logic).

Used by the validator (the ``latency_safe`` step rate of a configuration) and by
``stepgen plan``. Times are exact :class:`~fractions.Fraction` ns, the base period whole ns.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from fractions import Fraction
from typing import Literal

from wavecheck.drives.datasheet import Drive
from wavecheck.errors import ConfigError
from wavecheck.rules import PLAN_RULES, rate_rule, width_rule

__all__ = [
    "PARAMS",
    "PLAN_RULES",
    "ActiveAt",
    "Requirement",
    "active_at",
    "evaluate",
    "period_limit_ns",
    "periods_needed",
    "require_figures",
    "step_rate_hz",
]

#: stepgen's timing parameters for step type 0, in the order LinuxCNC lists them.
PARAMS: tuple[str, ...] = ("steplen", "stepspace", "dirsetup", "dirhold")
#: The drive figures the arithmetic needs.

ActiveAt = Literal["start", "end"]
"""Where the drive's active edge lies on stepgen's pulse: its start or its end."""


def periods_needed(
    requirement_ns: Fraction | int, latency_ns: Fraction | int, period_ns: int
) -> int:
    """Whole base periods ``n`` such that ``n·P − J ≥ T``: ``ceil((T + J) / P)`` (≥ 0).

    Args:
        requirement_ns: the drive's minimum ``T`` in ns.
        latency_ns: worst latency ``J`` in ns.
        period_ns: base period ``P`` in ns (> 0).
    """
    need = Fraction(requirement_ns) + Fraction(latency_ns)
    return max(0, math.ceil(need / period_ns))


def step_rate_hz(period_ns: int | Fraction, periods: int) -> Fraction:
    """Exact step rate in Hz when one step takes ``periods`` base periods of ``period_ns``."""
    return Fraction(10**9) / (Fraction(period_ns) * periods)


def active_at(drive: Drive, step_inverted: bool) -> ActiveAt:
    """Whether ``drive``'s active edge is the start or the end of stepgen's pulse."""
    return "start" if (drive.active_edge == "rising") != step_inverted else "end"


def period_limit_ns(drive: Drive) -> Fraction | None:
    """The drive's shortest step period 1/fmax in ns, if it states a max rate."""
    return drive.limit_ns(rate_rule())


def require_figures(drive: Drive, rules: tuple[str, ...] = PLAN_RULES) -> None:
    """Raise ConfigError unless ``drive`` states every figure of ``rules``."""
    missing = [r for r in rules if drive.limit_ns(r) is None]
    if missing:
        given = " ".join(f"--limit {r}=T" for r in missing)
        raise ConfigError(
            f"drive {drive.id} ({drive.path}) gives no {', '.join(missing)} figure; stepgen's "
            f"timing needs {', '.join(PLAN_RULES)} (give the figure from the drive's manual or a "
            f"measurement: {given}, e.g. {missing[0]}=5us; or a rule file of your own with "
            f'extends = "{drive.id}" and it under [limits])'
        )


@dataclass(frozen=True)
class Requirement:
    """One interval the drive needs, and what stepgen guarantees for it under latency ``J``."""

    rule: str
    """Rule id (``step_high``, ``step_low``, ``dir_setup``, ``dir_hold``, ``step_period``)."""
    what: str
    """Which interval, in words (e.g. "DIR hold, active edge = end of pulse → DIR change")."""
    limit_ns: Fraction
    """The drive's minimum ``T``, ns."""
    params: tuple[str, ...]
    """The stepgen parameters whose periods add up to this interval."""
    periods: int
    """The interval in base periods (sum of ``params``)."""
    worst_ns: Fraction
    """Shortest real interval under latency ``J``: ``periods·P − J``, ns."""

    @property
    def margin_ns(self) -> Fraction:
        """``periods·P − J − T`` in ns (negative: a violation)."""
        return self.worst_ns - self.limit_ns

    @property
    def formula(self) -> str:
        """E.g. ``"(steplen + dirhold)·P − J"``."""
        names = " + ".join(self.params)
        return f"({names})·P − J" if len(self.params) > 1 else f"{names}·P − J"

    @property
    def rate_dependent(self) -> bool:
        """True for the intervals that grow as the step rate falls (the space between pulses
        and the step period in one direction); the others are fixed by the parameters."""
        return self.params in (("stepspace",), ("steplen", "stepspace"))


def _limit(drive: Drive, rule: str) -> Fraction:
    value = drive.limit_ns(rule)
    assert value is not None
    return value


def evaluate(
    drive: Drive,
    latency_ns: Fraction | int,
    base_period_ns: int,
    periods: Mapping[str, int],
    *,
    step_inverted: bool = False,
) -> tuple[Requirement, ...]:
    """The worst-case intervals of a stepgen setting against ``drive``, one per interval kind.

    Args:
        drive: needs step_high, step_low, dir_setup and dir_hold; a max rate adds step_period.
        latency_ns: worst latency ``J``.
        base_period_ns: ``P``.
        periods: steplen, stepspace, dirsetup, dirhold in whole base periods.
        step_inverted: the STEP pin is inverted between stepgen and the drive.
    Returns:
        One :class:`Requirement` per interval; a negative ``margin_ns`` is a violation.
    """
    require_figures(drive)
    j = Fraction(latency_ns)
    at = active_at(drive, step_inverted)
    active_rule = width_rule(0 if step_inverted else 1)  # stepgen's pulse at the drive
    idle_rule = width_rule(1 if step_inverted else 0)
    rows: list[tuple[str, str, tuple[str, ...]]] = [
        (active_rule, "stepgen's pulse", ("steplen",)),
        (idle_rule, "between pulses, same direction", ("stepspace",)),
        (idle_rule, "between pulses across a reversal", ("dirhold", "dirsetup")),
    ]
    if at == "start":
        rows += [
            ("dir_setup", "DIR change → active edge (start of pulse)", ("dirsetup",)),
            ("dir_hold", "active edge (start of pulse) → DIR change", ("steplen", "dirhold")),
        ]
    else:
        rows += [
            ("dir_setup", "DIR change → active edge (end of pulse)", ("dirsetup", "steplen")),
            ("dir_hold", "active edge (end of pulse) → DIR change", ("dirhold",)),
        ]
    if period_limit_ns(drive) is not None:
        rows += [
            ("step_period", f"active edge → active edge ({at} of pulse)", ("steplen", "stepspace")),
            ("step_period", "active edges across a reversal", ("steplen", "dirhold", "dirsetup")),
        ]
    out = []
    for rule, what, names in rows:
        n = sum(periods[name] for name in names)
        out.append(Requirement(rule, what, _limit(drive, rule), names, n, n * base_period_ns - j))
    return tuple(out)
