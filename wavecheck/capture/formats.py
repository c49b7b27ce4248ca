"""The capture formats wavecheck knows, one record each: its name and other spellings, how its
content is recognised (magic bytes, a test of the first bytes), its extensions, how it is read
whole (``read``) and, where it can be, block by block (``blocks``).

A new format is one record here and its reader module; :mod:`wavecheck.capture.open` only walks
this table. A format wavecheck recognises but cannot read (LXT2, a Saleae session) is a record
whose ``read`` refuses it by name with the way to a format that is read.
"""

from __future__ import annotations

import functools
import os
import re
from collections.abc import Callable, Sequence
from fractions import Fraction
from typing import TYPE_CHECKING, BinaryIO

from wavecheck.capture.edges import Capture
from wavecheck.errors import CaptureError, UsageError
from wavecheck.record import record

if TYPE_CHECKING:
    from wavecheck.capture.blocks import BlockSource

__all__ = [
    "FORMATS",
    "Format",
    "Request",
    "by_content",
    "by_extension",
    "by_folder",
    "by_name",
    "ghw_timescale",
]

ZIP_MAGIC = b"PK\x03\x04"


@record(frozen=True)
class Request:
    """One read: the capture (a path, or ``stream`` named ``path``), the format as given with its
    options (``binary:numchannels=4``), and the user's values."""

    path: str | os.PathLike[str]
    spec: str
    samplerate: Fraction | None = None
    resolution_s: Fraction | None = None
    require_time: bool = True
    channel_names: Sequence[str] | None = None
    chunk_bytes: int | None = None
    stream: BinaryIO | None = None

    @property
    def options(self) -> str:
        """What follows the format's name (``numchannels=4``; empty: none)."""
        return self.spec.partition(":")[2]


@record(frozen=True)
class Format:
    """One capture format.

    Attributes:
        name: the ``--input-format`` name.
        what: the format in words, for messages (``a sigrok .sr (zip) file``).
        read: reads a :class:`Request` whole (from a file; from ``stream`` when ``streams``).
        magic: the first bytes of every such file (any of them).
        sniff: a test of the first bytes beyond ``magic`` (both must hold when both are given).
        extensions: the file name endings (lower case) of the format.
        by_extension: the extension tells the format when the content does not (a CSV; an FST
            whose first block is not its header, as GHDL writes).
        blocks: a block source for a :class:`Request` (None from it: read whole, one block).
        streams: ``read`` and ``blocks`` take a stream; other formats are spooled to a file.
        aliases: other ``--input-format`` spellings.
        options: ``--input-format NAME:OPTIONS`` is accepted; ``"sigrok"``: with options
            the format is read by sigrok-cli's input of that name, which has them.
        folder: tells whether a folder holds a capture of this format (None: never one).
        readable: False for a format recognised only to be refused by name (its ``read``
            raises the reason and the way to a format that is read).
    """

    name: str
    what: str
    read: Callable[[Request], Capture]
    magic: tuple[bytes, ...] = ()
    sniff: Callable[[bytes], bool] | None = None
    extensions: tuple[str, ...] = ()
    by_extension: bool = False
    blocks: Callable[[Request], BlockSource | None] | None = None
    streams: bool = False
    aliases: tuple[str, ...] = ()
    options: bool | str = True
    folder: Callable[[str | os.PathLike[str]], bool] | None = None
    readable: bool = True

    def told_by(self, head: bytes) -> bool:
        """True when the first bytes ``head`` are this format's."""
        if not (self.magic or self.sniff):
            return False
        if self.magic and not head.startswith(self.magic):
            return False
        return self.sniff is None or self.sniff(head)


# -- the readers, each behind its record (imported when used: start-up stays short) -------------


def _read_sr(r: Request) -> Capture:
    from wavecheck.capture.sr import read_sr

    return read_sr(
        r.path, samplerate=r.samplerate, resolution_s=r.resolution_s, require_rate=r.require_time
    )


def _sr_blocks(r: Request) -> BlockSource:
    from wavecheck.capture.sr import DEFAULT_CHUNK_BYTES, SrBlocks

    return SrBlocks(
        r.path,
        samplerate=r.samplerate,
        resolution_s=r.resolution_s,
        chunk_bytes=r.chunk_bytes or DEFAULT_CHUNK_BYTES,
    )


def _read_vcd(r: Request) -> Capture:
    from wavecheck.capture.vcd import read_vcd

    return read_vcd(r.path, samplerate=r.samplerate, resolution_s=r.resolution_s, source=r.stream)


def _vcd_blocks(r: Request) -> BlockSource | None:
    from wavecheck.capture.vcd.reader import DEFAULT_CHUNK_BYTES, VcdBlocks

    return VcdBlocks(
        r.path,
        samplerate=r.samplerate,
        resolution_s=r.resolution_s,
        chunk_bytes=r.chunk_bytes or DEFAULT_CHUNK_BYTES,
        source=r.stream,
    )


def _read_fst(r: Request) -> Capture:
    from wavecheck.capture.wellen import read_fst

    return read_fst(r.path, samplerate=r.samplerate, resolution_s=r.resolution_s)


def _fst_blocks(r: Request) -> BlockSource | None:
    from wavecheck.capture.fst import FstUnsupported
    from wavecheck.capture.fst_source import SLICE_CHANGES, FstNativeBlocks

    try:
        return FstNativeBlocks(
            r.path, samplerate=r.samplerate, resolution_s=r.resolution_s,
            slice_changes=r.chunk_bytes or SLICE_CHANGES,  # the tests' tiny blocks
        )  # fmt: skip
    except FstUnsupported:
        pass  # FastLZ packing: GTKWave's fst2vcd, else the whole file with pywellen
    import shutil  # here: it imports bz2 and lzma, which a check of another format never needs

    tool = shutil.which("fst2vcd")
    if tool is None:
        return None
    from wavecheck.capture.wellen import FstBlocks

    return FstBlocks(
        r.path,
        tool,
        samplerate=r.samplerate,
        resolution_s=r.resolution_s,
        chunk_bytes=r.chunk_bytes,
    )


def _read_ghw(r: Request) -> Capture:
    from wavecheck.capture.wellen import read_wellen

    return read_wellen(
        r.path,
        kind="ghw",
        samplerate=r.samplerate,
        resolution_s=r.resolution_s,
        timescale=ghw_timescale(r.spec),
    )


def _read_binary(r: Request) -> Capture:
    from wavecheck.capture.binary import read_binary

    return read_binary(
        r.stream if r.stream is not None else r.path,
        r.spec,
        name=str(r.path),
        samplerate=r.samplerate,
        resolution_s=r.resolution_s,
        channel_names=r.channel_names,
        require_time=r.require_time,
    )


def _binary_blocks(r: Request) -> BlockSource | None:
    from wavecheck.capture.binary import binary_blocks

    return binary_blocks(
        r.stream if r.stream is not None else r.path,
        r.spec,
        name=str(r.path),
        samplerate=r.samplerate,
        resolution_s=r.resolution_s,
        channel_names=r.channel_names,
        chunk_bytes=r.chunk_bytes,
    )


def _read_saleae_csv(r: Request) -> Capture:
    from wavecheck.capture.saleae import read_saleae_csv

    return read_saleae_csv(r.path, samplerate=r.samplerate, resolution_s=r.resolution_s)


def _read_saleae_bin(r: Request) -> Capture:
    from wavecheck.capture.saleae_binary import read_saleae_binary

    return read_saleae_binary(r.path, samplerate=r.samplerate, resolution_s=r.resolution_s)


def _holds_saleae_export(folder: str | os.PathLike[str]) -> bool:
    from wavecheck.capture.saleae_binary import holds_export

    return holds_export(folder)


def _read_sigrok(r: Request) -> Capture:
    from wavecheck.capture.sigrokcli import read_with_sigrok

    return read_with_sigrok(
        r.path,
        r.spec,
        samplerate=r.samplerate,
        resolution_s=r.resolution_s,
        require_time=r.require_time,
    )


def _refuse(reason: str) -> Callable[[Request], Capture]:
    """A ``read`` that refuses the file with ``reason`` (a format recognised, not read)."""

    def refuse(r: Request) -> Capture:
        raise CaptureError(r.path, None, reason)

    return refuse


def _saleae_csv_head(head: bytes) -> bool:
    from wavecheck.capture.saleae import HEADER

    return head.removeprefix(b"\xef\xbb\xbf").startswith(HEADER)


def _saleae1_csv_head(head: bytes) -> bool:
    from wavecheck.capture.saleae import HEADER_1X

    return head.removeprefix(b"\xef\xbb\xbf").startswith(HEADER_1X)


def _vcd_head(head: bytes) -> bool:
    return head.lstrip().startswith(b"$")


#: A Saleae Logic 2 session (``.sal``) is a zip of ``meta.json`` and ``digital-N.bin``.
_SESSION_MEMBER = re.compile(rb"meta\.json|digital-\d+\.bin")


def _session_head(head: bytes) -> bool:
    return _SESSION_MEMBER.search(head) is not None


#: The formats, in the order their content is tested: the more particular first (a Saleae
#: session before sigrok's .sr, both zips).
FORMATS: tuple[Format, ...] = (
    Format(
        "saleae-session", "a Saleae Logic 2 session (.sal)",
        _refuse(
            "a Saleae Logic 2 session (.sal: Saleae's internal format, not documented); in Logic 2 "
            "use File > Export Raw Data (binary or CSV) and give wavecheck that export"
        ),
        magic=(ZIP_MAGIC,), sniff=_session_head, extensions=(".sal",), by_extension=True,
        options=False,
        readable=False,
    ),
    Format(
        "sr", "a sigrok .sr (zip) file", _read_sr, magic=(ZIP_MAGIC,), extensions=(".sr",),
        blocks=_sr_blocks, aliases=("srzip", "sigrok"), options=False,
    ),
    Format(
        "saleae-csv", "a Saleae Logic 2 CSV export", _read_saleae_csv, sniff=_saleae_csv_head,
        aliases=("saleae",),
    ),
    Format(
        "saleae1-csv", "a Saleae Logic 1.x CSV export", _read_saleae_csv, sniff=_saleae1_csv_head,
        aliases=("saleae1",),
    ),
    Format(
        "saleae-bin", "a Saleae Logic 2 binary export", _read_saleae_bin, magic=(b"<SALEAE>",),
        aliases=("saleae-binary",), folder=_holds_saleae_export,
    ),
    Format("ghw", "a GHDL waveform (GHW)", _read_ghw, magic=(b"GHDLwave\n",), extensions=(".ghw",),
           by_extension=True),
    # an FST file starts with its header block: type 0 and the block's length, 329, big-endian
    Format(
        "fst", "an FST file", _read_fst, magic=(b"\x00" + (329).to_bytes(8, "big"),),
        extensions=(".fst",), by_extension=True, blocks=_fst_blocks, options=False,
    ),
    # LXT2 starts with its header id 0x1380 and version 1, big-endian (GTKWave's lxt2_write.h)
    Format(
        "lxt2", "an LXT2 file",
        _refuse(
            "an LXT2 file (GTKWave's older compressed dump), not a VCD: convert it with GTKWave's "
            "lxt2vcd (lxt2vcd FILE > FILE.vcd), or dump VCD or FST (vvp without -lxt2, or -fst)"
        ),
        magic=(b"\x13\x80\x00\x01",), extensions=(".lxt2", ".lx2"), by_extension=True,
        options=False,
        readable=False,
    ),
    # LXT (the first) starts with its header id 0x0138 and version 4 (iverilog's vvp -lxt)
    Format(
        "lxt", "an LXT file",
        _refuse(
            "an LXT file (GTKWave's oldest compressed dump), not a VCD: dump VCD or FST instead "
            "(vvp without -lxt, or vvp -fst)"
        ),
        magic=(b"\x01\x38\x00\x04",), extensions=(".lxt",), by_extension=True, options=False,
        readable=False,
    ),
    Format(
        "vcd", "a VCD file", _read_vcd, sniff=_vcd_head, extensions=(".vcd",), blocks=_vcd_blocks,
        streams=True, options="sigrok",  # vcd:downsample=10 and the like
    ),
    Format(
        "binary", "raw binary samples", _read_binary, blocks=_binary_blocks, streams=True,
    ),
    Format("csv", "a CSV file", _read_sigrok, extensions=(".csv",), by_extension=True),
    Format(
        "chronovu-la8", "a ChronoVu LA8 file", _read_sigrok, extensions=(".kdt",),
        by_extension=True,
    ),
    Format(
        "logicport", "a LogicPort file", _read_sigrok, extensions=(".lpf",), by_extension=True,
    ),
)  # fmt: skip

#: Any other name is one of sigrok-cli's input formats, converted by sigrok-cli.
SIGROK = Format("sigrok-cli", "a sigrok-cli input format", _read_sigrok)


@functools.cache
def _names() -> dict[str, Format]:
    out: dict[str, Format] = {}
    for f in FORMATS:
        for n in (f.name, *f.aliases):
            out[n] = f
    return out


def by_name(spec: str) -> Format:
    """The format an ``--input-format`` value names (any other name: sigrok-cli's).

    Raises:
        UsageError: options given to a format that takes none.
    """
    fmt = _names().get(spec.partition(":")[0].strip().lower(), SIGROK)
    if ":" in spec and fmt.options == "sigrok":
        return SIGROK
    if ":" in spec and not fmt.options:
        raise UsageError(
            f"--input-format {spec!r}: {fmt.name} takes no options (give --input-format {fmt.name})"
        )
    return fmt


def by_content(head: bytes) -> Format | None:
    """The format the first bytes ``head`` of a capture tell, or None."""
    return next((f for f in FORMATS if f.told_by(head)), None)


def by_folder(folder: str | os.PathLike[str]) -> Format | None:
    """The format of the capture the folder ``folder`` holds, or None."""
    return next((f for f in FORMATS if f.folder is not None and f.folder(folder)), None)


def by_extension(ext: str) -> Format | None:
    """The format whose files end in ``ext`` (``.vcd``), or None."""
    return next((f for f in FORMATS if ext in f.extensions), None)


def named_formats() -> str:
    """The ``--input-format`` names, for a message's hint."""
    own = [f.name for f in FORMATS if f.readable and f.read is not _read_sigrok]
    via = [f.name for f in FORMATS if f.read is _read_sigrok]
    own[own.index("binary")] = "binary:numchannels=N"
    return f"{', '.join(own)}, or a sigrok-cli format such as {', '.join(via)}"


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
