"""What one channel's edges look like on their own: unchanging, a serial line, a pulse train (a
step train, a clock, PWM, periodic pulses, bursts at one rate, coded pulses: their rates are
told apart in :mod:`wavecheck.roles.periodic`), or other.

Everything here is vectorised over a channel's edge array (a few ``numpy`` passes, no Python loop
per edge), so a channel of ten million edges costs a few hundred milliseconds.

A **pulse train** (a STEP candidate): at least two complete pulses at one level whose widths are
nearly constant (the 10th..90th percentile within a factor 1.6, plus two samples of resolution),
and no longer than the typical time spent at the other level. Its gaps may vary (acceleration,
pauses); the pulse width does not.

A **serial line** (UART TX/RX, an ARM SWO/ITM trace): every interval shorter than a frame is a whole
multiple of one bit time *b* (the shortest interval), and *both* levels show several of those
multiples (a byte's bits give runs of 1·b, 2·b, 3·b … of either level), while a STEP line's pulse
level shows one width only. A UART idles at one level (high) between frames, so only that level
has long intervals, and runs of the other level stay within a frame (≤ 9·b). The grbl capture's TX
and RX have intervals of 17–104 samples at 2 MHz, all within ±1 sample of multiples of 17.36
(115,200 baud), with 1..6 bit runs at both levels: serial, never STEP.
"""

from __future__ import annotations

from fractions import Fraction
from typing import TYPE_CHECKING

import numpy as np

from wavecheck.capture.edges import Capture, Channel, EdgeArray
from wavecheck.record import record
from wavecheck.roles.periodic import Timing, timing
from wavecheck.roles.periodic import may_be_one_rate as may_be_rate
from wavecheck.units import format_frequency, format_time

if TYPE_CHECKING:
    import numpy.typing as npt

__all__ = [
    "BY_NAME_ONLY",
    "KIND_WORDS",
    "ChannelLook",
    "Pulses",
    "look_at",
    "may_be_one_rate",
    "pulses_of",
]

_WIDTH_SPREAD = 1.6  # p90/p10 of a pulse train's pulse widths stays below this
_FOLLOW_SPREAD = 1.15  # pulse widths varying this much (p90/p10) may follow the period …
_FOLLOW_R = 0.9  # … when their logarithms correlate this well with the period's
_SERIAL_FRAME_BITS = 10.5  # intervals up to this many bit times belong to a frame
_SERIAL_ON_GRID = 0.9  # share of in-frame intervals within a quarter bit of a whole multiple


@record(frozen=True)
class Pulses:
    """The complete pulses of a channel at its pulse level, in ticks.

    ``starts[i]`` and ``ends[i]`` bound pulse *i*; a pulse cut by the capture's start or end is
    left out (its width is unknown).
    """

    level: int
    starts: EdgeArray
    ends: EdgeArray

    @property
    def count(self) -> int:
        """Number of complete pulses."""
        return len(self.starts)

    @property
    def widths(self) -> EdgeArray:
        """Width of each pulse in ticks."""
        return self.ends - self.starts


def pulses_of(ch: Channel, level: int) -> Pulses:
    """The complete pulses of ``ch`` at ``level`` (an edge into ``level`` and the next edge)."""
    e = ch.edges
    # level after edge i is initial ^ ((i + 1) & 1); edges into `level` are those indices
    first = 0 if (ch.initial ^ 1) == level else 1
    starts = e[first::2]
    ends = e[first + 1 :: 2]
    return Pulses(level, starts[: len(ends)], ends)


#: What each kind of channel is called where the lines of a capture are summed up.
KIND_WORDS: dict[str, str] = {
    "constant": "unchanging",
    "serial": "serial line",
    "clock": "clock",
    "pwm": "PWM",
    "periodic": "periodic pulses",
    "bursts": "bursts at one rate",
    "coded": "coded pulses",
    "few": "a few pulses",
    "duty": "pulses at one duty",
    "pulses": "pulse train",
    "other": "other",
}
#: Kinds that are a STEP only when the channel's name says so (the waveform cannot tell).
BY_NAME_ONLY = frozenset({"periodic", "bursts", "coded", "few", "duty"})


@record(frozen=True)
class ChannelLook:
    """What a channel looks like on its own.

    Attributes:
        channel: the channel.
        kind: ``"constant"`` (no edge), ``"serial"``, ``"clock"`` (one period, about 50 % duty,
            no pause), ``"pwm"`` (one period, varying width), ``"periodic"`` (one period and
            width, no pause), ``"bursts"`` (runs at one rate without speeding up or slowing
            down), ``"coded"`` (periods that jump), ``"pulses"`` (a step train: fixed width, a
            rate that changes as a motor's), ``"other"`` (see :data:`KIND_WORDS`).
        pulses: for a pulse kind, its pulses at the pulse level; else the pulses at the level
            that is shorter on median (used to test whether it is a DIR with long "pulses").
        evidence: what was seen, in words.
        timing: the rate of the pulses, when there are two or more.
    """

    channel: Channel
    kind: str
    pulses: Pulses | None
    evidence: str
    timing: Timing | None = None

    @property
    def is_step_like(self) -> bool:
        """True for a step train (a STEP, UP or DOWN candidate on its waveform alone)."""
        return self.kind == "pulses"

    @property
    def step_by_name(self) -> bool:
        """True for pulses the waveform cannot tell from steps at one constant rate: a STEP only
        when named so."""
        return self.kind in BY_NAME_ONLY

    @property
    def clock_like(self) -> bool:
        """A clock, or bursts at one rate with about half the period at each level (a gated
        clock)."""
        t = self.timing
        return self.kind == "clock" or (
            self.kind == "bursts" and t is not None and 0.3 <= t.duty <= 0.7
        )

    @property
    def word(self) -> str:
        """The kind in a word or two (``"clock"``, ``"serial line"``)."""
        return KIND_WORDS[self.kind]


def _level_intervals(ch: Channel) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.int64]]:
    """Intervals between consecutive edges, split by the level they are at: (low, high)."""
    d = np.diff(ch.edges)
    after_first = ch.initial ^ 1  # level after edge 0; alternates from there
    lv0 = d[0::2] if after_first == 0 else d[1::2]
    lv1 = d[1::2] if after_first == 0 else d[0::2]
    return lv0, lv1


def _serial(ch: Channel, cap: Capture) -> str | None:
    """Evidence that ``ch`` is a serial line, or None."""
    if len(ch.edges) < 20:
        return None
    lows, highs = _level_intervals(ch)
    allv = np.concatenate([lows, highs])
    shortest = int(allv.min())
    near = allv[allv <= shortest + shortest // 2 + 1]
    b = float(np.median(near))
    if b <= 0:
        return None
    per_level: list[npt.NDArray[np.float64]] = []
    on_grid = 0
    in_frame = 0
    for v in (lows, highs):
        short = v[v <= _SERIAL_FRAME_BITS * b].astype(np.float64) / b
        per_level.append(short)
        on_grid += int(np.count_nonzero(np.abs(short - np.rint(short)) <= 0.25))
        in_frame += len(short)
    if in_frame < 20 or on_grid < _SERIAL_ON_GRID * in_frame:
        return None
    for short in per_level:
        if len(short) == 0:
            return None
        multiples = np.bincount(np.rint(short).astype(np.int64))
        if np.count_nonzero(multiples >= max(2, 0.05 * len(short))) < 2:
            return None  # one width only at this level: a pulse train, not bytes
    frame = allv[allv <= _SERIAL_FRAME_BITS * b].astype(np.float64)
    b = float(frame.sum() / np.rint(frame / b).sum())  # least-squares bit time
    bit = cap.timebase.seconds(1) * Fraction(b).limit_denominator(1000)
    long_low = int(np.count_nonzero(lows > _SERIAL_FRAME_BITS * b))
    long_high = int(np.count_nonzero(highs > _SERIAL_FRAME_BITS * b))
    idle = (
        "idle high"
        if long_high > 4 * long_low
        else "idle low"
        if long_low > 4 * long_high
        else "no idle level"
    )
    return (
        f"serial line: {on_grid:,} of {in_frame:,} in-frame intervals are whole multiples of "
        f"{format_time(bit)} (about {float(1 / bit):,.0f} baud), runs of several bit times "
        f"at both levels, {idle}: not a step signal"
    )


def _span(cap: Capture, lo: int, hi: int) -> str:
    a, b = format_time(cap.timebase.seconds(lo)), format_time(cap.timebase.seconds(hi))
    return a if lo == hi else f"{a}–{b}"


def _rate_text(cap: Capture, t: Timing) -> str:
    period = cap.timebase.seconds(1) * Fraction(t.period).limit_denominator(1000)
    return f"{format_time(period)} ({format_frequency(1 / period, 4)})" if period else "0 s"


def _shape_evidence(cap: Capture, kind: str, p: Pulses, t: Timing) -> str:
    """Why a pulse train of this ``kind`` is not taken as steps on its waveform alone."""
    rate = _rate_text(cap, t)
    pct = f"{t.steady:.0%}"
    if kind == "clock":
        return (
            f"clock: {p.count:,} pulses, every period {rate}, {t.duty:.0%} duty, no pause: "
            "a free-running clock, not a step signal"
        )
    if kind == "pwm":
        return (
            f"PWM: one period {rate} with pulse widths varying by {t.width_spread:.0%}: "
            "a step train keeps its pulse width, not its period"
        )
    if kind == "periodic":
        slower = (
            f", the longest {t.slowest:.2f}x that (it slows down now and then)"
            if t.slowest > 1.1
            else ""
        )
        return (
            f"periodic pulses: {p.count:,} pulses, {pct} of periods {rate}{slower}, "
            f"{t.duty:.0%} duty, no pause: a sync, frame or PWM line, or steps at one constant "
            "speed (the waveform cannot tell; a STEP only when named so)"
        )
    if kind == "few":
        return (
            f"a few pulses: {p.count} pulses, too few to see a motor's rate in (a reset, an "
            "interrupt or a handshake line pulses so too; a STEP only when named so)"
        )
    if kind == "bursts":
        return (
            f"bursts at one rate: {p.count:,} pulses in {t.pauses + 1:,} runs, {pct} of periods "
            f"{rate}, {t.duty:.0%} duty, no run speeds up or slows down: a gated clock, or steps "
            "without acceleration (a STEP only when named so)"
        )
    return (
        f"coded pulses: {p.count:,} pulses, {t.coded_why()}: no motor's rate changes so fast "
        "(a STEP only when named so)"
    )


def _follows_period(p: Pulses) -> str | None:
    """Evidence that the pulse widths follow the period (one duty at a changing rate: a
    tachometer, a Hall sensor, an encoder, a STEP toggled once a step), or None. A step
    generator's pulses keep their width whatever the rate."""
    if p.count < 8:
        return None
    w = p.widths[:-1].astype(np.float64)
    per = np.diff(p.starts).astype(np.float64)
    keep = per < 3 * np.median(per)  # pauses say nothing of the duty
    w, per = w[keep], per[keep]
    if len(w) < 8 or np.min(w) <= 0:
        return None
    lw, lp = np.log(w), np.log(per)
    lo, hi = np.percentile(w, [10, 90])
    if hi < _FOLLOW_SPREAD * lo or np.std(lp) == 0 or np.std(lw) == 0:
        return None  # widths nearly constant: what a step generator makes
    r = float(np.corrcoef(lw, lp)[0, 1])
    slope = float(np.polyfit(lp, lw, 1)[0])
    if r < _FOLLOW_R or not 0.5 <= slope <= 1.5:
        return None
    duty = float(np.median(w / per))
    return (
        f"pulses at one duty: the widths ({hi / lo:.2f}x from p10 to p90) follow the period "
        f"(correlation {r:.2f}), duty about {duty:.0%}: a tachometer, a Hall sensor or an "
        "encoder, or a STEP toggled once a step (TMC dedge); a step generator keeps its pulse "
        "width (a STEP only when named so)"
    )


def _pulse_level(ch: Channel, lows: EdgeArray, highs: EdgeArray) -> int:
    """The level of ``ch``'s pulses: the one it spends less time at on median."""
    med0, med1 = float(np.median(lows)), float(np.median(highs))
    if med0 != med1:
        return 0 if med0 < med1 else 1
    return ch.initial ^ 1


def may_be_one_rate(ch: Channel, cap: Capture) -> bool:
    """False when :func:`look_at` surely finds ``ch`` none of the kinds at one rate (a clock,
    PWM, periodic pulses, bursts: every :attr:`ChannelLook.clock_like` look), from the first steps of its look only: a line whose whole look
    is not needed (its name is judged, not its shape) costs a fraction of one."""
    if len(ch.edges) == 0:
        return False
    lows, highs = _level_intervals(ch)
    if len(lows) == 0 or len(highs) == 0:
        return False
    p = pulses_of(ch, _pulse_level(ch, lows, highs))
    return may_be_rate(p.starts, max(cap.resolution_ticks, 0))


def look_at(ch: Channel, cap: Capture) -> ChannelLook:
    """Classify one channel from its own edges (see the module docstring for the rules)."""
    n = len(ch.edges)
    if n == 0:
        lvl = "high" if ch.initial else "low"
        return ChannelLook(ch, "constant", None, f"never changes ({lvl} throughout)")
    serial = _serial(ch, cap)
    if serial is not None:
        return ChannelLook(ch, "serial", None, serial)
    lows, highs = _level_intervals(ch)
    if len(lows) == 0 or len(highs) == 0:
        return ChannelLook(ch, "other", None, f"changes {n} time{'s' if n != 1 else ''}")
    level = _pulse_level(ch, lows, highs)
    p = pulses_of(ch, level)
    gaps = lows if level == 1 else highs
    res = max(cap.resolution_ticks, 0)
    t = timing(p.starts, p.widths, res) if p.count >= 2 else None
    if p.count >= 2:
        w = p.widths
        p10, p90 = np.percentile(w, [10, 90])
        steady = p90 <= _WIDTH_SPREAD * p10 + 2 * res
        short = float(np.median(w)) <= float(np.median(gaps)) if len(gaps) else True
        if t is not None and steady:
            kind = t.shape(res)
            if kind != "steps":
                return ChannelLook(ch, kind, p, _shape_evidence(cap, kind, p, t), t)
        follows = _follows_period(p) if steady and short else None
        if follows is not None:
            return ChannelLook(ch, "duty", p, follows, t)
        if steady and short:
            periods = np.diff(p.starts)
            rate = ""
            if len(periods):
                fastest = int(periods.min())
                rate = f", rate up to {format_frequency(1 / cap.timebase.seconds(fastest), 3)}"
            gap_text = f", gaps {_span(cap, int(gaps.min()), int(gaps.max()))}" if len(gaps) else ""
            return ChannelLook(
                ch,
                "pulses",
                p,
                f"pulse train: {p.count:,} {'high' if level else 'low'} pulses of "
                f"{_span(cap, int(w.min()), int(w.max()))}{gap_text}{rate}",
                t,
            )
        if t is not None and t.one_rate:  # one period, widths that vary
            kind = "pwm" if t.pauses == 0 else "bursts"
            return ChannelLook(ch, kind, p, _shape_evidence(cap, kind, p, t), t)
    why = f"changes {n:,} time{'s' if n != 1 else ''}"
    if p.count >= 2:
        why += ", not a pulse train (its pulse widths vary, or are longer than its gaps)"
    return ChannelLook(ch, "other", p, why, t)
