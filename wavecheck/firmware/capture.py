"""Did the configured timing take effect? A capture against its own firmware's guarantee.

:func:`firmware_check` compares what a capture shows of one axis (:class:`Observed`: from
``check``'s :class:`~wavecheck.engine.outcome.Report`, or from ``measure``'s
:class:`~wavecheck.measurement.AxisMeasurement` without a drive) with an axis's
:class:`~wavecheck.firmware.guarantee.GeneratorGuarantee`: the shortest measured pulse vs the configured
pulse, the shortest DIR setup seen vs the configured delay (to the drive's active edge: plus the
pulse when that edge ends the pulse), in both-edge mode the shortest space too, and the highest
step rate vs the configured maximum. A capture shorter than its own configuration (by more than
the capture's resolution) is a finding of its own, apart from the drive's rules, but only when
it is shorter than the band the firmware may fall short by (:attr:`Guaranteed.short_by`): a
measured figure inside that band is what the firmware does, and a figure with a band no source
bounds cannot show that the setting did not take effect (indeterminate). From a Report,
only intervals the drive's rules measured are compared (a rule the drive states no figure for is
not measured); ``measure`` measures every interval kind of the step type.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, replace
from fractions import Fraction
from typing import TYPE_CHECKING

from wavecheck.drives.datasheet import ActiveEdge
from wavecheck.engine.planning import pulse_level
from wavecheck.firmware.guarantee import FirmwareConfig, GeneratorGuarantee, Guaranteed
from wavecheck.rules import rate_rule, width_rule
from wavecheck.steps.interface import StepInterface
from wavecheck.steptypes import StepType
from wavecheck.units import format_ns, format_rate, format_time
from wavecheck.verdict import Verdict, overall_verdict

if TYPE_CHECKING:
    from wavecheck.engine import Report
    from wavecheck.measurement import AxisMeasurement

__all__ = [
    "Comparison",
    "FirmwareCheck",
    "Observed",
    "firmware_check",
    "observed_in_measurement",
    "observed_in_report",
]


@dataclass(frozen=True)
class Observed:
    """What a capture shows of one axis, as the comparison needs it.

    Attributes:
        interface: the mapped signals (levels after ``--invert``).
        step_type: the step type decoded.
        active_edge: the STEP edge that counts a step.
        resolution_ns: T, exact ns (a shorter figure counts only when shorter by more than T).
        shortest: rule id → (the shortest interval in exact ns, where it starts in exact s).
        rate_hz: the highest instantaneous step rate, exact Hz (None: fewer than two steps).
        rate_at_s: where that rate's step interval starts, exact s.
        unmeasured: why a rule has no figure, in words (``"the drive states no {rule}"``).
        axis_name: the capture axis's name in a run of several axes (None: unnamed).
    """

    interface: StepInterface
    step_type: StepType
    active_edge: ActiveEdge
    resolution_ns: Fraction
    shortest: Mapping[str, tuple[Fraction, Fraction | None]]
    rate_hz: Fraction | None
    rate_at_s: Fraction | None
    unmeasured: str = "the drive states no {rule}"
    axis_name: str | None = None


def observed_in_report(report: Report) -> Observed:
    """``check``'s report of one axis as an :class:`Observed` (the rules the drive measured)."""
    shortest = {
        r.rule: (r.min_measured_ns, r.min_margin_at_s)
        for r in report.rules
        if r.min_measured_ns is not None
    }
    return Observed(report.interface, report.step_type, report.active_edge, report.resolution_ns,
                    shortest, report.rates.observed, report.rates.observed_at_s,
                    axis_name=report.axis)  # fmt: skip


def observed_in_measurement(axis: AxisMeasurement, resolution_ns: Fraction) -> Observed:
    """``measure``'s figures of one axis as an :class:`Observed` (every interval kind of its
    step type; the first shortest of each)."""
    shortest: dict[str, tuple[Fraction, Fraction | None]] = {}
    for s in axis.stats:
        ns = s.min_ns
        if ns is not None:
            shortest[s.rule] = (ns, None if s.min_at is None else s.timebase.seconds(s.min_at))
    period = next((s for s in axis.stats if s.rule == rate_rule()), None)
    at = None
    if period is not None and period.min_at is not None:
        at = period.timebase.seconds(period.min_at)
    return Observed(axis.interface, axis.step_type, axis.active_edge, resolution_ns,
                    shortest, axis.rate_max_hz, at, "no such interval in the capture",
                    axis_name=axis.name)  # fmt: skip


@dataclass(frozen=True)
class Comparison:
    """One configured figure vs the capture (ns, or Hz for ``rate``)."""

    what: str
    """``pulse``, ``space``, ``dir_setup`` or ``rate``."""
    rule: str
    """The drive rule whose intervals were compared ("" for the rate)."""
    configured: Fraction | None
    measured: Fraction | None
    unit: str
    at_s: Fraction | None
    setting: str
    where: str
    verdict: Verdict
    message: str
    short_by: Fraction | None = Fraction(0)
    """How far below ``configured`` the firmware may fall (Hz above it for the rate; None: no
    source bounds it): a measured figure inside that band is no finding."""


@dataclass(frozen=True)
class FirmwareCheck:
    """Every comparison of one capture with one axis's configured figures."""

    firmware: str
    path: str
    axis: GeneratorGuarantee
    comparisons: tuple[Comparison, ...]
    pairing: str = ""
    """Which capture axis was compared with this firmware axis, and how they were paired."""

    @property
    def verdict(self) -> Verdict:
        """fail when the capture violates its own configuration, else pass (unchecked when
        nothing could be compared)."""
        return overall_verdict(c.verdict for c in self.comparisons)

    @property
    def findings(self) -> tuple[Comparison, ...]:
        """The comparisons that failed."""
        return tuple(c for c in self.comparisons if c.verdict == "fail")


def _band(figs: list[Guaranteed]) -> Fraction | None:
    """The sum of the figures' bands (None when one is unbounded)."""
    short: Fraction | None = Fraction(0)
    for f in figs:
        short = None if short is None or f.short_by is None else short + f.short_by
    return short


def _time(
    seen: Observed, what: str, rule: str, fig: Guaranteed, added: Guaranteed | None, label: str
) -> Comparison:
    """``fig`` (+ ``added``: the pulse, to a trailing active edge) vs the shortest measured: a
    FAIL only below the band's worst end (:attr:`Guaranteed.short_by`), by more than T."""
    found = _time_verdict(seen, what, rule, fig, added, label)
    return replace(found, short_by=_band([f for f in (fig, added) if f is not None]))


def _time_verdict(
    seen: Observed, what: str, rule: str, fig: Guaranteed, added: Guaranteed | None, label: str
) -> Comparison:
    offset = added.value if added is not None and added.value is not None else Fraction(0)
    configured = None if fig.value is None else fig.value + offset
    where = fig.where
    measured, at = seen.shortest.get(rule, (None, None))
    if configured is None:
        return Comparison(
            what,
            rule,
            None,
            measured,
            "ns",
            at,
            fig.setting,
            where,
            "unchecked",
            f"the firmware does not enforce a {label}: measure it"
            if fig.status == "not_enforced"
            else f"the configuration guarantees no {label}",
        )
    if measured is None:
        return Comparison(
            what,
            rule,
            configured,
            None,
            "ns",
            None,
            fig.setting,
            where,
            "unchecked",
            f"configured {format_ns(configured)} {label}; not measured ({seen.unmeasured.format(rule=rule)})",
        )
    if fig.status == "not_enforced":
        return Comparison(what, rule, configured, measured, "ns", at, fig.setting, where,
                          "unchecked",
                          f"configured {format_ns(configured)} {label}, which the firmware does "
                          f"not enforce; shortest measured {format_ns(measured)}")  # fmt: skip
    t = seen.resolution_ns
    bands = [f for f in (fig, added) if f is not None and f.banded]
    short = _band(bands)
    band = "; ".join(f.band_text() for f in bands)
    place = f" at {format_time(at)}" if at is not None else ""
    if measured + t < configured and (short is None or measured + t >= configured - short):
        within = (
            "inside the band the firmware may fall short by"
            if short is not None
            else "and the firmware may fall short of it by an amount no source bounds"
        )
        return Comparison(
            what, rule, configured, measured, "ns", at, fig.setting, where,
            "pass" if short is not None else "indeterminate",
            f"configured {format_ns(configured)} {label} ({fig.setting}, {where}); shortest "
            f"measured {format_ns(measured)}{place}, {within}: {band}",
        )  # fmt: skip
    if measured + t < configured - (short or Fraction(0)):
        worst = (
            f", below the {format_ns(configured - short)} it may fall to ({band})" if short else ""
        )
        return Comparison(
            what,
            rule,
            configured,
            measured,
            "ns",
            at,
            fig.setting,
            where,
            "fail",
            f"configured {format_ns(configured)} {label} ({fig.setting}, {where}); shortest "
            f"measured {format_ns(measured)}{place}{worst}",
        )
    return Comparison(
        what,
        rule,
        configured,
        measured,
        "ns",
        at,
        fig.setting,
        where,
        "pass",
        f"configured {format_ns(configured)} {label}; shortest measured {format_ns(measured)}",
    )


def firmware_check(
    subject: Report | Observed,
    config: FirmwareConfig,
    axis: GeneratorGuarantee,
    pairing: str = "",
) -> FirmwareCheck:
    """Compare a capture (``check``'s report, or an :class:`Observed`) with ``axis``'s
    configured figures (see the module doc); ``pairing`` says how the two were paired."""
    seen = subject if isinstance(subject, Observed) else observed_in_report(subject)
    level = pulse_level(seen.interface, seen.step_type, axis.pulse_level)
    pulse_rule, space_rule = width_rule(level), width_rule(1 - level)
    leading = "rising" if level else "falling"
    out = [_time(seen, "pulse", pulse_rule, axis.pulse, None, "pulses")]
    if axis.both_edges:
        out.append(_time(seen, "space", space_rule, axis.idle, None, "space between edges"))
    trailing = seen.active_edge not in (leading, "both") and axis.pulse.value is not None
    added = axis.pulse if trailing else None
    setup = axis.dir_setup
    if trailing and axis.dir_setup_trailing is not None:  # DIR may change during the pulse
        setup, added = axis.dir_setup_trailing, None
    out.append(_time(seen, "dir_setup", "dir_setup", setup, added, "DIR setup"))
    out.append(_rate(axis.max_rate, seen.rate_hz, seen.rate_at_s))
    return FirmwareCheck(config.firmware, config.path, axis, tuple(out), pairing)


def _rate(fig: Guaranteed, rate: Fraction | None, at: Fraction | None) -> Comparison:
    """The highest measured step rate against the configured maximum (and its band above)."""
    cfg = fig.value

    def said(verdict: Verdict, message: str, at_s: Fraction | None = at,
             short: Fraction | None = fig.short_by) -> Comparison:  # fmt: skip
        return Comparison("rate", "", cfg, rate, "Hz", at_s, fig.setting, fig.where, verdict,
                          message, short)  # fmt: skip

    if cfg is None or rate is None:
        return said("unchecked", "no configured maximum or no steps", None, Fraction(0))
    configured = f"configured at most {format_rate(cfg)} ({fig.setting}); highest measured "
    if fig.short_by is None and rate > cfg:  # the band has no top
        return said("indeterminate", f"{configured}{format_rate(rate)}, and "
                    f"{fig.band_text(rate=True)}", short=None)  # fmt: skip
    ok = rate <= cfg + (fig.short_by or Fraction(0))
    return said("pass" if ok else "fail", configured + format_rate(rate)
                + ("" if ok or at is None else f" at {format_time(at)}"))  # fmt: skip
