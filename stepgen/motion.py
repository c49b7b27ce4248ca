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

The default run length with ``--move`` is the profile's length plus 50 ms to settle.
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from wavecheck.errors import ConfigError, UnitError
from wavecheck.units import parse_option

__all__ = ["Motion", "Segment", "parse_command_csv", "parse_moves"]

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
    """Read ``time_s,value`` rows; returns (times, values) sorted by time."""
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

    kind: str = "position"  # position | velocity | csv | moves
    value: float = 0.0
    csv_times: np.ndarray = field(default_factory=lambda: np.zeros(0))
    csv_values: np.ndarray = field(default_factory=lambda: np.zeros(0))
    segments: list[Segment] = field(default_factory=list)

    @property
    def natural_duration_s(self) -> float | None:
        """The profile's own length plus settling (moves), the last CSV row (csv), else None."""
        if self.kind == "moves":
            return sum(s.duration for s in self.segments) + SETTLE_S
        if self.kind == "csv":
            return float(self.csv_times[-1]) + SETTLE_S
        return None

    def commands(self, n_updates: int, servo_ns: int, mode: str) -> np.ndarray:
        """Pin values for updates 0..n_updates−1 (update u at u·servo_ns)."""
        t = np.arange(n_updates, dtype=float) * (servo_ns * 1e-9)
        if self.kind in ("position", "velocity"):
            return np.full(n_updates, self.value)
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
