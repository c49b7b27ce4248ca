"""Maximum achievable step rate, in exact hertz.

- ``drive`` = min(datasheet max rate, 1 / (step_high + step_low limits)); either part may be
  missing, both missing gives None.
- ``observed`` = 1 / the shortest interval between successive steps in the capture.
- ``headroom``: the highest rate at which this generator's pulses would still pass. A step
  generator makes pulses of a fixed length and shortens the gaps between them as the rate rises,
  so at the rate f the gap is 1/f − pulse and must stay at least the drive's minimum for the gap's
  level: headroom = 1 / (typical pulse + that minimum), capped by the drive's own figures (the
  binding one is named in :attr:`MaxStepRates.headroom_limited_by`). The typical pulse is the
  median of the complete pulses (one pulse stretched by latency does not decide it); the longest is
  reported beside it. No headroom (None, with the reason in :attr:`MaxStepRates.headroom_note`)
  when the pulses fail their own minimum (no rate helps), the drive states no minimum for the gap's
  level, the drive steps on both edges, or the step type has phases.

The pulse level is not read from the capture's duty cycle: a step generator's pulses are high at
its output (LinuxCNC's stepgen, grbl, Marlin, Klipper and Smoothieware by default), so at the
drive's input they are high, or low when the STEP (UP/DOWN) role is inverted (``--invert step``).
``pulse_level`` overrides that for a generator whose output pulses are low.
"""

from __future__ import annotations

from fractions import Fraction
from typing import TYPE_CHECKING

import numpy as np

from wavecheck.drives.datasheet import ActiveEdge, Drive
from wavecheck.record import record, replace
from wavecheck.rules import width_rule
from wavecheck.steps.decode import StepEvents, touches_stretches, unknown_stretches
from wavecheck.steps.interface import StepInterface
from wavecheck.steps.primitives import Intervals, widths
from wavecheck.steptypes import StepType
from wavecheck.timebase import Timebase

if TYPE_CHECKING:  # the LinuxCNC config is read only when given
    import numpy.typing as npt

    from wavecheck.linuxcnc.stepgen_config import ConfigRates

__all__ = ["MaxStepRates", "max_step_rates", "rates_from"]

_GIGA = Fraction(10**9)
_BLOCK = 1 << 20


def _diff_extreme(
    start: npt.NDArray[np.int64], end: npt.NDArray[np.int64], smallest: bool
) -> tuple[int, int]:
    """The smallest (or largest) ``end[i] - start[i]`` and its first index ``i`` (arrays not empty).

    Block by block into one reused buffer: no full-length temporary (fresh memory is what costs
    in a VM; bench/README.md).
    """
    buf = np.empty(min(len(start), _BLOCK), dtype=np.int64)
    best_v, best_i = 0, -1
    for i in range(0, len(start), _BLOCK):
        j = min(len(start), i + _BLOCK)
        d = buf[: j - i]
        np.subtract(end[i:j], start[i:j], out=d)
        k = int(np.argmin(d)) if smallest else int(np.argmax(d))
        v = int(d[k])
        if best_i < 0 or (v < best_v if smallest else v > best_v):
            best_v, best_i = v, i + k
    return best_v, best_i


def pulse_level(iface: StepInterface, st: StepType, generator_level: int = 1) -> int:
    """The level of the generator's pulses at the drive's input: ``generator_level`` (1: pulses
    high at the generator's output), flipped when the pulse roles are inverted."""
    inverted = any(s.inverted for s in (iface.get(r) for r in st.pulse_roles) if s is not None)
    return generator_level ^ int(inverted)


@record(frozen=True)
class MaxStepRates:
    """Maximum step rates in exact Hz (None where not defined).

    Attributes:
        drive: what the drive's figures allow.
        drive_limited_by: ``"max_rate"``, ``"pulse"`` (step_high + step_low) or None.
        observed: the capture's highest instantaneous rate.
        observed_at_s: start of the shortest step interval, exact seconds.
        headroom: the highest rate at which the observed pulses would still pass (module doc).
        longest_pulse_ns: the longest observed pulse (a stretch at :attr:`pulse_level`), exact ns.
        idle_min_ns: the drive's minimum for the other level, exact ns.
        pulse_level: the level of the generator's pulses at the drive's input (1 high, 0 low).
        typical_pulse_ns: the median pulse (the lower middle one), exact ns.
        headroom_limited_by: ``"gap"`` (typical pulse + the gap's minimum), ``"max_rate"`` or
            ``"pulse"`` (the drive's own step_high + step_low).
        headroom_note: why there is no headroom, or None.
        configured: the ``config`` and ``latency_safe`` rates of a stepgen configuration, with
            the settings they assume (None when no configuration was given).
    """

    drive: Fraction | None
    drive_limited_by: str | None
    observed: Fraction | None
    observed_at_s: Fraction | None
    headroom: Fraction | None
    longest_pulse_ns: Fraction | None
    idle_min_ns: Fraction | None
    pulse_level: int | None = None
    typical_pulse_ns: Fraction | None = None
    headroom_limited_by: str | None = None
    headroom_note: str | None = None
    configured: ConfigRates | None = None

    def named(self) -> dict[str, Fraction | None]:
        """The five rates by their report names: drive, observed, headroom, config,
        latency_safe (Hz; None where not defined)."""
        return {
            "drive": self.drive,
            "observed": self.observed,
            "headroom": self.headroom,
            "config": self.config,
            "latency_safe": self.latency_safe,
        }

    @property
    def config(self) -> Fraction | None:
        """stepgen's own clamp for the configuration given, Hz (None without one)."""
        return None if self.configured is None else self.configured.config

    @property
    def latency_safe(self) -> Fraction | None:
        """The highest rate that meets the drive under the configuration's worst latency, Hz."""
        return None if self.configured is None else self.configured.latency_safe


def _median(start: npt.NDArray[np.int64], end: npt.NDArray[np.int64]) -> int:
    """The lower median of ``end - start`` (arrays not empty)."""
    d = end - start
    k = (len(d) - 1) // 2
    return int(np.partition(d, k)[k])


def max_step_rates(
    iface: StepInterface,
    st: StepType,
    steps: StepEvents,
    drive: Drive,
    active_edge: ActiveEdge,
    timebase: Timebase,
    *,
    level: int,
    pulse_verdict: str | None = None,
) -> MaxStepRates:
    """Compute ``drive``, ``observed`` and ``headroom`` for a decoded capture.

    Args:
        level: the generator's pulse level at the drive's input (:func:`pulse_level`).
        pulse_verdict: the verdict of the pulse level's own rule (step_high for high pulses);
            a fail means no rate would pass.
    """
    gap = None
    unknown = unknown_stretches(iface, st.pulse_roles)  # no figure from an interval touching one
    a, b = steps.ticks[:-1], steps.ticks[1:]
    if len(unknown[0]):
        keep = ~touches_stretches(a, b, *unknown)
        a, b = a[keep], b[keep]
    if len(a):
        g, i = _diff_extreme(a, b, smallest=True)
        gap = (g, int(a[i]))
    pulse = None
    if st.kind != "phases" and active_edge != "both":
        sigs = [s for s in (iface.get(r) for r in st.pulse_roles) if s is not None]
        pulses = Intervals.concat([widths(s.initial, s.edges, level) for s in sigs])
        if len(unknown[0]) and len(pulses):
            keep = ~touches_stretches(pulses.start, pulses.end, *unknown)
            pulses = Intervals(pulses.start[keep], pulses.end[keep])
        if len(pulses):
            longest = _diff_extreme(pulses.start, pulses.end, smallest=False)[0]
            pulse = (longest, _median(pulses.start, pulses.end))
    return rates_from(
        drive,
        st,
        active_edge,
        timebase,
        level=level,
        pulse_verdict=pulse_verdict,
        gap=gap,
        pulse=pulse,
    )


def rates_from(
    drive: Drive,
    st: StepType,
    active_edge: ActiveEdge,
    timebase: Timebase,
    *,
    level: int,
    pulse_verdict: str | None,
    gap: tuple[int, int] | None,
    pulse: tuple[int, int] | None,
) -> MaxStepRates:
    """:func:`max_step_rates` from the capture's figures: ``gap`` the shortest interval between
    successive steps and the tick of the first such step (None: fewer than two steps), ``pulse``
    the longest and the (lower) median complete pulse at ``level`` in ticks (None: no complete
    pulse). Both are mergeable window by window (:mod:`wavecheck.engine.axis`)."""
    cap, limited_by = drive.step_rate()
    observed = observed_at = None
    if gap is not None and gap[0] > 0:
        observed = _GIGA / timebase.ns(gap[0])
        observed_at = timebase.seconds(gap[1])
    out = MaxStepRates(cap, limited_by, observed, observed_at, None, None, None, level)
    if st.kind == "phases" or active_edge == "both":
        why = "phase outputs" if st.kind == "phases" else "a drive that steps on both edges"
        return replace(out, pulse_level=None, headroom_note=f"not defined for {why}")
    if pulse is None:
        return replace(out, headroom_note="no complete pulse in the capture")
    longest = timebase.ns(pulse[0])
    typical = timebase.ns(pulse[1])
    own, other = width_rule(level), width_rule(1 - level)
    idle_min = drive.limit_ns(other)
    out = replace(out, longest_pulse_ns=longest, typical_pulse_ns=typical, idle_min_ns=idle_min)
    if pulse_verdict == "fail":
        return replace(out, headroom_note=f"the pulses fail {own} at any rate")
    if idle_min is None:
        return replace(out, headroom_note=f"the drive states no {other} minimum for the gaps")
    if typical + idle_min <= 0:
        return replace(out, headroom_note="zero-length pulses and gaps")
    headroom, by = _GIGA / (typical + idle_min), "gap"
    if cap is not None and cap < headroom:
        headroom, by = cap, limited_by or "drive"
    return replace(out, headroom=headroom, headroom_limited_by=by)
