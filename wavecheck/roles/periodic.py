"""How a pulse train's rate behaves: the shapes that tell a step train from a clock, PWM or code.

A motor's step rate is continuous: it speeds up from rest and slows down to rest, and changes
little from one step to the next. The pulse trains of other protocols do not:

- a **clock** runs at one period with about 50 % duty, never pauses and never slows down (a
  free-running clock is never a STEP; a line at one period that slows down now and then, as a
  STEP reversing at its top rate does, is periodic pulses: a STEP when named so);
- a **PWM** line keeps its period and varies its pulse width (a step train keeps its width);
- a **periodic** line (a frame sync, a PWM carrier at fixed duty) keeps one period and never
  pauses: the waveform cannot tell it from steps at one constant speed;
- **bursts at one rate** (a gated clock: SPI, I2C, a bit-banged bus) start and stop at their
  full rate, with no speeding up or slowing down around the pauses;
- **coded** pulses (IR remotes, pulse-distance codes, SENT, Miller) change their period from one
  pulse to the next by more than a motor can: where the line runs fastest, a motor speeding up
  from rest at constant acceleration changes its period by 2.41×, then 1.30×, 1.19× …, so a
  jump is a change by 1.35× or more (at 10 % of neighbouring periods; 5 % when the pulse widths
  are exact, as a timer makes them, so the periods' changes are no timing jitter), or one there
  and back (at 5 % of three neighbours); and lines that run a pulse or two at a time between
  pauses are stop-and-go, not moves. The first and last period of a run, from and to rest,
  never count.

A quantised step generator (LinuxCNC's stepgen, a firmware's step timer) alternates between
neighbouring whole numbers of its base period, 2 and 3 periods at its top rate (1.5×): a change
by no more than 1.15 pulse widths is one tick of it (its pulses last a tick at least), no jump.
The rules look at the periods between pulse starts, in ticks, with a few ``numpy`` passes.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from wavecheck.record import record

if TYPE_CHECKING:
    import numpy.typing as npt

__all__ = ["Timing", "may_be_one_rate", "timing"]

_FEW = 3  # fewest periods to see one rate in
_MANY = 8  # fewest periods to see jumps in
_SHORT_RUNS = 3.0  # runs of fewer periods than this on average: stop-and-go, not moves
_PAUSE = 3.0  # a period this many times the shorter of the periods beside it: a pause
_RAMP = 1.25  # a ramp's first (last) period is this much longer than two later (earlier)
_RAMPS = 0.1  # share of runs that may ramp in a line at one rate (a stray slow start)
_JUMP = 1.35  # consecutive periods further apart than this (a motor speeding up from rest at
#   constant acceleration: 2.41, then 1.30, 1.19 …) …
_JUMP_WIDTHS = 1.15  # … and by more than this many pulse widths (a quantised step generator's
#   periods differ by one tick of it, and its pulses last at least one tick): a jump
_JUMPS = 0.1  # share of jumps that makes a line coded
_JUMPS_EXACT = 0.05  # … when the pulse widths are exact
_EXACT_WIDTHS = 0.02  # width spread (p95 - p5 over the median) of exact widths
_ZIGZAGS = 0.05  # share of there-and-back jumps that makes a line coded
_STEADY = 0.9  # share of periods at the median that makes one rate
_STEADY_TOL = 0.01  # … within this fraction of the median, plus two ticks of resolution
_CLOCK_DUTY = (0.4, 0.6)  # duty of a clock
_CLOCK_SLOW = 0.1  # a clock's longest period within runs is at most this much over its median
_PWM_SPREAD = 0.05  # width spread (p95 - p5) beyond this fraction of the median: PWM


@record(frozen=True)
class Timing:
    """The rate of one pulse train.

    Attributes:
        periods: number of periods (pulse start to next pulse start).
        period: median period within runs, ticks.
        steady: share of the periods within runs that lie at :attr:`period`.
        pauses: periods that are pauses (3 × the shorter of the periods beside them).
        ramps: runs that speed up after a pause or slow down before one.
        runs: runs of three periods or more.
        jumps: share of consecutive periods in a run, the shorter fast (within twice the 10th
            percentile), that jump (a ratio above 1.35 and a difference above 1.15 pulse
            widths).
        zigzags: share of three such consecutive periods that jump there and back.
        duty: median pulse width / :attr:`period`.
        width_spread: (p95 - p5) of the pulse widths / their median.
    """

    periods: int
    period: float
    steady: float
    pauses: int
    ramps: int
    runs: int
    jumps: float
    zigzags: float
    duty: float
    width_spread: float
    slowest: float = 1.0
    """The longest period within runs over :attr:`period` (a clock's stays at 1)."""

    @property
    def one_rate(self) -> bool:
        """Nearly every period within runs is the same, and no run speeds up or slows down."""
        return self.periods >= _FEW and self.steady >= _STEADY and self.ramps <= _RAMPS * self.runs

    @property
    def coded(self) -> bool:
        """The period jumps between neighbours, or runs are a pulse or two long: no motor's."""
        return bool(self.coded_why())

    def coded_why(self) -> str:
        """Why the pulses are coded, in words (empty when they are not)."""
        if self.periods < _MANY:
            return ""
        # with exact widths the periods' jumps are no timing jitter: the rate itself jumps
        exact = self.width_spread <= _EXACT_WIDTHS
        if self.jumps >= (_JUMPS_EXACT if exact else _JUMPS):
            return (
                f"{self.jumps:.0%} of neighbouring periods where it runs fastest differ by 1.35x "
                "or more"
            )
        if self.zigzags >= _ZIGZAGS:
            return f"its period jumps there and back in {self.zigzags:.0%} of three neighbours"
        per_run = (self.periods - self.pauses) / (self.pauses + 1)
        if per_run < _SHORT_RUNS:
            return f"it runs {per_run:.1f} periods at a time between pauses"
        return ""

    def shape(self, resolution: int) -> str:
        """``"coded"``, ``"pwm"``, ``"clock"``, ``"periodic"``, ``"bursts"``, ``"few"`` (fewer
        than 8 periods: too few to see a motor's rate in) or ``"steps"`` (a rate that changes as
        a motor's does); ``resolution`` in ticks."""
        if self.coded:
            return "coded"
        if not self.one_rate:
            return "few" if self.periods < _MANY else "steps"
        if self.pauses == 0:
            lo, hi = _CLOCK_DUTY
            spread_ticks = self.width_spread * self.duty * self.period
            if spread_ticks > max(2 * resolution + 2, _PWM_SPREAD * self.duty * self.period):
                return "pwm"
            free = self.slowest <= 1 + _CLOCK_SLOW  # a clock never slows down, even once
            return "clock" if lo <= self.duty <= hi and free else "periodic"
        return "bursts"


def _runs(
    per: npt.NDArray[np.float64], resolution: int
) -> tuple[npt.NDArray[np.bool_], npt.NDArray[np.float64], float, float, float]:
    """Of the periods ``per`` (at least one): which are pauses, those within runs, their
    median, the tolerance around it and the share of periods within runs inside it."""
    prev = np.r_[per[1:2], per[:-1]] if len(per) > 1 else per
    nxt = np.r_[per[1:], per[-2:-1]] if len(per) > 1 else per
    pause = per > _PAUSE * np.minimum(prev, nxt)
    inrun = per[~pause]
    period = float(np.median(inrun))
    tol = 2 * resolution + _STEADY_TOL * period
    steady = float(np.mean(np.abs(inrun - period) <= tol))
    return pause, inrun, period, tol, steady


def may_be_one_rate(starts: npt.NDArray[np.int64], resolution: int) -> bool:
    """False when pulses starting at ``starts`` are surely not at one rate
    (:attr:`Timing.one_rate` of their :func:`timing` is False): too few periods, or too few of
    them at the median. A first part of :func:`timing`, for a line most of whose look is not
    needed."""
    per = np.diff(starts).astype(np.float64)
    return len(per) >= _FEW and _runs(per, resolution)[4] >= _STEADY


def timing(starts: npt.NDArray[np.int64], widths: npt.NDArray[np.int64], resolution: int) -> Timing:
    """The :class:`Timing` of pulses starting at ``starts`` with ``widths`` (ticks; at least two
    pulses); ``resolution`` is the capture's resolution in ticks."""
    per = np.diff(starts).astype(np.float64)
    w = widths.astype(np.float64)
    mid_w = float(np.median(w))
    p5, p95 = np.percentile(w, [5, 95]) if len(w) else (0.0, 0.0)
    spread = float((p95 - p5) / mid_w) if mid_w > 0 else 0.0
    if len(per) == 0:
        return Timing(0, 0.0, 0.0, 0, 0, 0, 0.0, 0.0, 0.0, spread)
    pause, inrun, period, tol, steady = _runs(per, resolution)
    # jumps between consecutive periods inside one run, where the line runs fast (the shorter
    # period within 2x its 10th percentile: a motor speeding up from rest, or making a move of a
    # few steps, jumps, but only while slow): one way, or there and back
    # the first and last period of a run start from rest or end in it: no jump counts there
    edge = np.zeros(len(per), dtype=bool)
    edge[0] = edge[-1] = True
    edge[np.flatnonzero(pause[:-1]) + 1] = True
    edge[np.flatnonzero(pause[1:])] = True
    inside = ~pause[1:] & ~pause[:-1] & ~edge[:-1] & ~edge[1:]
    r = per[1:] / np.maximum(per[:-1], 1.0)
    ratio = np.maximum(r, 1 / np.maximum(r, 1e-12))
    jump = (ratio > _JUMP) & (np.abs(np.diff(per)) > _JUMP_WIDTHS * mid_w + 2 * resolution)
    fast = inside & (np.minimum(per[1:], per[:-1]) <= 2 * float(np.percentile(inrun, 10)))
    jumps = float(np.mean(jump[fast])) if fast.any() else 0.0
    zig = jump[1:] & jump[:-1] & ((r[1:] > 1) != (r[:-1] > 1)) & fast[1:] & fast[:-1]
    both = fast[1:] & fast[:-1]
    zigzags = float(np.mean(zig[both])) if both.any() else 0.0
    # a run of at least three periods ramps when it speeds up through its first periods (each
    # shorter than the one before, the first well above the third) or slows down likewise
    cut = np.flatnonzero(pause)
    first = np.r_[0, cut + 1]
    last = np.r_[cut - 1, len(per) - 1]
    long_run = last - first >= 2
    f, lst = first[long_run], last[long_run]
    tick = 2 * resolution
    up = (per[f] > _RAMP * per[f + 2] + tick) & (per[f + 1] > per[f + 2] + tick)
    up &= per[f] > per[f + 1] + tick
    down = (per[lst] > _RAMP * per[lst - 2] + tick) & (per[lst - 1] > per[lst - 2] + tick)
    down &= per[lst] > per[lst - 1] + tick
    ramps = int(np.count_nonzero(up | down))
    runs = int(np.count_nonzero(long_run))
    duty = mid_w / period if period > 0 else 0.0
    slowest = float(inrun.max() - tol) / period if period > 0 and len(inrun) else 1.0
    return Timing(
        len(per),
        period,
        steady,
        int(pause.sum()),
        ramps,
        runs,
        jumps,
        zigzags,
        duty,
        spread,
        max(slowest, 1.0),
    )
