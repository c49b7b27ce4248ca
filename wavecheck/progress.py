"""A progress bar on stderr for long work (reading large captures, long simulations).

The bar is drawn only when stderr is a terminal and the user did not ask for ``--quiet``, and
only once the work has run for :data:`DELAY_S` seconds, so short runs print nothing.

Code that does long work reports through a plain callback, ``(done, total) -> None``, in whatever
unit it counts (bytes read, base periods simulated); it never needs to know whether a bar is
shown. Two ways to get one:

- take it as an argument (``progress: ProgressCallback = no_progress``), or
- ask for the active one: ``cb = wavecheck.progress.current()`` — the CLI activates a bar around
  the work with :func:`activate`; outside it :func:`current` returns a no-op.

Example (a reader)::

    from wavecheck.progress import current

    report = current()
    for offset in range(0, size, chunk):
        ...
        report(offset + chunk, size)
"""

from __future__ import annotations

import contextlib
import contextvars
import sys
import time
from collections.abc import Callable, Iterator
from typing import TextIO

__all__ = [
    "DELAY_S",
    "QUIET_HELP",
    "ProgressBar",
    "ProgressCallback",
    "activate",
    "current",
    "no_progress",
]

#: The one meaning of ``-q/--quiet`` in both tools (wavecheck check/measure, stepgen simulate):
#: no bar and no summary line; the requested outputs, warnings and errors still come.
QUIET_HELP = (
    "quiet: no progress bar and no summary line; only the report (or -o FILE), the files asked "
    "for, warnings and errors (the same in wavecheck and stepgen)"
)

ProgressCallback = Callable[[int, int | None], None]
"""``callback(done, total)``: ``done`` units of ``total`` (None when the total is unknown)."""

#: Seconds of work before a bar appears (short runs stay silent).
DELAY_S = 0.5
#: Seconds between two redraws.
_REDRAW_S = 0.1
_WIDTH = 30


def no_progress(done: int, total: int | None = None) -> None:
    """Ignore a progress report."""


_ACTIVE: contextvars.ContextVar[ProgressCallback] = contextvars.ContextVar(
    "wavecheck_progress", default=no_progress
)


def current() -> ProgressCallback:
    """The progress callback of the work in hand (a no-op when no bar is active)."""
    return _ACTIVE.get()


class ProgressBar:
    """A one-line bar, redrawn in place on ``stream`` (default stderr).

    Args:
        label: what is being done (``"reading run.sr"``).
        unit: ``"bytes"`` shows sizes in kB/MB; anything else is printed after the counts.
        stream: where to draw (default ``sys.stderr``).
        enabled: force on or off; default: on when ``stream`` is a terminal.
        delay_s: seconds before the first draw (default :data:`DELAY_S`).
    """

    def __init__(
        self,
        label: str,
        *,
        unit: str = "",
        stream: TextIO | None = None,
        enabled: bool | None = None,
        delay_s: float = DELAY_S,
    ) -> None:
        self.label = label
        self.unit = unit
        self.stream = stream if stream is not None else sys.stderr
        if enabled is None:
            isatty = getattr(self.stream, "isatty", None)
            enabled = bool(isatty and isatty())
        self.enabled = enabled
        self.delay_s = delay_s
        self._t0 = time.monotonic()
        self._last = 0.0
        self._drawn = False

    def _amount(self, n: int) -> str:
        if self.unit != "bytes":
            return f"{n:,}{' ' + self.unit if self.unit else ''}"
        size = float(n)
        for suffix in ("B", "kB", "MB", "GB"):
            if size < 1000 or suffix == "GB":
                return f"{size:.0f} {suffix}" if suffix == "B" else f"{size:.1f} {suffix}"
            size /= 1000
        return f"{n} B"  # pragma: no cover

    def line(self, done: int, total: int | None) -> str:
        """The text of the bar for ``done`` of ``total`` (no terminal control characters)."""
        if total:
            frac = min(max(done / total, 0.0), 1.0)
            full = int(frac * _WIDTH)
            bar = "#" * full + "-" * (_WIDTH - full)
            return f"{self.label} [{bar}] {frac:4.0%} {self._amount(done)} / {self._amount(total)}"
        return f"{self.label} … {self._amount(done)}"

    def __call__(self, done: int, total: int | None = None) -> None:
        """Report ``done`` of ``total``; redraws at most every 0.1 s, after the start delay."""
        if not self.enabled:
            return
        now = time.monotonic()
        if now - self._t0 < self.delay_s or (self._drawn and now - self._last < _REDRAW_S):
            return
        self._last = now
        self._drawn = True
        self.stream.write("\r\x1b[2K" + self.line(done, total))
        self.stream.flush()

    def close(self) -> None:
        """Erase the bar (if it was drawn) so the next output starts on a clean line."""
        if self._drawn:
            self.stream.write("\r\x1b[2K")
            self.stream.flush()
            self._drawn = False


@contextlib.contextmanager
def activate(
    label: str, *, quiet: bool = False, unit: str = "", stream: TextIO | None = None
) -> Iterator[ProgressCallback]:
    """Make a bar the :func:`current` callback for the duration of the ``with`` block.

    Args:
        label: what is being done.
        quiet: no bar at all (the CLI's ``--quiet``).
        unit: unit of the counts (``"bytes"`` for readers).
        stream: where to draw (default stderr; the bar is off unless it is a terminal).
    """
    bar = ProgressBar(label, unit=unit, stream=stream, enabled=False if quiet else None)
    token = _ACTIVE.set(bar)
    try:
        yield bar
    finally:
        _ACTIVE.reset(token)
        bar.close()
