"""Open any capture: pick the reader from ``--input-format``, the file's content, or its extension.

The formats are the records of :data:`wavecheck.capture.formats.FORMATS` (name, magic bytes,
extensions, ``read``, ``blocks``); this module only walks them, for a file, a folder, standard
input or a pipe (a format that cannot read a stream is spooled to a temporary file first), and
gives a capture read whole the reader of its vectors' bits (:func:`_wired`).
"""

from __future__ import annotations

import contextlib
import functools
import io
import os
import stat
import sys
from collections.abc import Sequence
from fractions import Fraction
from pathlib import Path
from typing import TYPE_CHECKING, Any, BinaryIO

from wavecheck.capture.edges import Capture
from wavecheck.capture.formats import (
    ZIP_MAGIC,
    Format,
    Request,
    by_content,
    by_extension,
    by_folder,
    by_name,
    named_formats,
)
from wavecheck.errors import CaptureError, UsageError
from wavecheck.record import record, replace

if TYPE_CHECKING:
    from wavecheck.capture.blocks import BlockSource

__all__ = [
    "STDIN",
    "detect_format",
    "format_of",
    "is_stream",
    "open_capture",
    "open_source",
]

_SNIFF_BYTES = 4096
#: The capture path that means standard input.
STDIN = "-"


def detect_format(path: str | os.PathLike[str]) -> str:
    """The input format of ``path``: ``"sr"``, ``"vcd"``, ``"fst"``, ``"ghw"`` or a sigrok-cli
    input format name.

    Raises:
        CaptureError: missing file, a folder, an empty file, or a format that cannot be told.
    """
    p = Path(path)
    if not p.exists():
        raise CaptureError(path, None, "no such file")
    if p.is_dir():
        if (held := by_folder(p)) is not None:
            return held.name
        raise CaptureError(path, None, "is a folder, not a capture file")
    try:
        with open(p, "rb") as f:
            head = f.read(_SNIFF_BYTES)
    except OSError as err:
        raise CaptureError(path, None, f"cannot open: {err.strerror or err}") from None
    if head.startswith(ZIP_MAGIC):
        head += _zip_names(p)  # a member named beyond the first bytes (the central directory)
    return format_of(path, head, p.suffix.lower())


def _zip_names(path: Path) -> bytes:
    """The member names of a zip file, one a line (nothing when it cannot be read as a zip)."""
    from wavecheck.capture.zipdir import Archive, ZipError

    try:
        with Archive(path) as zf:
            return "\n".join(zf.namelist()[:1000]).encode("utf-8", "replace")
    except (OSError, ZipError, EOFError):
        return b""  # the .sr reader says what is wrong with the zip


def format_of(path: str | os.PathLike[str], head: bytes, ext: str) -> str:
    """The format told by the first bytes ``head`` of a capture, else by its extension ``ext``.

    Raises:
        CaptureError: an empty input, or a format that cannot be told.
    """
    if not head.strip():
        raise CaptureError(path, None, "the file is empty")
    told = by_content(head)
    if told is not None:
        return told.name
    known = by_extension(ext)
    if known is None or not known.by_extension:
        what = (
            f"is not {known.what}" if known else "has a format that cannot be told from its content"
        )
        raise CaptureError(
            path,
            None,
            f"{what} (give --input-format: {named_formats()})",
        )
    return known.name


def is_stream(path: str | os.PathLike[str]) -> bool:
    """True for ``-`` (standard input) and for a pipe, FIFO, socket or character device (such as
    ``/dev/stdin`` on a pipe): inputs that cannot be read twice or seeked."""
    if str(path) == STDIN:
        return True
    try:
        mode = os.stat(path).st_mode
    except OSError:
        return False
    return stat.S_ISFIFO(mode) or stat.S_ISCHR(mode) or stat.S_ISSOCK(mode)


class _Prefixed(io.RawIOBase):
    """A stream that gives ``head`` (bytes already read from ``rest``) and then ``rest``."""

    def __init__(self, head: bytes, rest: BinaryIO) -> None:
        super().__init__()
        self._head = memoryview(head)
        self._rest = rest

    def readable(self) -> bool:
        return True

    def close(self) -> None:
        """Close the stream and the file under it (standard input stays open)."""
        if not self.closed and self._rest is not sys.stdin.buffer:
            self._rest.close()
        super().close()

    def readinto(self, buffer: Any) -> int:
        out = memoryview(buffer).cast("B")
        if self._head.nbytes:
            n = min(len(out), self._head.nbytes)
            out[:n] = self._head[:n]
            self._head = self._head[n:]
            return n
        data = self._rest.read(len(out))
        out[: len(data)] = data
        return len(data)


def _read_head(f: BinaryIO, size: int) -> bytes:
    """Up to ``size`` bytes from ``f`` (a pipe may give them in several reads)."""
    parts: list[bytes] = []
    got = 0
    while got < size and (block := f.read(size - got)):
        parts.append(block)
        got += len(block)
    return b"".join(parts)


def _say_waiting(path: str | os.PathLike[str]) -> None:
    """On a terminal, say that a FIFO (which blocks until a writer opens it) or a terminal's
    standard input is waited for; Ctrl-C ends the wait (KeyboardInterrupt, exit 130)."""
    if not sys.stderr.isatty():
        return
    if str(path) == STDIN:
        if sys.stdin.isatty():
            print("wavecheck: reading the capture from standard input (a terminal: pipe a "
                  "file in; Ctrl-C to stop)", file=sys.stderr, flush=True)  # fmt: skip
        return
    with contextlib.suppress(OSError):
        if stat.S_ISFIFO(os.stat(path).st_mode):
            print(f"wavecheck: waiting for data on FIFO {path} (Ctrl-C to stop)",
                  file=sys.stderr, flush=True)  # fmt: skip


@record
class _Sniffed:
    """A stream whose first bytes told its format: ``stream`` gives them again, then the rest."""

    name: str
    spec: str
    fmt: Format
    stream: BinaryIO
    raw: BinaryIO

    def close(self) -> None:
        """Close the underlying file (never standard input)."""
        if self.raw is not sys.stdin.buffer:
            self.raw.close()


def _sniff_stream(path: str | os.PathLike[str], input_format: str | None) -> _Sniffed:
    """Open standard input or a pipe and tell its format from its first bytes (or
    ``input_format``) without losing them. Messages name ``path`` (``-`` is ``<stdin>``)."""
    name = "<stdin>" if str(path) == STDIN else str(path)
    _say_waiting(path)
    try:
        f: BinaryIO = sys.stdin.buffer if str(path) == STDIN else open(path, "rb")
    except OSError as err:
        raise CaptureError(name, None, f"cannot open: {err.strerror or err}") from None
    try:
        head = _read_head(f, _SNIFF_BYTES)
        if input_format:
            spec = input_format.strip()
            fmt = by_name(spec)
            if not head.strip():
                raise CaptureError(name, None, "the input is empty")
        else:
            spec = format_of(name, head, "")
            fmt = by_name(spec)
    except BaseException:
        if f is not sys.stdin.buffer:
            f.close()
        raise
    stream = io.BufferedReader(_Prefixed(head, f), buffer_size=1 << 20)
    return _Sniffed(name, spec, fmt, stream, f)


def _read_stream(sniffed: _Sniffed, request: Request) -> Capture:
    """Read a capture from standard input or a pipe (its format told: :func:`_sniff_stream`).

    A format that reads a stream (VCD, raw binary samples) reads it itself; any other (a
    ``.sr``, a zip, needs seeking) is copied to a temporary file first. Messages name the stream
    (``-`` is named ``<stdin>``).
    """
    name, fmt = sniffed.name, sniffed.fmt
    try:
        if fmt.streams:
            return _wired(fmt.read(replace(request, path=name, stream=sniffed.stream)))
        suffix = (*fmt.extensions, "." + sniffed.spec.partition(":")[0].strip().lower())[0]
        import shutil  # here: only a stream that needs seeking is spooled
        import tempfile

        with tempfile.TemporaryDirectory(prefix="wavecheck-stdin-") as tmp:
            spool = Path(tmp) / f"input{suffix}"
            with open(spool, "wb") as out:
                shutil.copyfileobj(sniffed.stream, out, 1 << 20)
            try:
                cap = fmt.read(replace(request, path=spool))
            except CaptureError as err:
                raise CaptureError(name, err.where, err.msg) from None
        cap.path = name
        cap.bit_source = None  # the spooled copy is gone
        return _wired(cap)
    finally:
        sniffed.close()


def _check_given(samplerate: Fraction | None, resolution_s: Fraction | None) -> None:
    """Refuse a sample rate or resolution no capture can have (before any reading)."""
    if samplerate is not None and samplerate <= 0:
        raise UsageError(f"--samplerate must be positive, got {samplerate} Hz")
    if resolution_s is not None and resolution_s < 0:
        raise UsageError(f"--resolution must not be negative, got {resolution_s} s")


def _wired(cap: Capture) -> Capture:
    """``cap`` with a reader of its vectors' bits: the file read again with pywellen, when the
    capture names one and its reader set none (:meth:`Capture.bit`)."""
    if cap.bit_reader is None and cap.bit_source is not None and cap.vectors:
        from wavecheck.capture.wellen import load_bit

        cap.bit_reader = functools.partial(load_bit, cap)
    return cap


def _file_request(
    path: str | os.PathLike[str], input_format: str | None, **values: Any
) -> tuple[Format, Request]:
    """The format of the capture file ``path`` (``input_format``, else told by its content and
    extension) and the read to make."""
    spec = input_format.strip() if input_format else detect_format(path)
    fmt = by_name(spec)
    if input_format and not (fmt.folder is not None and Path(path).is_dir()):
        detect_path_exists(path)
    return fmt, Request(path, spec, **values)


def open_capture(
    path: str | os.PathLike[str],
    *,
    samplerate: Fraction | None = None,
    resolution_s: Fraction | None = None,
    input_format: str | None = None,
    require_time: bool = True,
    channel_names: Sequence[str] | None = None,
) -> Capture:
    """Read a capture file into a :class:`Capture`; ``-`` (or a pipe such as ``/dev/stdin``)
    is read from standard input, its format detected without losing the bytes sniffed.

    Args:
        path: the capture.
        samplerate: sample rate in Hz, for files that lack one (a ``.sr`` without it, raw
            binary, csv) or to state a VCD's sampling; overrides the file's value with a note.
        resolution_s: the resolution (sample period) in seconds, overriding the derived one.
        input_format: a name of :data:`wavecheck.capture.formats.FORMATS` (``"sr"``,
            ``"vcd"``, ``"fst"``, ``"ghw"``, …) or a sigrok-cli input format, with its options
            (``"binary:numchannels=4"``); default: detected from content and extension. A VCD
            with options (``"vcd:downsample=10"``) is read through sigrok-cli, which has them.
        require_time: with False, a file that states no sample rate is read anyway, untimed
            (:attr:`Capture.time_known` False: counts in samples; for ``wavecheck info``).
        channel_names: names for raw binary samples' channels 0, 1, … (default sigrok-cli's
            ``0``, ``1``, …); other formats name their own channels.

    Raises:
        CaptureError: the file cannot be read (the message names the file and the place).
    """
    _check_given(samplerate, resolution_s)
    values: dict[str, Any] = {
        "samplerate": samplerate,
        "resolution_s": resolution_s,
        "require_time": require_time,
        "channel_names": channel_names,
    }
    if is_stream(path):
        sniffed = _sniff_stream(path, input_format)
        return _read_stream(sniffed, Request(sniffed.name, sniffed.spec, **values))
    fmt, request = _file_request(path, input_format, **values)
    return _wired(fmt.read(request))


def detect_path_exists(path: str | os.PathLike[str]) -> None:
    """Raise :class:`CaptureError` unless ``path`` is an existing, non-empty regular file."""
    p = Path(path)
    if not p.exists():
        raise CaptureError(path, None, "no such file")
    if p.is_dir():
        raise CaptureError(path, None, "is a folder, not a capture file")
    if p.stat().st_size == 0:
        raise CaptureError(path, None, "the file is empty")


def open_source(
    path: str | os.PathLike[str],
    *,
    samplerate: Fraction | None = None,
    resolution_s: Fraction | None = None,
    input_format: str | None = None,
    require_time: bool = True,
    channel_names: Sequence[str] | None = None,
    chunk_bytes: int | None = None,
) -> BlockSource:
    """A block source for any capture (as :func:`open_capture` reads it): a format with
    ``blocks`` in :data:`~wavecheck.capture.formats.FORMATS` (``.sr``, VCD, timed raw binary
    samples, FST), from a file or, where it reads a stream, from standard
    input or a pipe, is read block by block in bounded memory; every other input is read whole
    first and given as one block (:class:`~wavecheck.capture.blocks.MemorySource`).

    Raises:
        CaptureError: the file cannot be read (the message names the file and the place).
    """
    _check_given(samplerate, resolution_s)
    values: dict[str, Any] = {
        "samplerate": samplerate,
        "resolution_s": resolution_s,
        "require_time": require_time,
        "channel_names": channel_names,
        "chunk_bytes": chunk_bytes,
    }
    if is_stream(path):
        sniffed = _sniff_stream(path, input_format)
        request = Request(sniffed.name, sniffed.spec, **values)
        if sniffed.fmt.streams and sniffed.fmt.blocks is not None:
            try:
                source = sniffed.fmt.blocks(replace(request, stream=sniffed.stream))
            except BaseException:
                sniffed.close()
                raise
            if source is not None:
                return source
        whole = _read_stream(sniffed, request)
        return _one_block(whole, f"{whole.format} from {sniffed.name}")
    fmt, request = _file_request(path, input_format, **values)
    if fmt.blocks is not None:
        source = fmt.blocks(request)
        if source is not None:
            return source
    whole = _wired(fmt.read(request))
    return _one_block(whole, whole.format)


def _one_block(whole: Capture, what: str) -> BlockSource:
    """A capture its reader gives only whole (``what``: ``"ghw"``, ``"sr from <stdin>"``), as
    one block; its notes say so, once."""
    from wavecheck.capture.blocks import MemorySource

    whole.notes.append(
        f"read whole, then checked as one block ({what} is not read block by block): "
        "memory follows the capture's length"
    )
    return MemorySource(whole)
