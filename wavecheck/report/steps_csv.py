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

import contextlib
import errno
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from fractions import Fraction
from typing import TYPE_CHECKING, Any

import numpy as np

from wavecheck.capture.edges import EdgeArray
from wavecheck.errors import UsageError
from wavecheck.output import atomic_path
from wavecheck.steps.mapping import check_axis_names
from wavecheck.timebase import Timebase

if TYPE_CHECKING:
    import numpy.typing as npt

__all__ = [
    "StepsCsvWriter",
    "decimal_digits",
    "format_times",
    "parse_steps_per_unit",
    "steps_per_unit_of",
]

#: Rows formatted at a time.
CHUNK = 1 << 16
_LIMIT = 1 << 62
#: Decimals of ``rate_hz`` (mHz) and of the machine-unit columns (1e-6 units: nm for mm).
RATE_PLACES = 3
UNIT_PLACES = 6
HEADER = ("time_s", "tick", "axis", "direction", "position", "rate_hz")
UNIT_HEADER = ("position_units", "velocity_units_per_s")


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


def _format(
    ticks: EdgeArray,
    which: npt.NDArray[np.int32],
    direction: npt.NDArray[np.int8],
    position: EdgeArray,
    gaps: EdgeArray,
    first: npt.NDArray[np.bool_],
    names: npt.NDArray[np.str_],
    per_unit: npt.NDArray[np.float64] | None,
    timebase: Timebase,
) -> str:
    """The rows of steps already in order (one line each, no final newline)."""
    hz = float(timebase.samplerate_hz)
    valid = ~first
    rate = np.divide(hz, gaps, out=np.zeros(len(ticks)), where=valid)
    fields = [
        _decimal_field(*_time_parts(ticks, timebase.tick_s)),
        _Field("%d", [ticks.tolist()]),
        _Field("%s", [names[which].tolist()]),
        _Field("%d", [direction.tolist()]),
        _Field("%d", [position.tolist()]),
        _fixed_field(rate, valid, RATE_PLACES),
    ]
    if per_unit is not None:
        spu = per_unit[which]
        has = ~np.isnan(spu)
        fields += [
            _fixed_field(position / np.where(has, spu, 1.0), has, UNIT_PLACES),
            _fixed_field(
                direction * rate / np.where(has, spu, 1.0),
                has & valid & (direction != 0),
                UNIT_PLACES,
            ),
        ]
    return _rows(fields)


class _Pending:
    """One axis's steps handed over and not yet written, with what the next ones continue."""

    def __init__(self) -> None:
        self.parts: list[tuple[EdgeArray, npt.NDArray[np.int8], EdgeArray, EdgeArray]] = []
        self.position = 0
        self.last: int | None = None

    def add(self, ticks: EdgeArray, direction: npt.NDArray[np.int8]) -> None:
        if not len(ticks):
            return
        position = self.position + np.cumsum(direction, dtype=np.int64)
        prev = np.empty(len(ticks), dtype=np.int64)
        prev[1:] = ticks[:-1]
        prev[0] = ticks[0] if self.last is None else self.last
        self.parts.append((ticks.copy(), direction.copy(), position, ticks - prev))
        self.position = int(position[-1])
        self.last = int(ticks[-1])

    def take(self, before: int) -> tuple[EdgeArray, npt.NDArray[np.int8], EdgeArray, EdgeArray]:
        """The steps before tick ``before``, removed."""
        if not self.parts:
            z = np.zeros(0, dtype=np.int64)
            return z, np.zeros(0, np.int8), z, z
        t, d, p, g = (np.concatenate(x) for x in zip(*self.parts, strict=True))
        k = int(np.searchsorted(t, before, side="left"))
        self.parts = [(t[k:], d[k:], p[k:], g[k:])] if k < len(t) else []
        return t[:k], d[:k], p[:k], g[:k]


class StepsCsvWriter:
    """The CSV written while the engine runs: each axis's steps come through its sink
    (:meth:`sink`), and :meth:`settled` writes every row before a tick no axis can still add
    steps before, in time order over all axes; :meth:`close` writes the rest and puts the file
    in place (whole or not at all, :func:`wavecheck.output.atomic_path`).

    Args:
        target: the CSV file.
        timebase: the capture's tick.
        units: write the machine-unit columns.
        named: axes ``--steps-per-unit`` names (each must be an axis of the run).
    """

    def __init__(
        self,
        target: str | os.PathLike[str],
        timebase: Timebase,
        units: bool,
        named: set[str | None] | None = None,
    ) -> None:
        self.target = target
        self.timebase = timebase
        self.units = units
        self.named = set(named or ())
        self._checked = False
        self.names: list[str] = []
        self._axis_names: list[str | None] = []
        self.per_unit: list[float] = []
        self.axes: list[_Pending] = []
        self.rows = 0
        self._stack = contextlib.ExitStack()
        try:
            path = self._stack.enter_context(atomic_path(target))
            self._file = self._stack.enter_context(open(path, "w", encoding="utf-8", newline=""))
            self._file.write(",".join(HEADER + (UNIT_HEADER if units else ())) + "\n")
        except OSError as err:
            self._stack.close()
            raise UsageError(f"{os.fspath(target)}: cannot write ({err.strerror or err})") from None

    def sink(self, name: str | None, steps_per_unit: Fraction | None = None) -> _Pending:
        """The step sink of the next axis (``name`` None: the single unnamed axis)."""
        self._axis_names.append(name)
        self.names.append("" if name is None else _csv_field(name))
        self.per_unit.append(np.nan if steps_per_unit is None else float(steps_per_unit))
        pending = _Pending()
        self.axes.append(pending)
        return pending

    def settled(self, before: int) -> None:
        """Write every step before tick ``before`` (no axis adds one earlier any more)."""
        if not self._checked:  # every axis has its sink by now
            self._checked = True
            check_axis_names({"--steps-per-unit": self.named}, self._axis_names)
        taken = [a.take(before) for a in self.axes]
        n = sum(len(t[0]) for t in taken)
        if not n:
            return
        ticks = np.concatenate([t[0] for t in taken])
        which = np.concatenate([np.full(len(t[0]), k, dtype=np.int32) for k, t in enumerate(taken)])
        order = np.lexsort((which, ticks))
        cols = [np.concatenate([t[i] for t in taken])[order] for i in range(1, 4)]
        direction, position, gaps = cols[0], cols[1], cols[2]
        ticks, which = ticks[order], which[order]
        first = gaps <= 0
        names = np.array(self.names, dtype=np.str_)
        per_unit = np.array(self.per_unit) if self.units else None
        for i in range(0, n, CHUNK):
            j = slice(i, i + CHUNK)
            self._write(
                _format(ticks[j], which[j], direction[j], position[j], gaps[j], first[j],
                        names, per_unit, self.timebase) + "\n"
            )  # fmt: skip
        self.rows += n

    def _write(self, text: str) -> None:
        try:
            self._file.write(text)
        except OSError as err:
            self.abort()
            if err.errno == errno.EPIPE:
                raise
            raise UsageError(
                f"{os.fspath(self.target)}: cannot write ({err.strerror or err})"
            ) from None

    def close(self) -> int:
        """Write the rest and put the file in place; the number of rows."""
        self.settled(_LIMIT)
        try:
            self._stack.close()
        except OSError as err:
            raise UsageError(
                f"{os.fspath(self.target)}: cannot write ({err.strerror or err})"
            ) from None
        return self.rows

    def abort(self) -> None:
        """Leave no file (an error stopped the run)."""
        self._stack.__exit__(RuntimeError, RuntimeError("aborted"), None)


def _csv_field(text: str) -> str:
    if any(c in text for c in ',"\n\r'):
        return '"' + text.replace('"', '""') + '"'
    return text


def steps_per_unit_of(
    values: Mapping[str | None, str], option: str = "--steps-per-unit"
) -> dict[str | None, Fraction]:
    """Per-axis ``--steps-per-unit`` texts (see :func:`wavecheck.steps.mapping.per_axis`) as numbers."""
    return {axis: parse_steps_per_unit(text, option) for axis, text in values.items()}
