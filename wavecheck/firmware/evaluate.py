"""Can a configuration meet a drive? Each rule: the generator's guaranteed figure vs the drive's
limit, the margin, the verdict, and the setting to change when it fails (exact arithmetic; a
figure exactly equal to the limit passes).

Mapping (levels at the drive's input = the generator's output): the pulse is the high time when
pulses are high, else the low time. DIR setup/hold count from the drive's active edge: when that
is the pulse's trailing edge, setup gains the pulse width and hold is the trailing-edge hold. A
generator in both-edge mode configures the drive (TMC ``dedge``) to count both edges.
``step_period`` compares the axis's configured max step rate with the drive's. The max step rate
of the pair is min(the drive's max rate, 1 / (pulse + the drive's minimum for the idle level)), or
1 / the longest of the pulse and the two level minimums in both-edge mode.
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction

from wavecheck.drives.model import Drive, Figure
from wavecheck.firmware.model import FirmwareConfig, GeneratorGuarantee, Guaranteed, Role
from wavecheck.rules import applicable
from wavecheck.verdict import Verdict, overall_verdict

__all__ = ["PairResult", "PairRow", "evaluate_pair"]

_GIGA = Fraction(10**9)


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


def _mapping(
    g: GeneratorGuarantee, drive: Drive, rule: str
) -> tuple[Role | None, Guaranteed | None, Fraction, str]:
    """(role, figure, offset added, note) for ``rule``."""
    edge = "both" if g.both_edges else drive.active_edge
    trailing = edge != g.leading_edge and not g.both_edges
    if rule == "step_high":
        role: Role = "pulse" if g.pulse_level else "idle"
        return role, g.figure(role), Fraction(0), ""
    if rule == "step_low":
        role = "idle" if g.pulse_level else "pulse"
        return role, g.figure(role), Fraction(0), ""
    if rule == "dir_setup":
        if trailing and edge != "both" and g.pulse.value is not None:
            return (
                "dir_setup",
                g.dir_setup,
                g.pulse.value,
                "the drive's active edge ends the pulse: setup + pulse",
            )
        return "dir_setup", g.dir_setup, Fraction(0), ""
    if rule == "dir_hold":
        if trailing:
            return (
                "dir_hold",
                g.dir_hold_trailing,
                Fraction(0),
                "the drive's active edge ends the pulse: hold from the trailing edge",
            )
        return "dir_hold", g.dir_hold, Fraction(0), ""
    if rule == "step_period":
        return "max_rate", g.max_rate, Fraction(0), ""
    return None, None, Fraction(0), "the configuration says nothing about this"


def evaluate_pair(config: FirmwareConfig, g: GeneratorGuarantee, drive: Drive) -> PairResult:
    """Every step/dir rule of ``drive`` against axis ``g`` of ``config``."""
    rows: list[PairRow] = []
    for r in applicable("step-dir"):
        if r.figure == "none":
            continue
        role, fig, offset, note = _mapping(g, drive, r.id)
        if r.figure == "max_rate":
            limit_fig = drive.max_rate
            limit = _GIGA / limit_fig.value if limit_fig else None
            value = _GIGA / fig.value if fig is not None and fig.value else None
        else:
            limit_fig = drive.limits.get(r.id)
            limit = limit_fig.value if limit_fig else None
            value = fig.value + offset if fig is not None and fig.value is not None else None
        if role is None:
            rows.append(
                PairRow(r.id, None, None, None, limit, limit_fig, None, "unchecked", note=note)
            )
            continue
        if limit is None:
            rows.append(
                PairRow(
                    r.id,
                    role,
                    value,
                    fig,
                    None,
                    None,
                    None,
                    "unchecked",
                    note="the drive states no limit",
                )
            )
            continue
        if value is None:
            why = (
                fig.note
                if fig is not None and fig.note
                else note or "no bound in the configuration"
            )
            rows.append(
                PairRow(
                    r.id,
                    role,
                    None,
                    fig,
                    limit,
                    limit_fig,
                    None,
                    "indeterminate",
                    note=f"{why}; measure it",
                )
            )
            continue
        margin = value - limit
        verdict: Verdict = "pass" if margin >= 0 else "fail"
        fix = ""
        if verdict == "fail" and role is not None:
            need = (
                (drive.max_rate.value if drive.max_rate else Fraction(0))
                if role == "max_rate"
                else limit - offset
            )
            if r.id == "dir_hold" and note and g.pulse.value is not None:
                need = (
                    limit + g.pulse.value
                )  # a hold from the trailing edge, as a hold from the leading one
                note += " (inverting STEP would make it the leading edge)"
            fix = config.fix(g, role, need)
        rows.append(PairRow(r.id, role, value, fig, limit, limit_fig, margin, verdict, fix, note))
    notes = list(g.notes)
    if drive.active_edge == "both" and not g.both_edges:
        notes.append("the drive counts both edges but the generator makes one step per pulse")
    return PairResult(config.firmware, g, drive, tuple(rows), _pair_rate(g, drive), tuple(notes))


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
        timing = (
            _GIGA / total if total > 0 and (idle_lim is not None or pulse is not None) else None
        )
    rates = [v for v in (timing, drive.max_rate.value if drive.max_rate else None) if v is not None]
    return min(rates) if rates else None
