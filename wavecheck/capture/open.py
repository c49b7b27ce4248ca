"""Open any capture: pick the reader from ``--input-format``, the file's content, or its extension.

``.sr``, VCD, FST and GHW (:mod:`wavecheck.capture.wellen`), raw binary samples
(:mod:`wavecheck.capture.binary`, sigrok-cli's ``-O binary``) and Saleae Logic 2 exports are read
natively; every other format sigrok-cli knows (csv, chronovu-la8, logicport, …) is converted by
sigrok-cli to a temporary ``.sr`` first.
"""

from __future__ import annotations

import contextlib
import io
import os
import shutil
import stat
import sys
import tempfile
from collections.abc import Sequence
from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path
from typing import TYPE_CHECKING, Any, BinaryIO

from wavecheck.capture.edges import Capture
from wavecheck.capture.saleae import HEADER as SALEAE_CSV_HEADER
from wavecheck.errors import CaptureError, UsageError

if TYPE_CHECKING:
    from wavecheck.capture.blocks import BlockSource

__all__ = [
    "STDIN",
    "detect_format",
    "format_of",
    "ghw_timescale",
    "is_stream",
    "open_capture",
    "open_source",
    "path_argument",
]

_ALIASES = {"srzip": "sr", "sigrok": "sr", "saleae": "saleae-csv", "saleae-binary": "saleae-bin"}
_BY_EXTENSION = {
    ".sr": "sr",
    ".vcd": "vcd",
    ".csv": "csv",
    ".kdt": "chronovu-la8",
    ".lpf": "logicport",
    ".fst": "fst",
    ".ghw": "ghw",
}
_ZIP_MAGIC = b"PK\x03\x04"
_GHW_MAGIC = b"GHDLwave\n"
#: Saleae Logic 2's binary export (wavecheck.capture.saleae_binary.MAGIC; not imported: numpy).
_SALEAE_MAGIC = b"<SALEAE>"
#: An FST file starts with its header block: type 0 and the block's length, 329, big-endian.
_FST_MAGIC = b"\x00" + (329).to_bytes(8, "big")
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
        from wavecheck.capture.saleae_binary import holds_export

        if holds_export(p):
            return "saleae-bin"
        raise CaptureError(path, None, "is a folder, not a capture file")
    try:
        with open(p, "rb") as f:
            head = f.read(_SNIFF_BYTES)
    except OSError as err:
        raise CaptureError(path, None, f"cannot open: {err.strerror or err}") from None
    return format_of(path, head, p.suffix.lower())


def format_of(path: str | os.PathLike[str], head: bytes, ext: str) -> str:
    """The format told by the first bytes ``head`` of a capture, else by its extension ``ext``.

    Raises:
        CaptureError: an empty input, or a format that cannot be told.
    """
    if not head.strip():
        raise CaptureError(path, None, "the file is empty")
    if head.startswith(_ZIP_MAGIC):
        return "sr"
    if head.removeprefix(b"\xef\xbb\xbf").startswith(SALEAE_CSV_HEADER):
        return "saleae-csv"
    if head.startswith(_SALEAE_MAGIC):
        return "saleae-bin"
    if head.startswith(_GHW_MAGIC):
        return "ghw"
    if head.startswith(_FST_MAGIC):
        return "fst"
    if head.lstrip().startswith(b"$"):
        return "vcd"
    if ext in ("", ".sr", ".vcd") or ext not in _BY_EXTENSION:
        kind = {".sr": "a sigrok .sr (zip) file", ".vcd": "a VCD file"}.get(ext)
        what = f"is not {kind}" if kind else "has a format that cannot be told from its content"
        raise CaptureError(
            path,
            None,
            f"{what} (give --input-format: sr, vcd, fst, ghw, saleae-csv, saleae-bin, "
            "binary:numchannels=N, or a sigrok-cli format such as csv, chronovu-la8, logicport)",
        )
    return _BY_EXTENSION[ext]


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


@dataclass
class _Sniffed:
    """A stream whose first bytes told its format: ``stream`` gives them again, then the rest."""

    name: str
    fmt: str
    kind: str
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
            fmt = input_format.strip()
            if not head.strip():
                raise CaptureError(name, None, "the input is empty")
        else:
            fmt = format_of(name, head, "")
    except BaseException:
        if f is not sys.stdin.buffer:
            f.close()
        raise
    kind = _ALIASES.get(fmt.split(":", 1)[0].lower(), fmt.split(":", 1)[0].lower())
    stream = io.BufferedReader(_Prefixed(head, f), buffer_size=1 << 20)
    return _Sniffed(name, fmt, kind, stream, f)


def _read_stream(
    sniffed: _Sniffed,
    *,
    samplerate: Fraction | None,
    resolution_s: Fraction | None,
    require_time: bool,
    channel_names: Sequence[str] | None,
) -> Capture:
    """Read a capture from standard input or a pipe (its format told: :func:`_sniff_stream`).

    A VCD and raw binary samples are read from the stream itself (raw samples one chunk at a
    time); a ``.sr`` (a zip, which needs seeking) or a sigrok-cli format is copied to a
    temporary file first. Messages name the stream (``-`` is named ``<stdin>``).
    """
    name, fmt, kind, stream = sniffed.name, sniffed.fmt, sniffed.kind, sniffed.stream
    try:
        if kind == "vcd" and ":" not in fmt:
            from wavecheck.capture.vcd import read_vcd

            return read_vcd(name, samplerate=samplerate, resolution_s=resolution_s, source=stream)
        if kind == "binary":
            from wavecheck.capture.binary import read_binary

            return read_binary(
                stream,
                fmt,
                name=name,
                samplerate=samplerate,
                resolution_s=resolution_s,
                channel_names=channel_names,
                require_time=require_time,
            )
        suffix = ".sr" if kind == "sr" else f".{kind}"
        with tempfile.TemporaryDirectory(prefix="wavecheck-stdin-") as tmp:
            spool = Path(tmp) / f"input{suffix}"
            with open(spool, "wb") as out:
                shutil.copyfileobj(stream, out, 1 << 20)
            try:
                cap = open_capture(
                    spool,
                    samplerate=samplerate,
                    resolution_s=resolution_s,
                    input_format=fmt,
                    require_time=require_time,
                )
            except CaptureError as err:
                raise CaptureError(name, err.where, err.msg) from None
        cap.path = name
        cap.bit_source = None  # the spooled copy is gone
        return cap
    finally:
        sniffed.close()


def _check_given(samplerate: Fraction | None, resolution_s: Fraction | None) -> None:
    """Refuse a sample rate or resolution no capture can have (before any reading)."""
    if samplerate is not None and samplerate <= 0:
        raise UsageError(f"--samplerate must be positive, got {samplerate} Hz")
    if resolution_s is not None and resolution_s < 0:
        raise UsageError(f"--resolution must not be negative, got {resolution_s} s")


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
        input_format: ``"sr"``, ``"vcd"``, ``"fst"``, ``"ghw"`` or a sigrok-cli input format (may carry options,
            ``"binary:numchannels=4"``); default: detected from content and extension. A VCD
            with options (``"vcd:downsample=10"``) is read through sigrok-cli, which has them.
        require_time: with False, a file that states no sample rate is read anyway, untimed
            (:attr:`Capture.time_known` False: counts in samples; for ``wavecheck info``).
        channel_names: names for raw binary samples' channels 0, 1, … (default sigrok-cli's
            ``0``, ``1``, …); other formats name their own channels.

    Raises:
        CaptureError: the file cannot be read (the message names the file and the place).
    """
    _check_given(samplerate, resolution_s)
    if is_stream(path):
        return _read_stream(
            _sniff_stream(path, input_format),
            samplerate=samplerate,
            resolution_s=resolution_s,
            require_time=require_time,
            channel_names=channel_names,
        )
    fmt = input_format.strip() if input_format else detect_format(path)
    name = _ALIASES.get(fmt.split(":", 1)[0].lower(), fmt.split(":", 1)[0].lower())
    if input_format and not (name == "saleae-bin" and Path(path).is_dir()):
        detect_path_exists(path)
    options = ":" in fmt
    if name == "sr" and options:
        raise UsageError(f"--input-format {fmt!r}: sr takes no options (give --input-format sr)")
    if name == "sr":
        from wavecheck.capture.sr import read_sr

        return read_sr(
            path, samplerate=samplerate, resolution_s=resolution_s, require_rate=require_time
        )
    if name == "binary":
        from wavecheck.capture.binary import read_binary

        return read_binary(
            path,
            fmt,
            samplerate=samplerate,
            resolution_s=resolution_s,
            channel_names=channel_names,
            require_time=require_time,
        )
    if name == "saleae-bin":
        from wavecheck.capture.saleae_binary import read_saleae_binary

        return read_saleae_binary(path, samplerate=samplerate, resolution_s=resolution_s)
    if name == "saleae-csv":
        from wavecheck.capture.saleae import read_saleae_csv

        return read_saleae_csv(path, samplerate=samplerate, resolution_s=resolution_s)
    if name in ("fst", "ghw"):
        if options and name == "fst":
            raise UsageError(f"--input-format {fmt!r}: fst takes no options")
        from wavecheck.capture.wellen import read_fst, read_wellen

        if name == "fst":
            return read_fst(path, samplerate=samplerate, resolution_s=resolution_s)
        return read_wellen(
            path,
            kind="ghw",
            samplerate=samplerate,
            resolution_s=resolution_s,
            timescale=ghw_timescale(fmt),
        )
    if name == "vcd" and not options:  # with options: sigrok-cli's VCD input (below)
        from wavecheck.capture.vcd import read_vcd

        return read_vcd(path, samplerate=samplerate, resolution_s=resolution_s)
    from wavecheck.capture.sigrokcli import read_with_sigrok

    return read_with_sigrok(
        path, fmt, samplerate=samplerate, resolution_s=resolution_s, require_time=require_time
    )


def ghw_timescale(fmt: str) -> Fraction | None:
    """The tick of a GHW file from ``--input-format ghw:timescale=1ps`` (None: not given).

    Raises:
        UsageError: another option, or a timescale that is not a positive time.
    """
    from wavecheck.units import parse_option

    _, _, options = fmt.partition(":")
    value = None
    for item in filter(None, options.split(":")):
        key, eq, text = item.partition("=")
        if key.strip() != "timescale" or not eq:
            raise UsageError(
                f"--input-format {fmt!r}: ghw takes one option, timescale=TIME (e.g. "
                "ghw:timescale=1ps: GHDL's --time-resolution of the run)"
            )
        value = parse_option(text.strip(), "--input-format ghw:timescale", "time")
        if value <= 0:
            raise UsageError(f"--input-format {fmt!r}: the timescale must be positive")
    return value


def path_argument(path: str | os.PathLike[str]) -> str:
    """``path`` as an argument of another program (fst2vcd, sigrok-cli): a relative path that
    starts with ``-`` gets ``./`` so that it is never read as an option (``-fother.fst`` is
    fst2vcd's ``-f other.fst``)."""
    text = os.fspath(path)
    return f"./{text}" if text.startswith("-") else text


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
    """A block source for any capture (as :func:`open_capture` reads it): ``.sr``, VCD and timed
    raw binary samples, from a file or from standard input or a pipe, and FST through
    ``fst2vcd``, are read block by block in bounded memory; every other input is read whole
    first and given as one block
    (:class:`~wavecheck.capture.blocks.MemorySource`).

    Raises:
        CaptureError: the file cannot be read (the message names the file and the place).
    """
    _check_given(samplerate, resolution_s)
    if is_stream(path):
        return _stream_source(
            _sniff_stream(path, input_format),
            samplerate=samplerate,
            resolution_s=resolution_s,
            require_time=require_time,
            channel_names=channel_names,
            chunk_bytes=chunk_bytes,
        )
    fmt = (input_format.strip() if input_format else detect_format(path)).lower()
    if fmt in ("sr", "srzip", "sigrok"):
        from wavecheck.capture.sr import DEFAULT_CHUNK_BYTES, SrBlocks

        return SrBlocks(
            path,
            samplerate=samplerate,
            resolution_s=resolution_s,
            chunk_bytes=chunk_bytes or DEFAULT_CHUNK_BYTES,
        )
    if fmt == "vcd":
        from wavecheck.capture.vcd.reader import DEFAULT_CHUNK_BYTES as VCD_CHUNK
        from wavecheck.capture.vcd.reader import VcdBlocks

        return VcdBlocks(
            path,
            samplerate=samplerate,
            resolution_s=resolution_s,
            chunk_bytes=chunk_bytes or VCD_CHUNK,
        )
    if fmt == "fst" and (tool := shutil.which("fst2vcd")):
        from wavecheck.capture.wellen import FstBlocks

        return FstBlocks(
            path,
            tool,
            samplerate=samplerate,
            resolution_s=resolution_s,
            chunk_bytes=chunk_bytes,
        )
    if fmt.split(":", 1)[0] == "binary" and input_format:
        from wavecheck.capture.binary import binary_blocks

        detect_path_exists(path)
        raw = binary_blocks(
            path,
            input_format.strip(),
            name=str(path),
            samplerate=samplerate,
            resolution_s=resolution_s,
            channel_names=channel_names,
            chunk_bytes=chunk_bytes,
        )
        if raw is not None:
            return raw
    whole = open_capture(
        path,
        samplerate=samplerate,
        resolution_s=resolution_s,
        input_format=input_format,
        require_time=require_time,
        channel_names=channel_names,
    )
    return _one_block(whole, whole.format)


def _stream_source(
    sniffed: _Sniffed,
    *,
    samplerate: Fraction | None,
    resolution_s: Fraction | None,
    require_time: bool,
    channel_names: Sequence[str] | None,
    chunk_bytes: int | None,
) -> BlockSource:
    """The block source of standard input or a pipe: a VCD or timed raw samples read block by
    block from the stream (never held whole); any other format read whole
    (:func:`_read_stream`), one block."""
    if sniffed.kind == "vcd" and ":" not in sniffed.fmt:
        from wavecheck.capture.vcd.reader import DEFAULT_CHUNK_BYTES as VCD_CHUNK
        from wavecheck.capture.vcd.reader import VcdBlocks

        try:
            return VcdBlocks(
                sniffed.name,
                samplerate=samplerate,
                resolution_s=resolution_s,
                chunk_bytes=chunk_bytes or VCD_CHUNK,
                source=sniffed.stream,
            )
        except BaseException:
            sniffed.close()
            raise
    if sniffed.kind == "binary":
        from wavecheck.capture.binary import binary_blocks

        try:
            raw = binary_blocks(
                sniffed.stream,
                sniffed.fmt,
                name=sniffed.name,
                samplerate=samplerate,
                resolution_s=resolution_s,
                channel_names=channel_names,
                chunk_bytes=chunk_bytes,
            )
        except BaseException:
            sniffed.close()
            raise
        if raw is not None:
            return raw
    whole = _read_stream(
        sniffed,
        samplerate=samplerate,
        resolution_s=resolution_s,
        require_time=require_time,
        channel_names=channel_names,
    )
    return _one_block(whole, f"{whole.format} from {sniffed.name}")


def _one_block(whole: Capture, what: str) -> BlockSource:
    """A capture its reader gives only whole (``what``: ``"ghw"``, ``"sr from <stdin>"``), as
    one block; its notes say so, once."""
    from wavecheck.capture.blocks import MemorySource

    whole.notes.append(
        f"read whole, then checked as one block ({what} is not read block by block): "
        "memory follows the capture's length"
    )
    return MemorySource(whole)
