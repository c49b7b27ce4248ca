"""VCD header and what both VCD readers share: declarations, ``$timescale``, sigrok's
``$comment`` sample rate, the layout of the 1-bit signals the body is read into, and the final
assembly of a :class:`~wavecheck.capture.edges.Capture` from each signal's edges.

The readers are :mod:`wavecheck.capture.vcd.reader` (the fast one) and
:mod:`wavecheck.capture.vcd.reference` (the simple one the tests compare it with).
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass, field
from fractions import Fraction
from typing import TYPE_CHECKING, BinaryIO

import numpy as np

from wavecheck.capture.common import (
    ANALYZER_WRITERS,
    analyzer_writer,
    resolution_of,
    stated_samplerate,
)
from wavecheck.capture.edges import Capture, Channel, Vector
from wavecheck.errors import CaptureError
from wavecheck.timebase import Timebase

if TYPE_CHECKING:
    import numpy.typing as npt

__all__ = [
    "SCALAR_VALUES",
    "Layout",
    "SignalEdges",
    "VarDecl",
    "ANALYZER_WRITERS",
    "VcdHeader",
    "analyzer_writer",
    "build_capture",
    "decode_name",
    "header_timebase",
    "layout_of",
    "not_utf8_notes",
    "open_vcd",
    "parse_header",
    "read_header",
    "resolution_of",
    "stated_samplerate",
    "vector_of",
    "vectors_of",
]

_MAX_HEADER_BYTES = 64 << 20
#: Most variables a header may declare: a stepper's dump has a few, a whole FPGA's tens of
#: thousands; a million costs minutes and a gigabyte before any check (issue 27).
MAX_VARS = 250_000
_MAX_ID_LEN = 8
_TIMESCALE_RE = re.compile(r"^(\d+)\s*(s|ms|us|ns|ps|fs|as|zs)$")
_END_RE = re.compile(rb"\$end(\s|$)")
_NON_SIGNAL_TYPES = {"real", "realtime", "shortreal", "event", "string"}
_NOT_VECTORS = {"integer", "parameter"}
#: Scalar value character → 0, 1, 2 (unknown: x u w -) or 3 (z).
SCALAR_VALUES = {
    "0": 0, "1": 1, "l": 0, "h": 1, "x": 2, "u": 2, "w": 2, "-": 2, "z": 3,
}  # fmt: skip


@dataclass
class VarDecl:
    """One ``$var`` of the header."""

    type: str
    size: int
    id_code: str
    reference: str  # with its bit select, e.g. "data[3]"
    scope: tuple[str, ...]
    line: int

    @property
    def full_name(self) -> str:
        return ".".join((*self.scope, self.reference))


@dataclass
class VcdHeader:
    """What the header declares; ``body_offset`` is the byte after ``$enddefinitions $end``.

    ``version`` is the ``$version`` text (the writing program), ``notes`` what parsing assumed
    (names that are not UTF-8).
    """

    timescale: Timebase | None
    timescale_text: str | None
    vars: list[VarDecl]
    comments: list[str]
    body_offset: int
    body_line: int
    version: str | None = None
    notes: list[str] = field(default_factory=list)


class _Lines:
    """Line numbers of increasing offsets in ``data``, counted incrementally (linear overall)."""

    def __init__(self, data: bytes) -> None:
        self.data, self.pos, self.line = data, 0, 1

    def at(self, offset: int) -> int:
        if offset < self.pos:  # not expected; stay correct
            return self.data.count(b"\n", 0, offset) + 1
        self.line += self.data.count(b"\n", self.pos, offset)
        self.pos = offset
        return self.line


def not_utf8_notes(not_utf8: list[str]) -> list[str]:
    """The note for the names :func:`decode_name` read as latin-1 (none when there are none)."""
    if not not_utf8:
        return []
    listed = ", ".join(repr(n) for n in not_utf8[:5])
    return [
        f"{len(not_utf8)} name(s) are not valid UTF-8 and were read as latin-1: "
        f"{listed}" + (" …" if len(not_utf8) > 5 else "")
    ]


def decode_name(raw: bytes, not_utf8: list[str]) -> str:
    """A name as text: UTF-8 (as sigrok-cli and GTKWave write it), else latin-1 (noted)."""
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError:
        text = raw.decode("latin-1")
        not_utf8.append(text)
        return text


def parse_header(path: str | os.PathLike[str], data: bytes) -> VcdHeader:
    """Parse the declarations at the start of ``data`` (which must contain the whole header).

    Time and memory are linear in the header: tokens are taken one at a time and line numbers
    are counted on from the previous token. Names (references, scopes) are decoded as UTF-8,
    falling back to latin-1 with a note; id codes and keywords are bytes read as latin-1.

    Raises:
        CaptureError: with the line number, for a bad timescale, ``$var`` or missing
            ``$enddefinitions``.
    """
    tokens = re.finditer(rb"\S+", data)
    lines = _Lines(data)
    scope: list[str] = []
    decls: list[VarDecl] = []
    comments: list[str] = []
    version: str | None = None
    not_utf8: list[str] = []
    timescale: Timebase | None = None
    timescale_text: str | None = None

    def section(start: re.Match[bytes], line: int) -> tuple[list[bytes], int]:
        body: list[bytes] = []
        for m in tokens:
            if m.group() == b"$end":
                return body, m.end()
            body.append(m.group())
        raise CaptureError(
            path,
            f"line {line}",
            f"{start.group().decode('latin-1')[:40]} without $end (the header is cut off)",
        )

    def latin(body: list[bytes]) -> list[str]:
        return [t.decode("latin-1") for t in body]

    for tok in tokens:
        word = tok.group().decode("latin-1")
        line = lines.at(tok.start())
        where = f"line {line}"
        if word == "$enddefinitions":
            _, end = section(tok, line)
            notes = not_utf8_notes(not_utf8)
            return VcdHeader(
                timescale, timescale_text, decls, comments, end, lines.at(end), version, notes
            )
        if word == "$timescale":
            body_b, _ = section(tok, line)
            body = latin(body_b)
            text = "".join(body)
            match = _TIMESCALE_RE.match(text)
            if not match or int(match.group(1)) == 0:
                raise CaptureError(
                    path,
                    where,
                    f"bad $timescale {' '.join(body)[:60]!r} (write e.g. '$timescale 1 ns $end')",
                )
            tb = Timebase.from_timescale(int(match.group(1)), match.group(2))
            if not Fraction(1, 10**15) <= tb.tick_s <= 100:
                raise CaptureError(path, where, f"$timescale {text} is outside 1 fs … 100 s")
            timescale, timescale_text = tb, f"{match.group(1)} {match.group(2)}"
        elif word == "$scope":
            body_b, _ = section(tok, line)
            scope.append(decode_name(body_b[-1], not_utf8) if body_b else "")
        elif word == "$upscope":
            section(tok, line)
            if scope:
                scope.pop()
        elif word == "$var":
            body_b, _ = section(tok, line)
            body = latin(body_b[:3])
            if len(body_b) < 4 or not re.fullmatch(r"[0-9]+", body[1]) or int(body[1]) < 1:
                raise CaptureError(
                    path,
                    where,
                    f"bad $var {' '.join(latin(body_b))[:80]!r} (expected '$var wire 1 ! name $end')",
                )
            id_code = body[2]
            if len(id_code) > _MAX_ID_LEN:
                raise CaptureError(
                    path, where, f"id code {id_code[:40]!r} is longer than {_MAX_ID_LEN} characters"
                )
            ref = body_b[3:]
            # "data [3]" → "data[3]"; sigrok's "STEP (Y axis)" keeps its spaces
            raw = (
                b" ".join(ref[:-1]) + ref[-1]
                if len(ref) > 1 and ref[-1].startswith(b"[")
                else b" ".join(ref)
            )
            decls.append(
                VarDecl(
                    body[0], int(body[1]), id_code, decode_name(raw, not_utf8), tuple(scope), line
                )
            )
        elif word in ("$comment", "$date", "$version"):
            body_b, _ = section(tok, line)
            text = decode_name(b" ".join(body_b), [])
            if word == "$comment":
                comments.append(text)
            elif word == "$version":
                version = text
        elif word.startswith("$"):
            section(tok, line)  # $attrbegin and friends: ignored
        else:
            raise CaptureError(
                path, where, f"unexpected {word[:40]!r} in the header (is this a VCD file?)"
            )
    raise CaptureError(
        path, "header", "no $enddefinitions (the file is cut off in its header, or not a VCD)"
    )


def open_vcd(path: str | os.PathLike[str]) -> BinaryIO:
    """Open ``path`` for reading in binary mode.

    Raises:
        CaptureError: missing file, a folder, or not readable.
    """
    try:
        return open(path, "rb")
    except IsADirectoryError:
        raise CaptureError(path, None, "is a folder, not a capture file") from None
    except FileNotFoundError:
        raise CaptureError(path, None, "no such file") from None
    except OSError as err:
        raise CaptureError(path, None, f"cannot open: {err.strerror}") from None


def read_header(path: str | os.PathLike[str], f: BinaryIO) -> tuple[VcdHeader, bytes]:
    """Read until ``$enddefinitions ... $end``; return the header and the body bytes read so far.

    Linear in the header: each block is searched once (with a few bytes of overlap), and at most
    ``_MAX_HEADER_BYTES`` plus one block is held.
    """
    data = bytearray()
    end = -1
    pos = -1
    while True:
        block = f.read(1 << 20)
        before = len(data)
        data += block
        if pos < 0:
            pos = data.find(b"$enddefinitions", max(0, before - 15))
        if pos >= 0:
            match = _END_RE.search(data, max(pos + 15, before - 5))
            if match is not None and (match.end() < len(data) or not block):
                end = match.start() + 4
                break
        if not block or len(data) > _MAX_HEADER_BYTES:
            end = len(data)
            break
    if not data.strip():
        raise CaptureError(path, None, "the file is empty (no VCD header)")
    whole = bytes(data)
    del data
    declared = whole.count(b"$var", 0, end)
    if declared > MAX_VARS:
        raise CaptureError(
            path,
            None,
            f"declares {declared:,} variables, more than the {MAX_VARS:,} wavecheck reads (a "
            "logic analyzer has at most a few hundred channels): dump only the step "
            "generator's scope ($dumpvars with a depth and a scope)",
        )
    header = parse_header(path, whole[:end])
    return header, whole[header.body_offset :]


@dataclass
class Layout:
    """The 1-bit channels and skipped signals of a header."""

    names: list[str]
    decls: list[VarDecl]  # first declaration of each channel
    ids: list[str]
    vector_ids: set[str]
    skipped: dict[str, str]
    notes: list[str]
    aliases: dict[str, str]


def layout_of(header: VcdHeader) -> Layout:
    """The channels a reader makes of ``header``: unique names, aliases, skipped non-wires."""
    first: dict[str, VarDecl] = {}
    aliases: dict[str, list[str]] = {}
    for d in header.vars:
        if d.id_code in first:
            aliases.setdefault(d.id_code, []).append(d.full_name)
        else:
            first[d.id_code] = d
    scalar = [d for d in first.values() if d.size == 1 and d.type not in _NON_SIGNAL_TYPES]
    others = [d for d in first.values() if not (d.size == 1 and d.type not in _NON_SIGNAL_TYPES)]
    ids_by_short: dict[str, set[str]] = {}
    for d in header.vars:
        ids_by_short.setdefault(d.reference, set()).add(d.id_code)
    names: list[str] = []
    used: set[str] = set()
    next_k: dict[str, int] = {}  # per base name: the next "#k" to try (linear, not k² probes)
    for d in scalar:
        name = d.reference if len(ids_by_short[d.reference]) == 1 else d.full_name
        if name in used:
            base, k = name, next_k.get(name, 2)
            while f"{base}#{k}" in used:
                k += 1
            name, next_k[base] = f"{base}#{k}", k + 1
        used.add(name)
        names.append(name)
    skipped: dict[str, str] = {}
    notes: list[str] = list(header.notes)
    decls_by_id: dict[str, list[VarDecl]] = {}
    for d in header.vars:
        decls_by_id.setdefault(d.id_code, []).append(d)
    for d in others:
        if d.type in ("real", "realtime", "shortreal"):
            what = "a real"
        elif d.type in ("event", "string"):
            what = f"an {d.type}" if d.type == "event" else "a string"
        else:
            what = f"a {d.size}-bit {'integer' if d.type == 'integer' else 'vector'}"
        for d2 in decls_by_id[d.id_code]:
            skipped.setdefault(d2.full_name, what)
            if len(ids_by_short[d2.reference]) == 1 or d2.reference not in used:
                skipped.setdefault(d2.reference, what)
                bare = d2.reference.split("[", 1)[0]
                if bare and bare not in used:
                    skipped.setdefault(bare, what)
    if others:
        listed = ", ".join(d.full_name for d in others[:10])
        more = f" and {len(others) - 10} more" if len(others) > 10 else ""
        notes.append(
            f"skipped {len(others)} signal(s) that are not 1-bit wires "
            f"(vectors, integers, reals): {listed}{more}"
        )
    scalar_ids = {d.id_code for d in scalar}
    n_alias = sum(len(v) for k, v in aliases.items() if k in scalar_ids)
    alias_names: dict[str, str] = {}
    by_id = {d.id_code: name for d, name in zip(scalar, names, strict=True)}
    for d in header.vars:
        target = by_id.get(d.id_code)
        if target is None:
            continue
        for other in (d.full_name, d.reference):
            if other not in used and (other != d.reference or len(ids_by_short[other]) == 1):
                alias_names.setdefault(other, target)
    if n_alias:
        notes.append(f"{n_alias} declaration(s) alias a channel declared earlier (same id code)")
    return Layout(
        names,
        scalar,
        [d.id_code for d in scalar],
        {d.id_code for d in others},
        skipped,
        notes,
        alias_names,
    )


def header_timebase(header: VcdHeader, notes: list[str]) -> Timebase:
    """The header's ``$timescale``, or 1 s (with a note) when it has none."""
    if header.timescale is None:
        notes.append("no $timescale; assumed 1 s per tick as the VCD standard says")
        return Timebase(Fraction(1))
    return header.timescale


_RANGE = re.compile(r"^(.*?)\s*\[\s*(-?\d+)\s*:\s*(-?\d+)\s*\]$")


def vector_of(d: VarDecl) -> Vector | None:
    """The bit vector ``d`` declares (a wire or reg wider than 1 bit), named by its full name
    without the range (``tb.stout`` for ``stout [3:0]``) with its declared range; None for
    anything else."""
    if d.size <= 1 or d.type in _NON_SIGNAL_TYPES or d.type in _NOT_VECTORS:
        return None
    m = _RANGE.match(d.full_name)
    if m and abs(int(m.group(2)) - int(m.group(3))) + 1 == d.size:
        return Vector(d.size, int(m.group(2)), int(m.group(3)), m.group(1))
    return Vector(d.size, d.size - 1, 0, d.full_name)


def vectors_of(header: VcdHeader) -> dict[str, Vector]:
    """The header's bit vectors by name (:func:`vector_of`)."""
    out: dict[str, Vector] = {}
    for d in header.vars:
        v = vector_of(d)
        if v is not None:
            out.setdefault(v.key, v)
    return out


@dataclass
class SignalEdges:
    """What a reader found for one 1-bit channel; times in ticks of the timescale."""

    initial: int  # first known level (0 when never known)
    known_from: int | None  # tick of the first known value; None: never known
    edges: npt.NDArray[np.int64]  # ticks where the known level changes
    xz_times: npt.NDArray[np.int64]  # ticks where a known level turns x/z
    xz_ends: npt.NDArray[np.int64]  # for each, the tick a known value comes back (or NEVER)

    def channel(self, name: str, index: int, end: int) -> Channel:
        """The capture's channel (a never-known one is unknown up to ``end``, the last tick)."""
        known = self.known_from is not None
        return Channel(
            name=name,
            index=index,
            initial=self.initial if known else 0,
            edges=self.edges,
            known_from=self.known_from if self.known_from is not None else end,
            xz_times=self.xz_times,
            xz_ends=self.xz_ends,
            never_known=not known,
        )


def build_capture(
    path: str | os.PathLike[str],
    header: VcdHeader,
    layout: Layout,
    tb: Timebase,
    signals: list[SignalEdges],
    first_time: int | None,
    last_time: int | None,
    pre_time: bool,
    notes: list[str],
    samplerate: Fraction | None,
    resolution_s: Fraction | None,
) -> Capture:
    """Assemble the capture: ``signals`` in ``layout.ids`` order, ``first_time``/``last_time``
    the first and last ``#`` timestamps, ``pre_time`` whether changes came before the first.

    Raises:
        CaptureError: no timestamp after the header; a bad resolution.
    """
    if last_time is None or first_time is None:
        raise CaptureError(
            path,
            f"line {header.body_line}",
            "no timestamps after the header (the file is cut off?)",
        )
    start = 0 if pre_time else first_time
    end = last_time
    if not layout.ids:
        notes.append("no 1-bit signals in this file")
    res, rate = resolution_of(
        path, tb, header.comments, samplerate, resolution_s, notes, header.version
    )
    channels = [
        sig.channel(name, i, end)
        for i, (name, sig) in enumerate(zip(layout.names, signals, strict=True))
    ]
    never = [
        name for name, sig in zip(layout.names, signals, strict=True) if sig.known_from is None
    ]
    if never:
        notes.append(f"{len(never)} channel(s) never have a known level: {', '.join(never[:10])}")
    return Capture(
        path=str(path),
        format="vcd",
        timebase=tb,
        resolution_ticks=res,
        samplerate_hz=rate,
        start=start,
        end=end,
        channels=channels,
        notes=notes,
        skipped=layout.skipped,
        aliases=layout.aliases,
    )
