"""Did the configured timing take effect? A checked capture against its own firmware's guarantee.

:func:`firmware_check` compares a :class:`~wavecheck.report.model.Report` with an axis's
:class:`~wavecheck.firmware.model.GeneratorGuarantee`: the shortest measured pulse vs the configured
pulse, the shortest DIR setup seen vs the configured delay (to the drive's active edge: plus the
pulse when that edge ends the pulse), in both-edge mode the shortest space too, and the highest
step rate vs the configured maximum. A capture shorter than its own configuration (by more than
the capture's resolution) is a finding of its own, apart from the drive's rules. Only intervals
the drive's rules measured are compared (a rule the drive states no figure for is not measured).
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction
from typing import TYPE_CHECKING

from wavecheck.checks.rates import pulse_level
from wavecheck.firmware.model import FirmwareConfig, GeneratorGuarantee, Guaranteed
from wavecheck.units import format_ns, format_rate, format_time
from wavecheck.verdict import Verdict, overall_verdict

if TYPE_CHECKING:
    from wavecheck.report.model import Report

__all__ = ["Comparison", "FirmwareCheck", "firmware_check"]


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


@dataclass(frozen=True)
class FirmwareCheck:
    """Every comparison of one capture with one axis's configured figures."""

    firmware: str
    path: str
    axis: GeneratorGuarantee
    comparisons: tuple[Comparison, ...]

    @property
    def verdict(self) -> Verdict:
        """fail when the capture violates its own configuration, else pass (unchecked when
        nothing could be compared)."""
        return overall_verdict(c.verdict for c in self.comparisons)

    @property
    def findings(self) -> tuple[Comparison, ...]:
        """The comparisons that failed."""
        return tuple(c for c in self.comparisons if c.verdict == "fail")


def _time(
    report: Report, what: str, rule: str, fig: Guaranteed, offset: Fraction, label: str
) -> Comparison:
    configured = None if fig.value is None else fig.value + offset
    where = fig.where
    rr = report.rule(rule)
    measured = rr.min_measured_ns if rr is not None else None
    at = rr.min_margin_at_s if rr is not None else None
    if configured is None:
        return Comparison(what, rule, None, measured, "ns", at, fig.setting, where, "unchecked",
                          f"the configuration guarantees no {label}")
    if measured is None:
        return Comparison(what, rule, configured, None, "ns", None, fig.setting, where, "unchecked",
                          f"configured {format_ns(configured)} {label}; not measured (the drive states no {rule})")
    t = report.resolution_ns
    exact = "" if fig.status not in ("uncertain",) else " (the firmware does not enforce it exactly)"
    place = f" at {format_time(at)}" if at is not None else ""
    if measured + t < configured:
        return Comparison(what, rule, configured, measured, "ns", at, fig.setting, where, "fail",
                          f"configured {format_ns(configured)} {label} ({fig.setting}, {where}); shortest "
                          f"measured {format_ns(measured)}{place}{exact}")
    return Comparison(what, rule, configured, measured, "ns", at, fig.setting, where, "pass",
                      f"configured {format_ns(configured)} {label}; shortest measured {format_ns(measured)}")


def firmware_check(report: Report, config: FirmwareConfig, axis: GeneratorGuarantee) -> FirmwareCheck:
    """Compare ``report``'s capture with ``axis``'s configured figures (see the module doc)."""
    level = pulse_level(report.interface, report.step_type, axis.pulse_level)
    pulse_rule, space_rule = ("step_high", "step_low") if level else ("step_low", "step_high")
    leading = "rising" if level else "falling"
    out = [_time(report, "pulse", pulse_rule, axis.pulse, Fraction(0), "pulses")]
    if axis.both_edges:
        out.append(_time(report, "space", space_rule, axis.idle, Fraction(0), "space between edges"))
    trailing = report.active_edge not in (leading, "both") and axis.pulse.value is not None
    offset = axis.pulse.value if trailing and axis.pulse.value is not None else Fraction(0)
    out.append(_time(report, "dir_setup", "dir_setup", axis.dir_setup, offset, "DIR setup"))
    cfg_rate, seen = axis.max_rate.value, report.rates.observed
    if cfg_rate is None or seen is None:
        out.append(Comparison("rate", "", cfg_rate, seen, "Hz", None, axis.max_rate.setting,
                              axis.max_rate.where, "unchecked", "no configured maximum or no steps"))
    else:
        at = report.rates.observed_at_s
        ok = seen <= cfg_rate
        out.append(Comparison(
            "rate", "", cfg_rate, seen, "Hz", at, axis.max_rate.setting, axis.max_rate.where,
            "pass" if ok else "fail",
            f"configured at most {format_rate(cfg_rate)} ({axis.max_rate.setting}); highest measured "
            f"{format_rate(seen)}" + ("" if ok or at is None else f" at {format_time(at)}"),
        ))
    return FirmwareCheck(config.firmware, config.path, axis, tuple(out))
