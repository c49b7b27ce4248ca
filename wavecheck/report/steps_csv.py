"""The decoded steps as CSV (``--steps-csv FILE`` of ``check`` and ``measure``): one row per step.

Columns::

    time_s,tick,axis,direction,position,rate_hz[,position_units,velocity_units_per_s]

- ``time_s``: the step's time in seconds from the capture's tick 0, written from the exact tick
  × the exact tick length (no float): exact whenever the tick length is a terminating decimal
  (every VCD timescale; sample rates such as 1, 2, 4, 5, 8, 10, 16, 20, 25, 50, 100 MHz). A tick
  such as 1/12 MHz = 83.3… ns has no decimal: its times carry digits enough to be within a
  twentieth of a tick, and ``tick`` × the tick length is the exact time.
- ``tick``: the step's tick (exact integer); ``axis``: the axis name (empty for a single unnamed
  axis); ``direction``: 1 forward, -1 reverse, 0 unknown or ambiguous; ``position``: the running
  position in steps after the step (unknown steps count 0, so the last row of an axis is its
  final position and the directions sum to it).
- ``rate_hz``: the instantaneous step rate, 1 / the time since the axis's previous step, in
  3 decimals (empty on an axis's first step or after a step at the same tick).
- With steps per unit given for an axis: ``position_units`` (position / steps per unit) and
  ``velocity_units_per_s`` (direction × rate / steps per unit), in 6 decimals; empty for other
  axes (and the velocity of a step of unknown direction).

Rows are in time order over all axes (an axis's order first at equal times), written in chunks
formatted by numpy, through :func:`wavecheck.output.atomic_path` (whole or not at all).
"""

from __future__ import annotations

import errno
import os
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from fractions import Fraction
from typing import Any

import numpy as np
import numpy.typing as npt

from wavecheck.capture.edges import EdgeArray
from wavecheck.engine.decode import StepEvents
from wavecheck.errors import UsageError
from wavecheck.output import atomic_path
from wavecheck.timebase import Timebase

__all__ = [
    "AxisSteps",
    "decimal_digits",
    "format_times",
    "parse_steps_per_unit",
    "steps_per_unit_of",
    "steps_csv_chunks",
    "write_steps_csv",
]

#: Rows formatted at a time.
CHUNK = 1 << 16
_LIMIT = 1 << 62
#: Decimals of ``rate_hz`` (mHz) and of the machine-unit columns (1e-6 units: nm for mm).
RATE_PLACES = 3
UNIT_PLACES = 6
HEADER = ("time_s", "tick", "axis", "direction", "position", "rate_hz")
UNIT_HEADER = ("position_units", "velocity_units_per_s")


@dataclass(frozen=True)
class AxisSteps:
    """The steps of one axis for the CSV: its name, its steps, its steps per machine unit."""

    name: str | None
    steps: StepEvents
    steps_per_unit: Fraction | None = None


def decimal_digits(tick_s: Fraction) -> tuple[int, bool]:
    """The decimal places that write every multiple of ``tick_s`` seconds, and whether that is
    exact (a terminating decimal); when it is not, the places that keep a time within a
    twentieth of a tick."""
    d = tick_s.denominator
    twos = fives = 0
    while d % 2 == 0:
        d //= 2
        twos += 1
    while d % 5 == 0:
        d //= 5
        fives += 1
    if d == 1:
        return max(twos, fives), True
    places = 0
    while Fraction(1, 10**places) > tick_s / 10:
        places += 1
    return places, False


def _time_parts(
    ticks: EdgeArray, tick_s: Fraction
) -> tuple[npt.NDArray[np.bool_], npt.NDArray[Any], npt.NDArray[Any], int]:
    """``ticks`` × ``tick_s`` as (negative, whole seconds, fraction digits, places): integers
    only (see :func:`decimal_digits`; rounded half up where the decimal does not end)."""
    places, _ = decimal_digits(tick_s)
    num, den = tick_s.numerator, tick_s.denominator
    scale = 10**places
    negative = ticks < 0
    mag: npt.NDArray[np.int64] | npt.NDArray[np.object_] = np.abs(ticks)
    top = int(mag.max()) if len(mag) else 0
    if top * num >= _LIMIT or den * scale >= _LIMIT:  # beyond int64: Python integers, still exact
        mag = mag.astype(object)
    scaled = mag * num
    whole, rest = scaled // den, scaled % den
    frac = (rest * scale + den // 2) // den
    return negative, whole + frac // scale, frac % scale, places


@dataclass(frozen=True)
class _Field:
    """One CSV column: its printf format, one argument list per placeholder, and where it is
    written (None: every row; elsewhere the field is empty)."""

    fmt: str
    args: list[list[Any]]
    shown: npt.NDArray[np.bool_] | None = None


def _decimal_field(
    negative: npt.NDArray[np.bool_],
    whole: npt.NDArray[Any],
    frac: npt.NDArray[Any],
    places: int,
    shown: npt.NDArray[np.bool_] | None = None,
) -> _Field:
    fmt = f"%s%d.%0{places}d" if places else "%s%d%.0s"
    sign = np.where(negative, "-", "").tolist()
    return _Field(fmt, [sign, whole.tolist(), frac.tolist()], shown)


def _fixed_field(
    values: npt.NDArray[np.float64], shown: npt.NDArray[np.bool_], places: int
) -> _Field:
    """Floats in ``places`` decimals, from integers (a float formatter per value costs several
    times more on millions of rows)."""
    scale = 10**places
    v = np.where(shown, values, 0.0)
    scaled = np.rint(np.abs(v) * scale).astype(np.int64)
    return _decimal_field((v < 0) & (scaled > 0), scaled // scale, scaled % scale, places, shown)


def _rows(fields: Sequence[_Field]) -> str:
    """The rows of ``fields`` as text: one printf format per row, chosen by numpy from the few
    combinations of shown fields (a hidden one consumes its arguments with ``%.0s``), applied
    by ``str.__mod__`` in C; no Python code runs per row."""
    optional = [f for f in fields if f.shown is not None]
    n = len(fields[0].args[0])
    code = np.zeros(n, dtype=np.int64)
    for bit, f in enumerate(optional):
        assert f.shown is not None
        code |= f.shown.astype(np.int64) << bit
    table = []
    for c in range(1 << len(optional)):
        parts = []
        for f in fields:
            hidden = f.shown is not None and not (c >> optional.index(f)) & 1
            parts.append("%.0s" * len(f.args) if hidden else f.fmt)
        table.append(",".join(parts))
    fmts = np.array(table, dtype=object)[code].tolist()
    args = zip(*(a for f in fields for a in f.args), strict=True)
    return "\n".join(map(str.__mod__, fmts, args))


def format_times(ticks: EdgeArray, tick_s: Fraction) -> list[str]:
    """``ticks`` × ``tick_s`` as decimal strings in seconds (see :func:`decimal_digits`)."""
    if len(ticks) == 0:
        return []
    return _rows([_decimal_field(*_time_parts(ticks, tick_s))]).split("\n")


def parse_steps_per_unit(text: str, option: str = "--steps-per-unit") -> Fraction:
    """A positive number of steps per machine unit (``200``, ``80.5``, ``3200/25``).

    Raises:
        UsageError: not a number, or not positive.
    """
    try:
        value = Fraction(text.strip())
    except (ValueError, ZeroDivisionError):
        raise UsageError(
            f"{option} {text!r} is not a number of steps per unit (e.g. {option} 80 for 80 "
            f"steps/mm, or {option} x=80)"
        ) from None
    if value <= 0:
        raise UsageError(f"{option} {text}: must be positive")
    return value


def steps_csv_chunks(
    axes: Sequence[AxisSteps], timebase: Timebase, chunk: int = CHUNK
) -> Iterator[str]:
    """The CSV's text: the header line, then the rows in chunks of ``chunk`` lines."""
    units = any(a.steps_per_unit is not None for a in axes)
    yield ",".join(HEADER + (UNIT_HEADER if units else ())) + "\n"
    if not axes:
        return
    hz = float(timebase.samplerate_hz)
    ticks = np.concatenate([a.steps.ticks for a in axes])
    which = np.concatenate([np.full(a.steps.count, k, dtype=np.int32) for k, a in enumerate(axes)])
    direction = np.concatenate([a.steps.direction for a in axes])
    position = np.concatenate([a.steps.position for a in axes])
    gaps = np.concatenate([np.diff(a.steps.ticks, prepend=a.steps.ticks[:1]) for a in axes])
    first = np.concatenate([np.arange(a.steps.count) == 0 for a in axes]) | (gaps <= 0)
    names = np.array(["" if a.name is None else _csv_field(a.name) for a in axes], dtype=np.str_)
    per_unit = np.array(
        [np.nan if a.steps_per_unit is None else float(a.steps_per_unit) for a in axes]
    )
    order = np.lexsort((which, ticks))
    for i in range(0, len(order), chunk):
        idx = order[i : i + chunk]
        t, k, d = ticks[idx], which[idx], direction[idx]
        valid = ~first[idx]
        rate = np.divide(hz, gaps[idx], out=np.zeros(len(idx)), where=valid)
        fields = [
            _decimal_field(*_time_parts(t, timebase.tick_s)),
            _Field("%d", [t.tolist()]),
            _Field("%s", [names[k].tolist()]),
            _Field("%d", [d.tolist()]),
            _Field("%d", [position[idx].tolist()]),
            _fixed_field(rate, valid, RATE_PLACES),
        ]
        if units:
            spu = per_unit[k]
            has = ~np.isnan(spu)
            fields += [
                _fixed_field(position[idx] / np.where(has, spu, 1.0), has, UNIT_PLACES),
                _fixed_field(
                    d * rate / np.where(has, spu, 1.0), has & valid & (d != 0), UNIT_PLACES
                ),
            ]
        yield _rows(fields) + "\n"


def _csv_field(text: str) -> str:
    if any(c in text for c in ',"\n\r'):
        return '"' + text.replace('"', '""') + '"'
    return text


def write_steps_csv(
    target: str | os.PathLike[str],
    axes: Sequence[AxisSteps],
    timebase: Timebase,
    chunk: int = CHUNK,
) -> int:
    """Write the steps of ``axes`` to ``target`` (whole or not at all); returns the row count.

    Raises:
        UsageError: the target is refused or cannot be written.
    """
    try:
        with atomic_path(target) as path, open(path, "w", encoding="utf-8", newline="") as f:
            for text in steps_csv_chunks(axes, timebase, chunk):
                f.write(text)
    except OSError as err:
        if err.errno == errno.EPIPE:
            raise
        raise UsageError(f"{os.fspath(target)}: cannot write ({err.strerror or err})") from None
    return sum(a.steps.count for a in axes)


def steps_per_unit_of(
    values: Mapping[str | None, str], option: str = "--steps-per-unit"
) -> dict[str | None, Fraction]:
    """Per-axis ``--steps-per-unit`` texts (see :func:`wavecheck.axes.per_axis`) as numbers."""
    return {axis: parse_steps_per_unit(text, option) for axis, text in values.items()}
