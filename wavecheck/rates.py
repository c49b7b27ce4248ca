"""Maximum achievable step rate, in exact hertz.

- ``drive`` = min(datasheet max rate, 1 / (step_high + step_low limits)); either part may be
  missing, both missing gives None.
- ``observed`` = 1 / the shortest interval between successive steps in the capture.
- ``headroom`` = 1 / (longest observed active-level time + the drive's idle-level minimum),
  capped by ``drive``: the highest rate at which pulses as long as this generator's would still
  leave the drive its idle time. The active level is the one that starts at the active edge
  (high for a rising-edge drive, low for a falling-edge drive; see drive-timing.md §0). Not
  defined for phase types or a drive that steps on both edges.
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction

import numpy as np

from wavecheck.checks.primitives import Intervals, widths
from wavecheck.decode import ActiveEdge, StepEvents
from wavecheck.drives.model import Drive
from wavecheck.interface import StepInterface
from wavecheck.timebase import Timebase

__all__ = ["MaxStepRates", "max_step_rates"]

_GIGA = Fraction(10**9)


@dataclass(frozen=True)
class MaxStepRates:
    """Maximum step rates in exact Hz (None where not defined).

    Attributes:
        drive: what the drive's figures allow.
        drive_limited_by: ``"max_rate"``, ``"pulse"`` (step_high + step_low) or None.
        observed: the capture's highest instantaneous rate.
        observed_at_s: start of the shortest step interval, exact seconds.
        headroom: the highest rate at which the observed pulse lengths would still pass.
        longest_active_ns: the longest observed active-level time, exact ns.
        idle_min_ns: the drive's idle-level minimum, exact ns.
    """

    drive: Fraction | None
    drive_limited_by: str | None
    observed: Fraction | None
    observed_at_s: Fraction | None
    headroom: Fraction | None
    longest_active_ns: Fraction | None
    idle_min_ns: Fraction | None


def drive_rate(drive: Drive) -> tuple[Fraction | None, str | None]:
    """The drive's own maximum step rate (Hz) and which figure limits it."""
    candidates: list[tuple[Fraction, str]] = []
    if drive.max_rate is not None and drive.max_rate.value > 0:
        candidates.append((drive.max_rate.value, "max_rate"))
    hi, lo = drive.limit_ns("step_high"), drive.limit_ns("step_low")
    if hi is not None and lo is not None and hi + lo > 0:
        candidates.append((_GIGA / (hi + lo), "pulse"))
    if not candidates:
        return None, None
    return min(candidates, key=lambda c: c[0])


def max_step_rates(
    iface: StepInterface,
    type_number: int,
    steps: StepEvents,
    drive: Drive,
    active_edge: ActiveEdge,
    timebase: Timebase,
) -> MaxStepRates:
    """Compute ``drive``, ``observed`` and ``headroom`` for a decoded capture."""
    cap, limited_by = drive_rate(drive)
    observed = observed_at = None
    if steps.count > 1:
        gaps = np.diff(steps.ticks)
        i = int(np.argmin(gaps))
        if gaps[i] > 0:
            observed = _GIGA / timebase.ns(int(gaps[i]))
            observed_at = timebase.seconds(int(steps.ticks[i]))
    headroom = longest = idle_min = None
    if type_number in (0, 1) and active_edge != "both":
        active_level = 1 if active_edge == "rising" else 0
        idle_min = drive.limit_ns("step_low" if active_level == 1 else "step_high")
        roles = ("step",) if type_number == 0 else ("up", "down")
        parts = []
        for role in roles:
            sig = iface.get(role)
            if sig is not None:
                parts.append(widths(sig.initial, sig.edges, active_level))
        active = Intervals.concat(parts)
        if len(active):
            longest = timebase.ns(int(active.measured.max()))
            if idle_min is not None and longest + idle_min > 0:
                headroom = _GIGA / (longest + idle_min)
                if cap is not None:
                    headroom = min(headroom, cap)
    return MaxStepRates(cap, limited_by, observed, observed_at, headroom, longest, idle_min)
