"""Short ``.sr`` captures around violations found live (``wavecheck watch --snippets DIR``).

:class:`SampleRing` keeps the most recent raw sample bytes; :class:`Snippets` takes each violation
as the check finds it, waits until the window after it has arrived, and writes the samples
``[first event − window, last event + window]`` as an srzip file PulseView opens, named by the
violation's time, axis and rule (``000012.345678s-x-dir_hold.sr``). A violation that lies
inside a snippet already planned is counted there (``violations=`` in its metadata), so a
snippet is never longer than its violation and two windows. The ``[wavecheck]`` metadata group says where the snippet starts in the
watched stream (``first_sample``), so a time in it maps back to the live report's time.
"""

from __future__ import annotations

import collections
import os
from dataclasses import dataclass, field
from fractions import Fraction
from pathlib import Path

from wavecheck.capture.srzip import sr_metadata, write_sr
from wavecheck.errors import UsageError

__all__ = ["SampleRing", "Snippets"]


class SampleRing:
    """The last ``keep`` samples' bytes (at least), as the pieces they arrived in."""

    def __init__(self, unitsize: int, keep: int) -> None:
        self.unitsize = unitsize
        self.keep_bytes = max(1, keep) * unitsize
        self.pieces: collections.deque[tuple[int, bytes]] = collections.deque()  # (offset, data)
        self.end = 0  # bytes taken so far

    def add(self, data: bytes) -> None:
        """Append the next bytes of the stream (any split, whole samples or not)."""
        if data:
            self.pieces.append((self.end, data))
            self.end += len(data)
        while (
            self.pieces and self.pieces[0][0] + len(self.pieces[0][1]) <= self.end - self.keep_bytes
        ):
            self.pieces.popleft()

    @property
    def first_sample(self) -> int:
        """The earliest whole sample still held."""
        if not self.pieces:
            return self.end // self.unitsize
        return -(-self.pieces[0][0] // self.unitsize)

    def samples(self, first: int, last: int) -> bytes:
        """The bytes of samples ``[first, last)`` (all held: see :attr:`first_sample`)."""
        lo, hi = first * self.unitsize, last * self.unitsize
        out = bytearray()
        for off, data in self.pieces:
            a, b = max(lo, off), min(hi, off + len(data))
            if a < b:
                out += data[a - off : b - off]
        return bytes(out)


@dataclass
class _Pending:
    first: int  # first sample to write
    last: int  # one past the last sample to write
    at: int  # the first violation's tick
    axis: str | None
    rule: str
    count: int = 1


@dataclass
class Snippets:
    """Snippet files in ``folder`` (created if missing), at most ``max_files``.

    ``window``: samples kept before and after each violation.
    """

    folder: Path
    ring: SampleRing
    names: list[str]
    samplerate: Fraction
    window: int
    max_files: int = 100
    written: list[Path] = field(default_factory=list)
    left_out: int = 0
    _pending: list[_Pending] = field(default_factory=list)

    def __post_init__(self) -> None:
        try:
            self.folder.mkdir(parents=True, exist_ok=True)
        except OSError as err:
            raise UsageError(f"--snippets {self.folder}: cannot create: {err.strerror}") from None
        if not os.access(self.folder, os.W_OK):
            raise UsageError(f"--snippets {self.folder}: folder is not writable")

    def add(self, axis: str | None, rule: str, start: int, end: int) -> None:
        """A violation between ticks ``start`` and ``end`` (samples)."""
        lo, hi = min(start, end) - self.window, max(start, end) + 1 + self.window
        last = self._pending[-1] if self._pending else None
        if last is not None and max(start, end) < last.last:  # inside it: shown there
            last.count += 1
            return
        if len(self.written) + len(self._pending) >= self.max_files:
            self.left_out += 1
            return
        self._pending.append(_Pending(max(0, lo), hi, min(start, end), axis, rule))

    def due(self, now: int, final: bool = False) -> None:
        """Write the snippets whose window has arrived (``now``: samples so far; ``final``: all,
        cut at the end of the stream)."""
        while self._pending and (final or self._pending[0].last <= now):
            self._write(self._pending.pop(0), now)

    def _write(self, p: _Pending, now: int) -> None:
        first = max(p.first, self.ring.first_sample)
        last = min(p.last, now)
        if last <= first:
            return
        seconds = Fraction(p.at) / self.samplerate
        tag = f"{float(seconds):013.6f}s-{p.axis + '-' if p.axis else ''}{p.rule}"
        path = self.folder / f"{tag}.sr"
        extra = (
            f"\n[wavecheck]\nsnippet_of=wavecheck watch\nfirst_sample={first}\n"
            f"violations={p.count}\n"
        )
        rate = int(self.samplerate) if self.samplerate.denominator == 1 else str(self.samplerate)
        meta = sr_metadata(
            self.names, samplerate=rate, unitsize=self.ring.unitsize, total_analog=0, extra=extra
        )
        write_sr(path, self.ring.samples(first, last), metadata=meta)
        self.written.append(path)
