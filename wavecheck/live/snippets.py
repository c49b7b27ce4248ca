"""Short ``.sr`` captures around violations found live (``wavecheck watch --snippets DIR``).

:class:`SampleRing` keeps the most recent raw sample bytes; :class:`Snippets` takes each violation
as the check finds it, waits until the window after it has arrived, and writes the samples
``[first event − window, last event + window]`` as an srzip file PulseView opens, named by the
violation's time, axis and rule (``000012.345678s-x-dir_hold.sr``). A violation that lies
inside a snippet already planned is counted there (``violations=`` in its metadata), so a
snippet is never longer than its violation and two windows. The ``[wavecheck]`` metadata group
says where the snippet starts in the watched stream (``first_sample``), so a time in it maps
back to the live report's time, and what it was checked with (``check=``: the drive, map,
inversions, step type, limits, as ``wavecheck check`` options, :func:`replay_arguments`), so
``wavecheck check SNIPPET.sr`` without options repeats the check (:func:`stored_arguments`).
:meth:`Snippets.summary` says how many violations were seen and why some have no file of their
own (inside another's window, beyond ``--max-snippets``, more at once than the check hands on).
"""

from __future__ import annotations

import argparse
import collections
import os
import shlex
import zlib
from collections.abc import Sequence
from dataclasses import dataclass, field
from fractions import Fraction
from pathlib import Path
from typing import TYPE_CHECKING

from wavecheck.capture.keyfile import KeyFileError, escape, parse_keyfile, unescape
from wavecheck.capture.srzip import EXACT_SECTION, sr_metadata, write_sr
from wavecheck.capture.zipdir import Archive, ZipError
from wavecheck.errors import UsageError
from wavecheck.steps.mapping import per_axis

if TYPE_CHECKING:
    from wavecheck.engine.planning import AxisPlan

__all__ = ["SampleRing", "Snippets", "replay_arguments", "stored_arguments"]

#: The metadata key of a snippet's check options.
CHECK_KEY = "check"


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
    check: Sequence[str] = ()
    written: list[Path] = field(default_factory=list)
    handed: int = 0  # violations handed to add()
    inside: int = 0  # of them, inside the window of a snippet already planned
    left_out: int = 0  # of them, beyond max_files
    lost: int = 0  # snippets not written: their samples had left the ring
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
        self.handed += 1
        lo, hi = min(start, end) - self.window, max(start, end) + 1 + self.window
        last = self._pending[-1] if self._pending else None
        if last is not None and max(start, end) < last.last:  # inside it: shown there
            last.count += 1
            self.inside += 1
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
            self.lost += 1
            return
        seconds = Fraction(p.at) / self.samplerate
        tag = f"{float(seconds):013.6f}s-{p.axis + '-' if p.axis else ''}{p.rule}"
        path = self.folder / f"{tag}.sr"
        extra = (
            f"\n[{EXACT_SECTION}]\nsnippet_of=wavecheck watch\nfirst_sample={first}\n"
            f"violations={p.count}\n{CHECK_KEY}={escape(shlex.join(self.check))}\n"
        )
        rate = int(self.samplerate) if self.samplerate.denominator == 1 else str(self.samplerate)
        meta = sr_metadata(
            self.names, samplerate=rate, unitsize=self.ring.unitsize, total_analog=0, extra=extra
        )
        write_sr(path, self.ring.samples(first, last), metadata=meta)
        self.written.append(path)

    def summary(self, total: int) -> str:
        """One line: ``total`` violations seen by the check, the snippets written and why the
        others have no file of their own."""
        why = []
        if self.inside:
            why.append(f"{self.inside} inside another snippet's window")
        if self.left_out:
            why.append(f"{self.left_out} beyond --max-snippets {self.max_files}")
        if total > self.handed:
            why.append(f"{total - self.handed} more at once than the live check hands on")
        if self.lost:
            why.append(f"{self.lost} snippet(s) whose samples had already gone")
        return (
            f"snippets: {len(self.written)} file(s) in {self.folder} for {total} violation(s) "
            f"seen" + (f" ({'; '.join(why)})" if why else "")
        )


def _channel_ref(channel: str, names: Sequence[str]) -> str:
    """A channel as a ``--map`` value: its name, or its index when the name would not parse
    (a comma, an equals sign) or is not unique."""
    if "," in channel or "=" in channel or names.count(channel) != 1:
        return str(names.index(channel))
    return channel


def replay_arguments(
    args: argparse.Namespace, plans: Sequence[AxisPlan], names: Sequence[str]
) -> list[str]:
    """The ``wavecheck check`` options that repeat the live check of the axes ``plans`` on a
    snippet of the stream (channels ``names``): each axis's drive, its resolved map (roles
    shared by every axis once, without an axis), inversions, step type and DIR sense, and the
    run's ``--limit``, ``--margin``, ``--pulse-level``, ``--active-edge``, ``--user-step-type``."""
    drives = per_axis(args.drive, "--drive", [p.name for p in plans])
    maps = [
        {role: _channel_ref(sig.channel, names) for role, sig in p.interface.signals.items()}
        for p in plans
    ]
    shared = (
        {k: v for k, v in maps[0].items() if all(m.get(k) == v for m in maps)}
        if len(maps) > 1
        else {}
    )
    argv: list[str] = []
    for p, roles in zip(plans, maps, strict=True):
        dot, eq = (f"{p.name}.", f"{p.name}=") if p.name else ("", "")
        drive = drives[p.name]
        if Path(drive).is_file():
            drive = str(Path(drive).resolve())
        argv += ["--drive", eq + drive]
        own = {k: v for k, v in roles.items() if k not in shared}
        if own:
            argv += ["--map", ",".join(f"{dot}{k}={v}" for k, v in own.items())]
        for role, sig in p.interface.signals.items():
            if sig.inverted:
                argv += ["--invert", role if role in shared else dot + role]
        argv += ["--type", f"{eq}{p.step_type.number}"]
        if p.forward_level:
            argv += ["--dir-forward", f"{eq}high"]
    if shared:
        argv += ["--map", ",".join(f"{k}={v}" for k, v in shared.items())]
    for option, value in (
        ("--user-step-type", args.user_step_type),
        ("--active-edge", args.active_edge),
        ("--margin", args.margin),
    ):
        if value:
            argv += [option, value]
    if args.pulse_level is not None:
        argv += ["--pulse-level", args.pulse_level]
    for item in args.limit:
        argv += ["--limit", item]
    return _dedupe_inverts(argv)


def _dedupe_inverts(argv: list[str]) -> list[str]:
    """A shared role's ``--invert`` once (every axis lists it)."""
    out: list[str] = []
    seen: set[str] = set()
    for k in range(0, len(argv), 2):
        pair = argv[k : k + 2]
        if pair[0] == "--invert":
            if pair[1] in seen:
                continue
            seen.add(pair[1])
        out += pair
    return out


def stored_arguments(path: str | os.PathLike[str]) -> list[str] | None:
    """The check options a snippet written by ``wavecheck watch`` carries (None: ``path`` is
    not such a snippet, or cannot be read; the check then says what it needs)."""
    try:
        with Archive(path) as z:
            info = z.getinfo("metadata")
            if info.file_size > 1 << 16:
                return None
            text = z.read("metadata").decode("utf-8", "replace")
        line = parse_keyfile(text).get(EXACT_SECTION, {}).get(CHECK_KEY)
        return shlex.split(unescape(line)) if line else None
    except (OSError, KeyError, ValueError, EOFError, zlib.error, ZipError, KeyFileError):
        return None
