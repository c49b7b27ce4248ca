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

A figure the firmware does not keep exactly (status ``uncertain``) carries a band
(:attr:`Guaranteed.short_by`): the rule passes only if the band's worst end (the value less
``short_by``; a rate plus it) still meets the limit, fails only if the value itself misses it,
and is indeterminate in between, the note naming the band and the firmware line it comes from; a
band no source bounds is never a PASS. The printed fix clears the band. The pair's max step rate
takes the generator's ceiling at the top of its band (a rate with no bound above is no ceiling)
and the pulse at its aim (a pulse shorter than its aim only raises the timing term).

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

__all__ = [
    "ConfigResult",
    "PairResult",
    "PairRow",
    "band_verdict",
    "evaluate_config",
    "evaluate_pair",
    "worst_end",
]

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
    worst_ns: Fraction | None = None
    """The band's worst end as compared (ns; a rate's as its period): ``guaranteed_ns`` when the
    figure is exact, None when no source bounds its band."""
    in_band: bool = False
    """Indeterminate because the limit falls inside the figure's band (the value meets it, the
    worst end does not)."""


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
        """``PASS (dir_setup, dir_hold not checked: drive tb6600 states no figure)``; axes the
        file names but gives nothing to check lead (``PASS (axis U not checked: …)``)."""
        lead = "; ".join(f"axis {', '.join(axes)} not checked: {why}"
                         for why, axes in self.config.unchecked_axes)  # fmt: skip
        return qualified_verdict(self.verdict, self.unchecked, lead)


_EXACT = Guaranteed(Fraction(0), "", "")


def _mapping(
    g: GeneratorGuarantee, drive: Drive, r: Rule
) -> tuple[Role | None, Guaranteed | None, Guaranteed, str]:
    """(role, figure, figure added (its value and band: the pulse, when setup counts to the
    trailing edge), note) for rule ``r``, by what the rule table says it measures: a width at
    the pulse level is the pulse, at the other the idle time; a DIR setup or hold is the
    generator's DIR delay or hold (from the trailing edge when the drive's active edge ends the
    pulse); the rate rule the maximum step rate."""
    edge = "both" if g.both_edges else drive.active_edge
    trailing = _trailing(g, drive)
    if r.check == "width":
        role: Role = "pulse" if r.level == g.pulse_level else "idle"
        return role, g.figure(role), _EXACT, ""
    if r.check == "setup" and r.ref == "dir":
        if trailing and g.dir_setup_trailing is not None:
            note = "the drive's active edge ends the pulse, and DIR may change during it"
            return "setup", g.dir_setup_trailing, _EXACT, note
        if trailing and edge != "both" and g.pulse.value is not None:
            note = "the drive's active edge ends the pulse: setup + pulse"
            return "setup", g.dir_setup, g.pulse, note
        return "setup", g.dir_setup, _EXACT, ""
    if r.check == "hold" and r.data == "dir":
        if trailing:
            note = "the drive's active edge ends the pulse: hold from the trailing edge"
            return "hold", g.dir_hold_trailing, _EXACT, note
        return "hold", g.dir_hold, _EXACT, ""
    if r.figure == "max_rate":
        return "max_rate", g.max_rate, _EXACT, ""
    return None, None, _EXACT, _SILENT


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


def worst_end(fig: Guaranteed, rate: bool, added: Guaranteed = _EXACT) -> Fraction | None:
    """The worst end of ``fig``'s band as ns to compare with a limit (``rate``: the period of
    the highest rate the band allows), ``added``'s band counted too; None when no source
    bounds it (or the figure is unknown)."""
    if fig.value is None or fig.short_by is None or added.short_by is None:
        return None
    if rate:
        top = fig.value + fig.short_by
        return _GIGA / top if top else None
    return _floor0(fig.value - fig.short_by) + _floor0(
        (added.value or Fraction(0)) - added.short_by
    )


def _floor0(ns: Fraction) -> Fraction:
    """A time the firmware may fall short to: no time is below 0."""
    return max(ns, Fraction(0))


def band_verdict(value: Fraction, worst: Fraction | None, limit: Fraction) -> Verdict:
    """A figure that may be anywhere from ``worst`` (None: unbounded below) up to ``value``
    against a lower limit (exact; a figure equal to the limit passes): pass when even the worst
    end meets it, fail when the value itself misses it, else indeterminate."""
    if value < limit:
        return "fail"
    return "pass" if worst is not None and worst >= limit else "indeterminate"


def evaluate_pair(config: FirmwareConfig, g: GeneratorGuarantee, drive: Drive) -> PairResult:
    """Every step/dir rule of ``drive`` against axis ``g`` of ``config``."""
    rows: list[PairRow] = []
    for r in applicable("step-dir"):
        if r.figure == "none":
            continue
        role, fig, added, note = _mapping(g, drive, r)
        offset = added.value or Fraction(0)
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
        assert fig is not None and fig.value is not None
        worst = worst_end(fig, rate, added)
        verdict = band_verdict(value, worst, limit)
        in_band = verdict == "indeterminate"
        if in_band:
            bands = [f.band_text(rate) for f in (fig, added) if f.banded]
            note = (
                "; ".join(x for x in (note, *bands) if x)
                + (
                    f": {format_ns(worst)} against the {format_ns(limit)} limit at worst"
                    if worst is not None
                    else ""
                )
                + "; measure it"
            )
        if fig.status == "not_enforced":
            note = "; ".join(x for x in (note, fig.note) if x)
            if verdict == "pass":
                verdict = "indeterminate"  # the setting meets the limit; the firmware need not
        split = False  # the two readings of a disputed figure give different verdicts
        if other is not None:
            split = _judge(other, limit) != _judge(value, limit)
            said = f"{format_ns(value)} under the reading used, {format_ns(other)} under the other"
            note = "; ".join(x for x in (note, said) if x)
            if split:
                verdict = "indeterminate"
                note += ": the readings give different verdicts (measure it)"
        fix = ""
        clears = in_band and worst is not None  # an unbounded band: no value clears it
        if verdict == "fail" or (verdict == "indeterminate" and (split or clears)):
            fix = config.fix(g, _fix_role(role, g, drive), _need(fig, added, drive, limit, role))
        rows.append(PairRow(r.id, role, value, fig, limit, limit_fig, margin, verdict, fix, note,
                            worst_ns=worst, in_band=in_band))  # fmt: skip
    notes = list(g.notes)
    if drive.active_edge == "both" and not g.both_edges:
        notes.append("the drive counts both edges but the generator makes one step per pulse")
    return PairResult(config.firmware, g, drive, tuple(rows), _pair_rate(g, drive), tuple(notes))


def _need(
    fig: Guaranteed, added: Guaranteed, drive: Drive, limit: Fraction, role: Role
) -> Fraction:
    """What the figure must reach for the rule to pass at the band's worst end: the limit less
    the added figure's worst end, plus the band (a rate: the drive's maximum less the band);
    an unbounded band adds nothing (no value can clear it: the fix only ends the FAIL)."""
    if role == "max_rate":
        top = drive.max_rate.value if drive.max_rate else Fraction(0)
        return max(top - (fig.short_by or Fraction(0)), Fraction(0))
    added_worst = _floor0((added.value or Fraction(0)) - (added.short_by or Fraction(0)))
    return limit - added_worst + (fig.short_by or Fraction(0))


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
    top = g.max_rate  # the generator's ceiling: its value plus its band (no band top: none)
    ceiling = None if top.value is None or top.short_by is None else top.value + top.short_by
    rates = [v for v in (timing, drive_rate, ceiling) if v is not None]
    return min(rates) if rates else None
