"""Commands for the stepgen's position-cmd / velocity-cmd pin, one value per servo update.

Update u happens at t = u·S (S = the HAL-rounded servo period) and sees the command at t.

* ``--position X`` / ``--velocity V``: a constant (position units; units/s).
* ``--command FILE.csv``: rows ``time_s,value``; each value holds until the next row's time;
  before the first row the pin is 0 (LinuxCNC's default). A non-numeric first line is a header.
* ``--move "SPEC"``: trapezoid moves from position 0, items separated by commas:

  - ``X``          move to X (position units) at ``--move-vel`` / ``--move-accel``;
  - ``X@V``        move to X with peak velocity V (units/s) for this move only;
  - ``pause T``    stay still for T, with its unit (``pause 20ms``).

  e.g. ``--move "0.04, pause 10ms, 0"`` is a move forward and back: a reversal. In position mode
  the pin gets the sampled position profile; in velocity mode its exact velocity.
* ``--motion worst`` (the default with ``--latency worst:J:RULE`` and no other motion):
  :func:`worst_motion`, velocity commands that make every interval make-pulses can produce
  with the channel's parameters at its fewest base periods — runs at the full step rate (the
  pulse, the gap and the step period at steplen, stepspace and steplen + stepspace periods) and
  reversals requested at the earliest moment after a pulse, so DIR changes dirhold periods after
  the pulse ends and the next step comes dirsetup periods after that (reference §2.3: the DIR
  hold, DIR setup, the gap dirhold + dirsetup and the step period steplen + dirhold + dirsetup
  across a reversal). It is designed by running the reference model itself, closed loop.

The default run length with ``--move`` is the profile's length plus 50 ms to settle; with
``--motion worst`` the designed commands' length.
"""

from __future__ import annotations

import copy
import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from stepgen.reference import PICKOFF, Component, StepgenConfig, make_pulses_channel
from wavecheck.errors import ConfigError, UnitError
from wavecheck.units import parse_option

__all__ = ["Motion", "Segment", "parse_command_csv", "parse_moves", "worst_motion"]

SETTLE_S = 0.05


@dataclass(frozen=True)
class Segment:
    """One trapezoid move (or a pause when ``dx == 0``), in position units, units/s, units/s², s."""

    start: float
    dx: float
    vmax: float
    accel: float
    duration: float

    def position(self, t: np.ndarray) -> np.ndarray:
        """Position at times ``t`` since the segment's start (clipped to [0, duration])."""
        if self.dx == 0:
            return np.full_like(t, self.start)
        s, a = math.copysign(1.0, self.dx), self.accel
        dist = abs(self.dx)
        ta = min(self.vmax / a, math.sqrt(dist / a))
        peak = a * ta
        tc = max(self.duration - 2 * ta, 0.0)
        tt = np.clip(t, 0.0, self.duration)
        d1 = 0.5 * a * np.minimum(tt, ta) ** 2
        d2 = peak * np.clip(tt - ta, 0.0, tc)
        td = np.clip(tt - ta - tc, 0.0, ta)
        d3 = peak * td - 0.5 * a * td**2
        return self.start + s * np.minimum(d1 + d2 + d3, dist)

    def velocity(self, t: np.ndarray) -> np.ndarray:
        """Velocity at times ``t`` since the segment's start (0 outside it)."""
        if self.dx == 0:
            return np.zeros_like(t)
        s, a = math.copysign(1.0, self.dx), self.accel
        ta = min(self.vmax / a, math.sqrt(abs(self.dx) / a))
        peak = a * ta
        v = np.minimum(np.minimum(a * t, peak), a * (self.duration - t))
        v = np.where((t < 0) | (t > self.duration), 0.0, np.maximum(v, 0.0))
        return s * v


def _trapezoid(start: float, target: float, vmax: float, accel: float) -> Segment:
    dist = abs(target - start)
    if dist == 0:
        return Segment(start, 0.0, vmax, accel, 0.0)
    if dist <= vmax * vmax / accel:
        duration = 2 * math.sqrt(dist / accel)
    else:
        duration = 2 * vmax / accel + (dist - vmax * vmax / accel) / vmax
    return Segment(start, target - start, vmax, accel, duration)


def parse_moves(spec: str, vel: float, accel: float) -> list[Segment]:
    """Parse a ``--move`` spec into segments (see the module docstring)."""
    segments: list[Segment] = []
    pos = 0.0
    for raw in spec.split(","):
        item = raw.strip()
        if not item:
            continue
        word = item.split(None, 1)
        if word[0].lower() in ("pause", "wait", "dwell"):
            if len(word) != 2:
                raise ConfigError(f"--move item {item!r}: write 'pause 20ms'")
            try:
                secs = float(parse_option(word[1], "pause", "time"))
            except UnitError as err:
                raise ConfigError(f"--move: {err}") from None
            if secs < 0:
                raise ConfigError(f"--move item {item!r}: a pause must not be negative")
            segments.append(Segment(pos, 0.0, vel, accel, secs))
            continue
        target_text, _, v_text = item.partition("@")
        try:
            target = float(target_text)
            v = float(v_text) if v_text else vel
        except ValueError:
            raise ConfigError(
                f"--move item {item!r} is not X, X@V or 'pause T' (e.g. --move '0.04, pause 10ms, 0')"
            ) from None
        if not (v > 0 and accel > 0 and math.isfinite(target)):
            raise ConfigError(
                f"--move item {item!r} needs a velocity and an acceleration > 0 "
                f"(have {v} units/s, {accel} units/s²; give --move-vel/--move-accel or --maxvel/--maxaccel)"
            )
        segments.append(_trapezoid(pos, target, v, accel))
        pos = target
    if not segments:
        raise ConfigError(f"--move {spec!r} has no moves (e.g. --move '0.04, pause 10ms, 0')")
    return segments


def parse_command_csv(path: str | Path) -> tuple[np.ndarray, np.ndarray]:
    """Read ``time_s,value`` rows; returns (times, values) sorted by time.

    A file of plain ``number,number`` lines (after an optional header) is parsed at once
    (:func:`_parse_plain_lines`); anything else, and every error, goes through the row-by-row
    reader :func:`_parse_rows`, which gives the same result and names the line of an error."""
    try:
        with open(path, "rb") as fh:
            data = fh.read()
    except OSError as err:
        raise ConfigError(f"{path}: cannot read command file ({err.strerror})") from None
    fast = _parse_plain_lines(data)
    return fast if fast is not None else _parse_rows(path)


_CSV_PIECE = 1 << 16  #: characters of the command CSV split and converted at a time


def _parse_plain_lines(data: bytes) -> tuple[np.ndarray, np.ndarray] | None:
    """The rows of ``data`` when every line is two comma-separated fields without quotes (the
    first may be a header) that give finite numbers with times in order, else None. Fields
    are converted by ``float`` as in :func:`_parse_rows`, so the numbers are the same; that
    each line has one comma is checked on the bytes (the separators alternate ``,`` and a
    newline), not line by line."""
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError:
        return None
    if '"' in text or "#" in text:
        return None
    if "\r" in text:
        text = text.replace("\r\n", "\n")
        if "\r" in text:
            return None
    first, _, rest = text.partition("\n")
    head = first.split(",")
    try:
        float(head[0]), float(head[1])
        body = text
    except (ValueError, IndexError):
        if not "".join(head).strip():
            return None  # a blank line: the row reader skips it
        body = rest  # the header
    if not body:
        return None
    if not body.endswith("\n"):
        body += "\n"
    # a piece of whole lines at a time: its field strings are freed before the next piece
    # is split, so their memory is reused instead of touched anew (~6 MB for 20 k lines)
    parts = []
    start = 0
    while start < len(body):
        stop = body.find("\n", start + _CSV_PIECE) + 1 or len(body)
        piece = body[start:stop]
        raw = np.frombuffer(piece.encode("utf-8"), dtype=np.uint8)
        seps = raw[(raw == ord(",")) | (raw == ord("\n"))]
        if len(seps) % 2 or (seps[0::2] != ord(",")).any() or (seps[1::2] != ord("\n")).any():
            return None
        fields = piece[:-1].replace("\n", ",").split(",")
        try:
            parts.append(np.fromiter(map(float, fields), dtype=float, count=len(fields)))
        except ValueError:
            return None
        start = stop
    numbers = np.concatenate(parts)
    times, values = numbers[0::2], numbers[1::2]
    if not np.isfinite(numbers).all() or (times[1:] < times[:-1]).any():
        return None
    return times, values


def _parse_rows(path: str | Path) -> tuple[np.ndarray, np.ndarray]:
    """:func:`parse_command_csv` row by row with the ``csv`` module (the plain reader)."""
    import csv  # only for files the whole-file path does not take

    times: list[float] = []
    values: list[float] = []
    try:
        with open(path, newline="", encoding="utf-8") as fh:
            for lineno, row in enumerate(csv.reader(fh), 1):
                if not row or not "".join(row).strip() or row[0].lstrip().startswith("#"):
                    continue
                try:
                    t, v = float(row[0]), float(row[1])
                except (ValueError, IndexError):
                    if lineno == 1:
                        continue  # header
                    raise ConfigError(
                        f"{path}: line {lineno}: expected time_s,value, got {','.join(row)!r}"
                    ) from None
                if not (math.isfinite(t) and math.isfinite(v)):
                    raise ConfigError(f"{path}: line {lineno}: {','.join(row)!r} is not finite")
                if times and t < times[-1]:
                    raise ConfigError(
                        f"{path}: line {lineno}: time {t} s goes backwards (rows must be in time order)"
                    )
                times.append(t)
                values.append(v)
    except OSError as err:
        raise ConfigError(f"{path}: cannot read command file ({err.strerror})") from None
    if not times:
        raise ConfigError(f"{path}: no time_s,value rows")
    return np.array(times), np.array(values)


@dataclass
class Motion:
    """What the command pin does; :meth:`commands` samples it at the servo updates."""

    kind: str = "position"  # position | velocity | csv | moves | worst
    value: float = 0.0
    csv_times: np.ndarray = field(default_factory=lambda: np.zeros(0))
    csv_values: np.ndarray = field(default_factory=lambda: np.zeros(0))
    segments: list[Segment] = field(default_factory=list)
    updates: np.ndarray = field(default_factory=lambda: np.zeros(0))
    """``worst``: the velocity-cmd of each servo update (units/s); the last is held."""
    servo_ns: int = 0
    """``worst``: the servo period the commands were designed for (ns)."""
    notes: list[str] = field(default_factory=list)
    """What the motion made (``worst``), for the summary."""

    @property
    def natural_duration_s(self) -> float | None:
        """The profile's own length plus settling (moves), the last CSV row (csv), the designed
        updates (worst), else None."""
        if self.kind == "moves":
            return sum(s.duration for s in self.segments) + SETTLE_S
        if self.kind == "csv":
            return float(self.csv_times[-1]) + SETTLE_S
        if self.kind == "worst":
            return len(self.updates) * self.servo_ns * 1e-9
        return None

    def commands(self, n_updates: int, servo_ns: int, mode: str) -> np.ndarray:
        """Pin values for updates 0..n_updates−1 (update u at u·servo_ns)."""
        t = np.arange(n_updates, dtype=float) * (servo_ns * 1e-9)
        if self.kind in ("position", "velocity"):
            return np.full(n_updates, self.value)
        if self.kind == "worst":
            if mode != "velocity" or servo_ns != self.servo_ns:
                raise ConfigError(
                    "the worst-case motion was designed for velocity mode at a servo period of "
                    f"{self.servo_ns} ns (run with that configuration)"
                )
            idx = np.minimum(np.arange(n_updates), len(self.updates) - 1)
            return self.updates[idx]
        if self.kind == "csv":
            idx = np.searchsorted(self.csv_times, t, side="right") - 1
            return np.where(idx >= 0, self.csv_values[np.maximum(idx, 0)], 0.0)
        out = np.zeros(n_updates)
        start = 0.0
        last = 0.0
        for seg in self.segments:
            inside = (t >= start) & (t < start + seg.duration)
            local = t[inside] - start
            out[inside] = seg.position(local) if mode == "position" else seg.velocity(local)
            start += seg.duration
            last = seg.start + seg.dx
        if mode == "position":
            out[t >= start] = last
        return out


# ----------------------------------------------------------------------------------------------
# The worst-case motion

#: Reversals :func:`worst_motion` requests by default (two each way).
WORST_REVERSALS = 4
#: Most reversals designed for a long run (``n_updates``); full speed is held after them.
WORST_MAX_REVERSALS = 64
#: Steps made at the full rate before slowing down for each reversal.
WORST_FULL_RATE_STEPS = 4
#: Servo updates :func:`worst_motion` stands still first: the first update-freq may use the
#: start-up constants (P = 50 µs, reference §3), which are no interval of the configuration.
WORST_SETTLE_UPDATES = 2
#: Base periods :func:`worst_motion` waits, per phase, for the state it needs before giving up.
WORST_WAIT_PERIODS = 2_000_000


class _Enough(Exception):
    """The requested number of servo updates has been designed."""


class _Run:
    """The reference model driven one servo period at a time (the designer's view of it)."""

    def __init__(self, config: StepgenConfig) -> None:
        self.comp = Component([config])
        self.ch = self.comp.channels[0]
        self.base = config.base_period_ns
        self.servo = config.servo_ns
        self.n = config.servo_multiple
        self.k = 0  #: the next make-pulses invocation
        self.last_step = -1
        self.last_dir = 0
        if config.thread_order == "pulses-first":
            self.pulse()  # invocation 0 runs before the first update-freq

    def pulse(self) -> bool:
        """One make-pulses invocation; True if it stepped."""
        self.comp.periodns = self.base
        stepped = make_pulses_channel(self.ch, self.base)
        if stepped:
            self.last_step = self.k
            self.last_dir = 1 if self.ch.addval > 0 else -1
        self.k += 1
        return stepped

    def update(self, cmd: float) -> None:
        """update-freq with velocity-cmd ``cmd``."""
        self.ch.vel_cmd = cmd
        self.comp.update_freq(self.servo)

    def periods(self) -> tuple[int, int, int, int]:
        """steplen, stepspace, dirhold (dirdelay), dirsetup as rounded by update-freq, in periods."""
        ch = self.ch
        return (
            ch.step_len // self.base,
            ch.step_space // self.base,
            ch.dir_hold_dly // self.base,
            ch.dir_setup // self.base,
        )

    def earliest_reversal(self, cmd: float, sign: int) -> bool:
        """Would requesting ``cmd`` now reverse at the earliest moment after the last step?

        That is (reference §2.3): the direction changes L+H periods after that step and the
        next step, in the new direction, comes S periods later. Run on a copy.
        """
        if self.last_step < 0 or self.last_dir != sign or self.ch.timer2 == 0:
            return False
        steplen, _, hold, setup = self.periods()
        want_dir = self.last_step + steplen + hold
        want_step = want_dir + setup
        trial = copy.deepcopy(self)
        dir_at: int | None = None
        while trial.k <= want_step:
            trial.update(cmd)
            for _ in range(trial.n):
                k = trial.k
                stepped = trial.pulse()
                if dir_at is None and trial.ch.curr_dir == -sign:
                    dir_at = k
                if stepped:
                    return dir_at == want_dir and k == want_step and trial.last_dir == -sign
        return False

    def aim(self, cmd_for: Callable[[int], float], flip: float, sign: int) -> float | None:
        """A slow command for this servo period that puts a step in its last L+H periods, so
        that reversing at the next update is the earliest reversal (checked on copies); None if
        no addval below deltalim does."""
        ch = self.ch
        if ch.addval * sign <= 0 or ch.deltalim <= 1 or abs(ch.addval) >= ch.deltalim:
            return None
        steplen, _, hold, _ = self.periods()
        boundary = ((ch.accum >> PICKOFF) + (1 if sign > 0 else 0)) << PICKOFF
        rest = boundary - ch.accum if sign > 0 else ch.accum - boundary + 1
        for j in range(min(steplen + hold, self.n)):
            x = -(-rest // (self.n - j))  # the step falls in period n − j after the update
            if not 1 <= x < ch.deltalim:
                continue
            trial = copy.deepcopy(self)
            trial.update(cmd_for(sign * x))
            for _ in range(trial.n):
                trial.pulse()
            if trial.earliest_reversal(flip, sign):
                return cmd_for(sign * x)
        return None


def worst_motion(
    config: StepgenConfig, *, n_updates: int | None = None, reversals: int = WORST_REVERSALS
) -> Motion:
    """Velocity commands that make every interval make-pulses can produce at its fewest periods.

    After ``WORST_SETTLE_UPDATES`` servo periods standing still, repeatedly: full speed (the
    velocity command above any rate, clamped by update-freq to
    stepgen's maximum) until ``WORST_FULL_RATE_STEPS`` steps were made at the steady full rate;
    then a slow speed from which one base period of ramp reverses ``addval``; then, at the
    first servo update where the reference model (run on a copy) shows that reversing now makes
    the direction change dirhold periods after the last pulse ends and the next step dirsetup
    periods after that, full speed the other way. The channel runs in velocity mode (make-pulses,
    which makes every interval, does not depend on ctrl_type).

    Args:
        config: the channel and threads (its ``mode`` is taken as velocity).
        n_updates: the run's servo updates: reversals go on until then, at most
            ``WORST_MAX_REVERSALS`` (full speed is held after the last). Default: ``reversals``
            reversals and a last full-speed run.
        reversals: reversals to request when ``n_updates`` is None.
    Returns:
        a ``Motion(kind="worst")`` whose ``notes`` say what it made.
    """
    cfg = replace(config, mode="velocity")
    cfg.validate()
    run = _Run(cfg)
    big = 2e9 / cfg.position_scale  # steps/s above any rate stepgen allows (1 step per ns)
    cmds: list[float] = []
    misses: list[str] = []

    def servo(cmd: float) -> None:
        if n_updates is not None and len(cmds) >= n_updates:
            raise _Enough
        cmds.append(cmd)
        run.update(cmd)
        for _ in range(run.n):
            run.pulse()

    def full_rate(sign: int) -> None:
        steady = 0
        start = run.k
        while True:
            before = run.ch.target_addval
            servo(sign * big)
            ch = run.ch
            steplen, space, _, _ = run.periods()
            if ch.addval == ch.target_addval == before:
                steady += run.n
                if steady >= WORST_FULL_RATE_STEPS * (steplen + space):
                    return
            if run.k - start > WORST_WAIT_PERIODS:
                misses.append(f"full speed not steady after {WORST_WAIT_PERIODS} periods")
                return

    def cmd_for(addval: int) -> float:
        """The velocity-cmd whose target addval is ``addval`` (trunc of freq·freqscale)."""
        return math.copysign(abs(addval) + 0.5, addval) / run.comp.freqscale / cfg.position_scale

    def reverse(sign: int) -> bool:
        # slow enough that one period of ramp (deltalim) reverses addval
        d, full = run.ch.deltalim, abs(run.ch.target_addval)
        slow = cmd_for(sign * (max(1, min(full, d - 1)) if d > 0 else 1))
        flip = -sign * big
        start = run.k
        while run.k - start <= WORST_WAIT_PERIODS:
            if run.earliest_reversal(flip, sign):
                servo(flip)
                return True
            aimed = run.aim(cmd_for, flip, sign)
            servo(slow if aimed is None else aimed)
        servo(flip)
        return False

    done = late = 0
    sign = 1
    try:
        for _ in range(WORST_SETTLE_UPDATES):
            servo(0.0)  # standing still while update-freq leaves its start-up constants (§3)
        while True:
            full_rate(sign)
            if done + late >= (reversals if n_updates is None else WORST_MAX_REVERSALS):
                break  # then full speed is held to the end of the run
            if reverse(sign):
                done += 1
            else:
                late += 1
            sign = -sign
    except _Enough:
        pass
    steplen, space, hold, setup = run.periods()
    notes = [
        f"worst-case motion (velocity-cmd, {len(cmds)} servo updates): runs of "
        f">= {WORST_FULL_RATE_STEPS} steps at the full rate ({steplen + space} periods per step at "
        f"most) and {done} reversal(s) requested at the earliest moment after a pulse (direction "
        f"{hold} periods after the pulse ends, the next step {setup} periods later)"
    ]
    if late:
        notes.append(
            f"worst-case motion: {late} reversal(s) could not be requested at the earliest moment "
            f"within {WORST_WAIT_PERIODS} base periods (maxaccel too low for a one-period reversal?): "
            "the intervals across them are longer than their minimum"
        )
    notes += [f"worst-case motion: {m}" for m in misses]
    return Motion(
        kind="worst", updates=np.array(cmds, dtype=float), servo_ns=cfg.servo_ns, notes=notes
    )
