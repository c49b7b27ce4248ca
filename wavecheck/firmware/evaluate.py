"""Can a configuration meet a drive? Each rule: the generator's guaranteed figure vs the drive's
limit, the margin, the verdict, and the setting to change when it fails (exact arithmetic; a
figure exactly equal to the limit passes).

Mapping (levels at the drive's input = the generator's output): the pulse is the high time when
pulses are high, else the low time. DIR setup/hold count from the drive's active edge: when that
is the pulse's trailing edge, setup gains the pulse width and hold is the trailing-edge hold. A
generator in both-edge mode configures the drive (TMC ``dedge``) to count both edges.
``step_period`` compares the axis's configured max step rate with the drive's. The max step rate
of the pair is the smallest of the generator's max rate, the drive's, and 1 / (pulse + the
drive's minimum for the idle level), or 1 / the longest of the pulse and the two level minimums
in both-edge mode.

A figure whose sources disagree (:attr:`Guaranteed.disputed`) is judged under both readings: a
rule that passes under one and fails under the other is indeterminate, and says so. A figure the
firmware does not enforce (status ``not_enforced``) is never a PASS: it is indeterminate, with the
note saying why and how to measure it; a setting that asks for too little still FAILs.
:class:`ConfigResult` holds every pair, the overall verdict (:mod:`wavecheck.verdict`) and the
rules that were not checked, with why.
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction

from wavecheck.drives.datasheet import Drive, Figure
from wavecheck.firmware.guarantee import (
    FirmwareConfig,
    FixRole,
    GeneratorGuarantee,
    Guaranteed,
    Role,
)
from wavecheck.rules import Rule, applicable
from wavecheck.units import format_ns
from wavecheck.verdict import (
    RuleStatus,
    Verdict,
    exit_code,
    overall_verdict,
    qualified_verdict,
    unchecked_by_reason,
)

__all__ = ["ConfigResult", "PairResult", "PairRow", "evaluate_config", "evaluate_pair"]

_GIGA = Fraction(10**9)
_SILENT = "the configuration says nothing about it"


@dataclass(frozen=True)
class PairRow:
    """One rule of one axis against one drive (ns; ``step_period`` in ns of period too)."""

    rule: str
    role: Role | None
    guaranteed_ns: Fraction | None
    source: Guaranteed | None
    limit_ns: Fraction | None
    limit: Figure | None
    margin_ns: Fraction | None
    verdict: Verdict
    fix: str = ""
    note: str = ""
    why_unchecked: str = ""
    """For an ``unchecked`` row: why (the drive states no figure; the configuration says nothing)."""


@dataclass(frozen=True)
class PairResult:
    """One axis of a configuration against one drive."""

    firmware: str
    axis: GeneratorGuarantee
    drive: Drive
    rows: tuple[PairRow, ...]
    max_rate_hz: Fraction | None
    notes: tuple[str, ...]

    @property
    def verdict(self) -> Verdict:
        """fail if any rule fails, else indeterminate if any cannot be proven, else pass."""
        return overall_verdict(r.verdict for r in self.rows)


@dataclass(frozen=True)
class ConfigResult:
    """``wavecheck config``'s answer: every axis/drive pair of one configuration."""

    config: FirmwareConfig
    pairs: tuple[PairResult, ...]

    @property
    def verdict(self) -> Verdict:
        """The worst verdict of the pairs (:func:`~wavecheck.verdict.overall_verdict`)."""
        return overall_verdict(p.verdict for p in self.pairs)

    @property
    def exit_code(self) -> int:
        """0 pass, 1 a rule fails, 3 something cannot be proven (:mod:`wavecheck.verdict`)."""
        return exit_code(self.verdict)

    @property
    def statuses(self) -> tuple[RuleStatus, ...]:
        """Every rule of every pair as the verdict line and ``--require`` read it
        (:mod:`wavecheck.verdict`)."""
        return tuple(
            RuleStatus(
                row.rule,
                row.verdict,
                (row.why_unchecked or _SILENT) if row.verdict == "unchecked" else row.note,
                pair.axis.axis,
                stated=row.limit is not None,
            )
            for pair in self.pairs
            for row in pair.rows
        )

    @property
    def unchecked(self) -> dict[str, tuple[str, ...]]:
        """Why → the rules not checked for that reason, in rule order (a rule not checked on
        every axis for that reason named ``AXIS.RULE``)."""
        return unchecked_by_reason(self.statuses)

    @property
    def verdict_line(self) -> str:
        """``PASS (dir_setup, dir_hold not checked: drive tb6600 states no figure)``."""
        return qualified_verdict(self.verdict, self.unchecked)


def _mapping(
    g: GeneratorGuarantee, drive: Drive, r: Rule
) -> tuple[Role | None, Guaranteed | None, Fraction, str]:
    """(role, figure, offset added, note) for rule ``r``, by what the rule table says it
    measures: a width at the pulse level is the pulse, at the other the idle time; a DIR setup or
    hold is the generator's DIR delay or hold (from the trailing edge when the drive's active
    edge ends the pulse); the rate rule the maximum step rate."""
    edge = "both" if g.both_edges else drive.active_edge
    trailing = _trailing(g, drive)
    if r.check == "width":
        role: Role = "pulse" if r.level == g.pulse_level else "idle"
        return role, g.figure(role), Fraction(0), ""
    if r.check == "setup" and r.ref == "dir":
        if trailing and g.dir_setup_trailing is not None:
            note = "the drive's active edge ends the pulse, and DIR may change during it"
            return "setup", g.dir_setup_trailing, Fraction(0), note
        if trailing and edge != "both" and g.pulse.value is not None:
            note = "the drive's active edge ends the pulse: setup + pulse"
            return "setup", g.dir_setup, g.pulse.value, note
        return "setup", g.dir_setup, Fraction(0), ""
    if r.check == "hold" and r.data == "dir":
        if trailing:
            note = "the drive's active edge ends the pulse: hold from the trailing edge"
            return "hold", g.dir_hold_trailing, Fraction(0), note
        return "hold", g.dir_hold, Fraction(0), ""
    if r.figure == "max_rate":
        return "max_rate", g.max_rate, Fraction(0), ""
    return None, None, Fraction(0), _SILENT


def _fix_role(role: Role, g: GeneratorGuarantee, drive: Drive) -> FixRole:
    """What the fix must reach: the trailing-edge hold or setup where the drive counts the
    trailing edge and the generator says so."""
    if role == "hold" and _trailing(g, drive):
        return "trailing_hold"
    if role == "setup" and _trailing(g, drive) and g.dir_setup_trailing is not None:
        return "trailing_setup"
    return role


def _trailing(g: GeneratorGuarantee, drive: Drive) -> bool:
    """The drive's active edge ends the generator's pulse."""
    return not g.both_edges and drive.active_edge != g.leading_edge


def _as_ns(v: Fraction | None, rate: bool, offset: Fraction) -> Fraction | None:
    """A figure as ns to compare with the limit (a rate as its period)."""
    if v is None:
        return None
    if rate:
        return _GIGA / v if v else None
    return v + offset


def _judge(value: Fraction, limit: Fraction) -> Verdict:
    return "pass" if value >= limit else "fail"


def evaluate_pair(config: FirmwareConfig, g: GeneratorGuarantee, drive: Drive) -> PairResult:
    """Every step/dir rule of ``drive`` against axis ``g`` of ``config``."""
    rows: list[PairRow] = []
    for r in applicable("step-dir"):
        if r.figure == "none":
            continue
        role, fig, offset, note = _mapping(g, drive, r)
        rate = r.figure == "max_rate"
        limit_fig = drive.max_rate if rate else drive.limits.get(r.id)
        limit = (_GIGA / limit_fig.value if rate else limit_fig.value) if limit_fig else None

        value = _as_ns(fig.value, rate, offset) if fig is not None else None
        other = _as_ns(fig.disputed, rate, offset) if fig is not None else None
        if role is None or limit is None:
            why = note if role is None else f"drive {drive.id} states no figure"
            rows.append(PairRow(r.id, role, value, fig, limit, limit_fig, None, "unchecked",
                                note=note, why_unchecked=why))  # fmt: skip
            continue
        if value is None:
            why = (
                fig.note
                if fig is not None and fig.note
                else note or "no bound in the configuration"
            )
            why += "" if "measure it" in why else "; measure it"
            rows.append(PairRow(r.id, role, None, fig, limit, limit_fig, None, "indeterminate",
                                note=why))  # fmt: skip
            continue
        margin = value - limit
        verdict = _judge(value, limit)
        if fig is not None and fig.status == "not_enforced":
            note = "; ".join(x for x in (note, fig.note) if x)
            if verdict == "pass":
                verdict = "indeterminate"  # the setting meets the limit; the firmware need not
        if other is not None:
            second = _judge(other, limit)
            said = f"{format_ns(value)} under the reading used, {format_ns(other)} under the other"
            note = "; ".join(x for x in (note, said) if x)
            if second != verdict:
                verdict = "indeterminate"
                note += ": the readings give different verdicts (measure it)"
        fix = ""
        if verdict in ("fail", "indeterminate") and (verdict == "fail" or other is not None):
            need = (
                (drive.max_rate.value if drive.max_rate else Fraction(0))
                if role == "max_rate"
                else limit - offset
            )
            fix = config.fix(g, _fix_role(role, g, drive), need)
        rows.append(PairRow(r.id, role, value, fig, limit, limit_fig, margin, verdict, fix, note))
    notes = list(g.notes)
    if drive.active_edge == "both" and not g.both_edges:
        notes.append("the drive counts both edges but the generator makes one step per pulse")
    return PairResult(config.firmware, g, drive, tuple(rows), _pair_rate(g, drive), tuple(notes))


def evaluate_config(
    config: FirmwareConfig, pairs: list[tuple[GeneratorGuarantee, Drive]]
) -> ConfigResult:
    """Every pair (axis, drive) of ``config`` judged (:func:`evaluate_pair`)."""
    return ConfigResult(config, tuple(evaluate_pair(config, g, d) for g, d in pairs))


def _pair_rate(g: GeneratorGuarantee, drive: Drive) -> Fraction | None:
    hi, lo = drive.limit_ns("step_high"), drive.limit_ns("step_low")
    pulse = g.pulse.value
    pulse_lim, idle_lim = (hi, lo) if g.pulse_level else (lo, hi)
    if g.both_edges:
        parts = [v for v in (pulse, hi, lo) if v is not None]
        timing = _GIGA / max(parts) if parts and max(parts) > 0 else None
    else:
        width = max(v for v in (pulse, pulse_lim, Fraction(0)) if v is not None)
        total = width + (idle_lim or Fraction(0))
        known = idle_lim is not None or pulse is not None
        timing = _GIGA / total if total > 0 and known else None
    drive_rate = drive.max_rate.value if drive.max_rate else None
    rates = [v for v in (timing, drive_rate, g.max_rate.value) if v is not None]
    return min(rates) if rates else None
