"""Commanded motion against the position decoded from a capture: the following error.

The *command* is a trajectory: a CSV of time and position, LinuxCNC ``halsampler`` output of a
position or count pin, or a STEP/DIR (up/down) train in the capture itself (a servo drive's
step input). The *feedback* is the position decoded from the capture (:mod:`wavecheck.steps.decode`):
a stepper's STEP/DIR, or a quadrature encoder's A/B (step type 2).

Positions are in feedback counts (steps or encoder counts); a command in position units is
multiplied by ``scale`` (counts per unit). A command file is linear between its rows (a sampled
trajectory); a step train holds each position until its next step. The feedback holds each
position from the decoded step's tick on.

The error ``e(t) = command(t) − feedback(t)`` is piecewise linear between the breakpoints (the
command's rows, the feedback's steps), so its maximum over time is taken exactly at them (both
limits at a step) and its RMS is the exact integral over the window where both exist. Times
are exact integers on one grid (1/D ns, D the least common denominator of the capture's tick,
the command's time unit and the delay in ns), so "at a step" and "at a sample" are exact.

CSV (comma-separated, ``#`` comments): a header row names the columns; the time column is
``time_s``, ``time_ms``, ``time_us`` or ``time_ns`` (its unit in its name: a bare time is not
accepted; values are taken to the nearest nanosecond); the position column is the one named by ``column`` (default: the first column after
the time column). A position column named ``steps``, ``counts`` or ending in ``_steps``/
``_counts`` is in counts, any other in position units (``unit`` overrides).

halsampler (``sample_period`` given): one line per sample, whitespace-separated values in the
order of sampler's ``cfg`` string; with ``tagged`` (``halsampler -t``) the first value is the
sample number, so a lost sample leaves a gap rather than shifting the time axis. Sample n is at
``n · sample_period``. ``column`` is 1-based among the data values (default 1); a float pin
(``position-fb``, ``joint.N.motor-pos-cmd``) is in units, an s32 count pin (``counts``) in
counts: say which with ``unit`` (default: units when any value has a fraction, else counts).
"""

from __future__ import annotations

import csv
import math
import os
import re
import stat
from dataclasses import dataclass, field
from fractions import Fraction
from pathlib import Path
from typing import Literal

import numpy as np
import numpy.typing as npt

from wavecheck.errors import UsageError
from wavecheck.steps.decode import StepEvents
from wavecheck.units import check_finite

__all__ = [
    "Command",
    "FollowReport",
    "command_from_steps",
    "follow",
    "positions_at",
    "read_command",
]

Floats = npt.NDArray[np.float64]
Ints = npt.NDArray[np.int64]
Unit = Literal["counts", "units"]

_TIME_COLUMN = re.compile(r"^\s*(?:time|t)[ _]?\(?(s|ms|us|µs|ns)\)?\s*$", re.IGNORECASE)
_TIME_NS = {"s": 1e9, "ms": 1e6, "us": 1e3, "µs": 1e3, "ns": 1.0}
#: Most rows read from a command file (bounded memory on hostile input).
MAX_ROWS = 50_000_000
#: Longest line of a command file (a CSV row or a halsampler sample is tens of bytes).
MAX_LINE = 1 << 16


@dataclass(frozen=True)
class Command:
    """A commanded trajectory.

    Attributes:
        times: sample times, integers of ``unit_ns`` each, non-decreasing.
        position: the commanded position at each time, in ``unit``.
        unit: ``counts`` (steps or encoder counts) or ``units`` (position units).
        source: what it was read from, for the report.
        hold: True for a step train (each position holds until the next step), False for a
            sampled trajectory (linear between samples).
    """

    times: Ints
    position: Floats
    unit: Unit
    source: str
    hold: bool = False
    unit_ns: Fraction = Fraction(1)


def _counts_name(name: str) -> bool:
    key = name.strip().lower()
    return key in ("steps", "counts", "count") or key.endswith(("_steps", "_counts", "-counts"))


def _bad(path: Path, lineno: int, msg: str) -> UsageError:
    return UsageError(f"{path}: line {lineno}: {msg}")


def _read_csv(
    path: Path, lines: list[tuple[int, str]], column: str | None
) -> tuple[Ints, Floats, str]:
    header_no, header_line = lines[0]
    header = [h.strip() for h in next(csv.reader([header_line]))]
    t_col = next((i for i, h in enumerate(header) if _TIME_COLUMN.match(h)), None)
    if t_col is None:
        raise _bad(
            path,
            header_no,
            f"no time column with its unit in the header {header_line.strip()[:60]!r} "
            "(name it time_s, time_ms, time_us or time_ns, e.g. 'time_s,position'; "
            "halsampler output needs --sample-period)",
        )
    if column is None:
        p_col = t_col + 1
        if p_col >= len(header):
            raise _bad(path, header_no, "no position column after the time column")
    elif column in header:
        p_col = header.index(column)
    elif column.isdigit() and 1 <= int(column) <= len(header):
        p_col = int(column) - 1
    else:
        raise UsageError(f"{path}: no column {column!r} (columns: {', '.join(header)})")
    scale = _TIME_NS[_TIME_COLUMN.match(header[t_col]).group(1).lower()]  # type: ignore[union-attr]
    times: list[float] = []
    values: list[float] = []
    for lineno, text in lines[1:]:
        row = next(csv.reader([text]))
        try:
            t, v = float(row[t_col]), float(row[p_col])
        except (ValueError, IndexError):
            raise _bad(
                path,
                lineno,
                f"expected numbers in columns {header[t_col]} and "
                f"{header[p_col]}, got {text.strip()[:60]!r}",
            ) from None
        times.append(t * scale)
        values.append(v)
    t_ns = np.array(times, dtype=np.float64)
    check_finite(t_ns, lambda i: f"{path}: line {lines[i + 1][0]}: time in ns", limit=2**62)
    return np.rint(t_ns).astype(np.int64), np.array(values), header[p_col]


def _read_halsampler(
    path: Path, lines: list[tuple[int, str]], column: str | None, tagged: bool
) -> tuple[Ints, Floats, bool]:
    col = 1 if column is None else int(column) if column.isdigit() else 0
    if col < 1:
        raise UsageError(
            f"{path}: halsampler column {column!r}: give its number (1 = the first value)"
        )
    times: list[float] = []
    values: list[float] = []
    fraction = False
    for n, (lineno, text) in enumerate(lines):
        parts = text.split()
        first = 1 if tagged else 0
        try:
            sample = int(parts[0]) if tagged else n
            raw = parts[first + col - 1]
            v = float(raw)
        except (ValueError, IndexError):
            raise _bad(
                path,
                lineno,
                f"expected {'a sample number and ' if tagged else ''}"
                f"at least {col} value(s), got {text.strip()[:60]!r}",
            ) from None
        fraction = fraction or not raw.lstrip("+-").isdigit()
        times.append(sample)
        values.append(v)
    if times and max(abs(min(times)), abs(max(times))) >= 2**62:
        raise UsageError(f"{path}: a sample number is too large")
    return np.array(times, dtype=np.int64), np.array(values), fraction


def _command_lines(p: Path) -> list[tuple[int, str]]:
    """The non-blank, non-comment lines of a command file with their numbers (a UTF-8 byte
    order mark dropped), read with bounds: a device or folder is refused before reading, a line
    longer than :data:`MAX_LINE` or more than :data:`MAX_ROWS` rows end the reading."""
    try:
        mode = os.stat(p).st_mode
    except OSError as err:
        raise UsageError(f"{p}: cannot read the command file ({err.strerror})") from None
    if stat.S_ISDIR(mode) or stat.S_ISCHR(mode) or stat.S_ISBLK(mode):
        what = "a folder" if stat.S_ISDIR(mode) else "a device"
        raise UsageError(f"{p}: is {what}, not a command file (a CSV or halsampler output)")
    lines: list[tuple[int, str]] = []
    try:
        with open(p, encoding="utf-8-sig", errors="replace") as fh:
            lineno = 0
            while text := fh.readline(MAX_LINE + 1):
                lineno += 1
                if len(text) > MAX_LINE:
                    raise _bad(p, lineno, f"longer than {MAX_LINE} characters: not a command file")
                stripped = text.strip()
                if not stripped or stripped.startswith("#"):
                    continue
                lines.append((lineno, text))
                if len(lines) > MAX_ROWS + 1:
                    raise UsageError(f"{p}: more than {MAX_ROWS} rows")
    except OSError as err:
        raise UsageError(f"{p}: cannot read the command file ({err.strerror})") from None
    return lines


def read_command(
    path: str | Path,
    *,
    column: str | None = None,
    unit: Unit | None = None,
    sample_period_s: Fraction | None = None,
    tagged: bool = False,
) -> Command:
    """Read a command file: a CSV with a header, or halsampler output when ``sample_period_s``
    is given (see the module docstring for the columns and units).

    Raises:
        UsageError: unreadable, no header or time unit, a non-number, time going backwards,
            non-finite values, no rows, or more than :data:`MAX_ROWS`.
    """
    p = Path(path)
    lines = _command_lines(p)
    if sample_period_s is not None:
        if sample_period_s <= 0:
            raise UsageError(f"{p}: the sample period must be > 0")
        times, values, fraction = _read_halsampler(p, lines, column, tagged)
        unit_ns = sample_period_s * 10**9
        name = f"halsampler value {column or 1}"
        guessed: Unit = "units" if fraction else "counts"
    else:
        if not lines:
            raise UsageError(f"{p}: no rows (expected a header such as 'time_s,position')")
        times, values, name = _read_csv(p, lines, column)
        unit_ns = Fraction(1)
        guessed = "counts" if _counts_name(name) else "units"
    if not len(times):
        raise UsageError(f"{p}: no command rows")
    first = 0 if sample_period_s is not None else 1
    check_finite(values, lambda i: f"{p}: line {lines[i + first][0]}")
    back = np.flatnonzero(np.diff(times) < 0)
    if len(back):
        i = int(back[0]) + 1
        raise _bad(
            p,
            lines[i + (0 if sample_period_s is not None else 1)][0],
            "time goes backwards (rows must be in time order)",
        )
    return Command(
        times, values, unit or guessed, f"{p} ({name}, {unit or guessed})", False, unit_ns
    )


def command_from_steps(
    events: StepEvents, tick_ns: Fraction, source: str, start: int, end: int
) -> Command:
    """A step train in the capture (ticks ``start`` … ``end``) as the command: counts from 0,
    each position held until the next step; steps of unknown direction count 0, as in
    :class:`~wavecheck.steps.decode.StepEvents`."""
    pos = events.position.astype(np.float64)
    last = float(pos[-1]) if len(pos) else 0.0
    times = np.concatenate([[start], events.ticks, [max(end, start)]]).astype(np.int64)
    return Command(
        times, np.concatenate([[0.0], pos, [last]]), "counts", source, hold=True, unit_ns=tick_ns
    )


def positions_at(
    report: FollowReport, ticks: Ints, feedback_ticks: Ints, feedback_pos: Ints
) -> Floats:
    """The feedback's position just before each of ``ticks`` (an encoder's index pulses)."""
    return _held(
        np.asarray(feedback_ticks, np.int64),
        np.asarray(feedback_pos, np.float64) + report.start_position,
        np.asarray(ticks, np.int64),
        "left",
        report.start_position,
    )


@dataclass
class FollowReport:
    """What ``wavecheck follow`` reports. Positions in feedback counts, times in seconds.

    ``t_s`` holds the breakpoints in the window; ``command``/``feedback``/``error`` the values
    just after each (right limits), ``error_before`` the error just before (they differ at a
    step). ``lag_s``: the least-squares τ in error ≈ command velocity × τ (None at rest).
    """

    command_source: str
    feedback_source: str
    scale: float | None
    delay_s: float
    start_s: float
    end_s: float
    start_position: float
    t_s: Floats
    command: Floats
    feedback: Floats
    error: Floats
    error_before: Floats
    max_error: float
    max_at_s: float
    rms: float
    mean: float
    lag_s: float | None
    end_command: float
    end_feedback: float
    end_moving: bool
    feedback_steps: int
    notes: list[str] = field(default_factory=list)
    index_counts: list[float] = field(default_factory=list)
    stepper: bool = True
    """The feedback is step pulses (a stepper: every count commanded is a step made, so a
    difference at rest is steps lost or extra); False for an encoder (a servo's residual)."""
    sampled: tuple[float, float, float, int] | None = None
    """At the command's samples only: (error of the largest |e|, its time, RMS, samples);
    None for a step-train command."""

    @property
    def end_difference(self) -> float:
        """command − feedback at the end of the window (counts)."""
        return self.end_command - self.end_feedback

    @property
    def lost_steps(self) -> int:
        """Whole steps the feedback lacks at the end (negative: extra steps). Only meaningful
        when the command is at rest at the end (:attr:`end_moving` False)."""
        return int(math.floor(self.end_difference + 0.5))


def _held(
    times: Ints, values: Floats, at: Ints, side: Literal["left", "right"], before: float
) -> Floats:
    i = np.searchsorted(times, at, side=side) - 1
    out = values[np.maximum(i, 0)] if len(values) else np.zeros(len(at))
    return np.where(i >= 0, out, before)


def _grid(unit_ns: Fraction, den: int, values: Ints) -> Ints:
    mult = unit_ns * den
    assert mult.denominator == 1
    m = int(mult)
    top = int(np.abs(values).max()) if len(values) else 0
    if top * m >= 2**53:
        raise UsageError("the capture or the command is too long for an exact time grid")
    return values.astype(np.int64) * m


def follow(
    command: Command,
    feedback_ticks: Ints,
    feedback_pos: Ints,
    *,
    tick_ns: Fraction,
    capture_start: int,
    capture_end: int,
    factor: float = 1.0,
    delay_ns: Fraction = Fraction(0),
    start_position: float | None = None,
    scale: float | None = None,
    feedback_source: str = "",
) -> FollowReport:
    """The following error of the feedback (position ``feedback_pos`` from each tick in
    ``feedback_ticks`` on, counts relative to the capture's start; ticks of ``tick_ns``)
    against ``command`` (its positions times ``factor`` = counts, its times plus ``delay_ns``).

    ``start_position``: the feedback's position at the capture's start (default: the command
    there, rounded to a whole count). ``scale``: counts per unit, for the report only.

    Raises:
        UsageError: the command and the capture do not overlap in time, or the times do not
            fit an exact grid.
    """
    den = math.lcm(command.unit_ns.denominator, tick_ns.denominator, delay_ns.denominator)
    to_s = 1e-9 / den
    d = int(delay_ns * den)
    ct = _grid(command.unit_ns, den, command.times) + d
    cv = command.position * factor
    fb_t = _grid(tick_ns, den, np.asarray(feedback_ticks, np.int64))
    c0, c1 = _grid(tick_ns, den, np.array([capture_start, capture_end], np.int64)).tolist()
    start, end = max(int(ct[0]), c0), min(int(ct[-1]), c1)
    if end < start or (end == start and len(ct) > 1):
        raise UsageError(
            f"the command ({ct[0] * to_s:.6g} s … {ct[-1] * to_s:.6g} s"
            f"{', delayed' if d else ''}) and the capture ({c0 * to_s:.6g} s … "
            f"{c1 * to_s:.6g} s) do not overlap"
        )
    ctf = ct.astype(np.float64)

    def cmd(at: Ints, side: Literal["left", "right"]) -> Floats:
        if command.hold:
            return _held(ct, cv, at, side, 0.0)
        return np.interp(at.astype(np.float64), ctf, cv)

    if start_position is None:
        start_position = float(np.floor(cmd(np.array([start], np.int64), "right")[0] + 0.5))
    fb_v = np.asarray(feedback_pos, dtype=np.float64) + start_position
    inside = (ct > start) & (ct < end)
    steps_in = (fb_t >= start) & (fb_t <= end)
    pts = np.unique(np.concatenate([np.array([start, end], np.int64), ct[inside], fb_t[steps_in]]))
    c_r, c_l = cmd(pts, "right"), cmd(pts, "left")
    f_r = _held(fb_t, fb_v, pts, "right", start_position)
    f_l = _held(fb_t, fb_v, pts, "left", start_position)
    e_r, e_l = c_r - f_r, c_l - f_l
    e_l[0] = e_r[0]  # nothing before the window
    both = np.concatenate([e_l, e_r])
    k = int(np.argmax(np.abs(both)))
    max_error = float(both[k])
    max_at = int(pts[k % len(pts)])
    dt = np.diff(pts).astype(np.float64) * to_s
    a, b = e_r[:-1], e_l[1:]
    total = float(end - start) * to_s
    lag = None
    if total > 0:
        mean = float(np.sum(dt * (a + b) / 2) / total)
        rms = math.sqrt(max(float(np.sum(dt * (a * a + a * b + b * b) / 3)) / total, 0.0))
        # the command's velocity on each segment: its slope between the command's own samples
        # (a step train's average rate between steps, not the zero slope of its treads)
        gaps = np.diff(ct).astype(np.float64) * to_s
        slope = np.where(gaps > 0, np.diff(cv) / np.where(gaps > 0, gaps, 1.0), 0.0)
        seg = np.clip(np.searchsorted(ct, pts[:-1], side="right") - 1, 0, max(len(slope) - 1, 0))
        vel = slope[seg] if len(slope) else np.zeros(len(dt))
        vv = float(np.sum(dt * vel * vel))
        lag = float(np.sum(dt * vel * (a + b) / 2) / vv) if vv > 0 else None
    else:
        mean = rms = abs(max_error)
    # at the command's own samples (what a servo thread sees: LinuxCNC's motion computes its
    # ferror once per servo period from the position read then, i.e. every change up to it)
    sampled = None
    if not command.hold:
        at = ct[(ct >= start) & (ct <= end)]
        if len(at):
            es = np.interp(at.astype(np.float64), ctf, cv) - _held(
                fb_t, fb_v, at, "right", start_position
            )
            j = int(np.argmax(np.abs(es)))
            sampled = (
                float(es[j]),
                float(at[j]) * to_s,
                math.sqrt(float(np.mean(es * es))),
                len(at),
            )
    # the command at rest at the end: its last segment flat (a step train: always)
    last = int(np.searchsorted(ct, end, side="left"))
    moving = (
        not command.hold
        and 0 < last < len(ct)
        and ct[last] > ct[last - 1]
        and cv[last] != cv[last - 1]
    )
    return FollowReport(
        command_source=command.source,
        feedback_source=feedback_source,
        scale=scale,
        delay_s=float(delay_ns) * 1e-9,
        start_s=start * to_s,
        end_s=end * to_s,
        start_position=start_position,
        t_s=pts.astype(np.float64) * to_s,
        command=c_r,
        feedback=f_r,
        error=e_r,
        error_before=e_l,
        max_error=max_error,
        max_at_s=max_at * to_s,
        rms=rms,
        mean=mean,
        lag_s=lag,
        end_command=float(c_r[-1]),
        end_feedback=float(f_r[-1]),
        end_moving=bool(moving),
        feedback_steps=int(np.count_nonzero(steps_in)),
        sampled=sampled,
    )
