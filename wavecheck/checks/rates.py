"""Maximum achievable step rate, in exact hertz.

- ``drive`` = min(datasheet max rate, 1 / (step_high + step_low limits)); either part may be
  missing, both missing gives None.
- ``observed`` = 1 / the shortest interval between successive steps in the capture.
- ``headroom`` = 1 / (longest observed pulse + the drive's minimum for the other level), capped
  by ``drive``: the highest rate at which pulses as long as this generator's would still leave
  the drive its minimum time at the other level. The design says "longest observed active-level
  time + the drive's idle-level minimum"; that is this formula when the generator's pulse starts
  at the active edge (a rising-edge drive, or a falling-edge drive with STEP inverted). When it
  ends at the active edge (Stepper Tuning's G202: falling-edge drive, STEP not inverted) the
  active level is the *gap* between pulses, whose longest value is the longest pause in the
  capture (seconds), and the literal formula would be meaningless. So the pulse level is taken
  from the capture: the level whose longest complete stretch is the shorter one (pulses are
  short and fixed, gaps grow as the rate falls); :attr:`MaxStepRates.pulse_level` says which.
  Not defined for phase types or a drive that steps on both edges.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from fractions import Fraction

import numpy as np
import numpy.typing as npt

from wavecheck.checks.primitives import Intervals, widths
from wavecheck.decode import StepEvents
from wavecheck.drives.model import ActiveEdge, Drive
from wavecheck.interface import RoleSignal, StepInterface
from wavecheck.linuxcnc.config import ConfigRates
from wavecheck.linuxcnc.steptypes import StepType
from wavecheck.timebase import Timebase

__all__ = ["MaxStepRates", "max_step_rates"]

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


def generator_pulses(signals: Sequence[RoleSignal]) -> tuple[int, int] | None:
    """The level of the generator's pulses and the longest pulse in ticks, read from the capture.

    Pulses are short and of fixed length while the gaps between them grow as the rate falls, so
    the pulse level is the one whose longest stretch is shorter (high on a tie). None when the
    signals never complete a stretch at either level.
    """
    longest_at: dict[int, int] = {}
    for level in (0, 1):
        stretch = Intervals.concat([widths(s.initial, s.edges, level) for s in signals])
        if len(stretch):
            longest_at[level] = _diff_extreme(stretch.start, stretch.end, smallest=False)[0]
    if not longest_at:
        return None
    level = min(longest_at, key=lambda lv: (longest_at[lv], lv != 1))
    return level, longest_at[level]


@dataclass(frozen=True)
class MaxStepRates:
    """Maximum step rates in exact Hz (None where not defined).

    Attributes:
        drive: what the drive's figures allow.
        drive_limited_by: ``"max_rate"``, ``"pulse"`` (step_high + step_low) or None.
        observed: the capture's highest instantaneous rate.
        observed_at_s: start of the shortest step interval, exact seconds.
        headroom: the highest rate at which the observed pulse lengths would still pass.
        longest_pulse_ns: the longest observed pulse (a stretch at :attr:`pulse_level`), exact ns.
        idle_min_ns: the drive's minimum for the other level, exact ns.
        pulse_level: the level of the generator's pulses (1 high, 0 low), from the capture.
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
    st: StepType,
    steps: StepEvents,
    drive: Drive,
    active_edge: ActiveEdge,
    timebase: Timebase,
) -> MaxStepRates:
    """Compute ``drive``, ``observed`` and ``headroom`` for a decoded capture."""
    cap, limited_by = drive_rate(drive)
    observed = observed_at = None
    if steps.count > 1:
        gap, i = _diff_extreme(steps.ticks[:-1], steps.ticks[1:], smallest=True)
        if gap > 0:
            observed = _GIGA / timebase.ns(gap)
            observed_at = timebase.seconds(int(steps.ticks[i]))
    headroom = longest = idle_min = None
    pulse_level: int | None = None
    if st.kind != "phases" and active_edge != "both":
        found = generator_pulses([s for s in (iface.get(r) for r in st.pulse_roles) if s is not None])
        if found is not None:
            pulse_level, longest_ticks = found
            longest = timebase.ns(longest_ticks)
            idle_min = drive.limit_ns("step_low" if pulse_level == 1 else "step_high")
            if idle_min is not None and longest + idle_min > 0:
                headroom = _GIGA / (longest + idle_min)
                if cap is not None:
                    headroom = min(headroom, cap)
    return MaxStepRates(
        cap, limited_by, observed, observed_at, headroom, longest, idle_min, pulse_level
    )
