"""The header of a GHDL GHW file, read here before pywellen reads the value changes.

Why a reader of our own for the header: pywellen (0.25) gives neither the declared range of a
vector (``std_logic_vector(0 to 3)`` and ``(5 downto 2)`` both come out as 4 bits with the left
one first) nor a Python exception on every malformed header (some become a Rust panic, a huge
allocation or an abort). :func:`read_ghw_header` walks the header once, with every count and
index checked against the file, and returns each bit vector's declared ``(left, right)`` under
the name pywellen gives it; anything it cannot read is a :class:`CaptureError` naming the byte.

The layout is GHDL's (``libghw.c``, ``grt-waves.adb``): the 16-byte header (``GHDLwave\\n``,
16, 0, version, byte order 1 little / 2 big, word length, offset length, 0), then sections
marked by four bytes: ``STR`` (the string table, each string sharing a prefix with the one
before), ``TYP`` (types by run-time kind: enumerations, scalars, physical types, arrays, array
and record subtypes with their ranges), ``WKT`` (well-known types), ``HIE`` (the hierarchy:
scopes and signals, each signal a list of basic signal numbers), ``EOH``; then the value
changes. Numbers in the sections are LEB128.

A GHW file records no time unit: its times are counts of the simulation's resolution, GHDL's
``--time-resolution`` (fs by default; mcode also takes ps, ns, us, ms, sec and auto). See
:data:`DEFAULT_TIME_UNIT`.
"""

from __future__ import annotations

import mmap
import os
import re
from dataclasses import dataclass, field

from wavecheck.errors import CaptureError

__all__ = ["DEFAULT_TIME_UNIT", "GhwHeader", "read_ghw_header"]

#: The time unit assumed for a GHW file: GHDL's default ``--time-resolution``.
DEFAULT_TIME_UNIT = "fs"

MAGIC = b"GHDLwave\n"
_MAX_DIMS = 16
_MAX_DEPTH = 1000

# GHDL run-time kinds (ghdl_rtik) of the type section and hierarchy kinds of the HIE section
_B2, _E8, _E32, _I32, _I64, _F64, _P32, _P64 = 22, 23, 24, 25, 26, 27, 28, 29
_ARRAY, _RECORD, _SUB_SCALAR, _SUB_ARRAY = 31, 32, 34, 35
_SUB_UARRAY, _SUB_RECORD, _SUB_URECORD = 37, 38, 39
_SCOPES = {3, 4, 5, 6, 7, 14}  # block, if-generate, for-generate, instance, package, generic
_FOR_GENERATE, _PROCESS, _END_OF_SCOPE = 5, 13, 15
_SIGNALS = {16, 17, 18, 19, 20, 21}  # signal, port in/out/inout/buffer/linkage
_BITS = (("0", "1"), ("u", "x", "0", "1", "z", "w", "l", "h", "-"))
#: The byte that ends a string of the string table (and starts its prefix length).
_STRING_END = re.compile(rb"[\x00-\x1f\x80-\x9f]")


@dataclass
class _Type:
    """One entry of the type section (only what the hierarchy needs)."""

    kind: int
    name: str
    base: _Type | None = None  # subtypes: the type they constrain
    element: _Type | None = None  # arrays: the element type
    dims: int = 0  # arrays: number of dimensions
    ranges: list[tuple[int, int]] = field(default_factory=list)  # (left, right) per dimension
    fields: list[tuple[str, _Type]] = field(default_factory=list)  # records
    literals: list[str] = field(default_factory=list)  # enumerations
    scalars: int = 1  # basic signals per value; -1 unbounded

    def root(self) -> _Type:
        t = self
        while t.kind in (_SUB_SCALAR, _SUB_ARRAY, _SUB_UARRAY) and t.base is not None:
            t = t.base
        return t

    def is_bit(self) -> bool:
        r = self.root()
        return r.kind in (_B2, _E8) and tuple(_lit(x) for x in r.literals) in _BITS


def _lit(text: str) -> str:
    return (text[1:-1] if len(text) == 3 and text[0] == "'" else text).lower()


@dataclass
class GhwHeader:
    """What the header of a GHW file says.

    Attributes:
        ranges: the declared ``(left, right)`` of every one-dimensional vector of bits
            (``bit_vector``, ``std_logic_vector`` and their subtypes), by pywellen's full name.
        signals: the number of basic signals.
        version: the GHW format version.
    """

    ranges: dict[str, tuple[int, int]]
    signals: int
    version: int


class _Reader:
    """Sequential reads from the mapped file, every one bounded by its end."""

    def __init__(self, path: str | os.PathLike[str], data: mmap.mmap | bytes) -> None:
        self.path = path
        self.data = data
        self.pos = 0
        self.big = False

    def fail(self, what: str, at: int | None = None) -> CaptureError:
        return CaptureError(self.path, f"byte {self.pos if at is None else at}", what)

    def take(self, n: int, what: str) -> bytes:
        if self.pos + n > len(self.data):
            raise self.fail(f"the file ends inside {what} (cut short?)")
        out = bytes(self.data[self.pos : self.pos + n])
        self.pos += n
        return out

    def byte(self, what: str) -> int:
        return self.take(1, what)[0]

    def i32(self, what: str) -> int:
        return int.from_bytes(self.take(4, what), "big" if self.big else "little", signed=True)

    def count(self, what: str) -> int:
        """A 32-bit count, which no file can exceed in bytes."""
        at = self.pos
        n = self.i32(what)
        if not 0 <= n <= len(self.data):
            raise self.fail(f"{what} {n} is more than the file's {len(self.data)} bytes hold", at)
        return n

    def uleb(self, what: str) -> int:
        value = shift = 0
        while True:
            b = self.byte(what)
            value |= (b & 0x7F) << shift
            shift += 7
            if not b & 0x80:
                return value
            if shift > 63:
                raise self.fail(f"{what}: a number longer than 64 bits")

    def sleb(self, what: str) -> int:
        value = shift = 0
        while True:
            b = self.byte(what)
            value |= (b & 0x7F) << shift
            shift += 7
            if not b & 0x80:
                return value - (1 << shift) if b & 0x40 else value
            if shift > 63:
                raise self.fail(f"{what}: a number longer than 64 bits")

    def zeros(self, what: str) -> None:
        if self.take(4, what) != b"\0\0\0\0":
            raise self.fail(f"{what} does not start with four zero bytes", self.pos - 4)


class _Header:
    def __init__(self, r: _Reader) -> None:
        self.r = r
        self.strings: list[str] = ["<anon>"]
        self.types: list[_Type] = []
        self.signals = 0
        self.ranges: dict[str, tuple[int, int]] = {}
        self.version = 0

    # -- strings and types -----------------------------------------------------------------------
    def strings_section(self) -> None:
        r = self.r
        r.zeros("the string table")
        n = r.count("the string count")
        r.count("the string table size")
        prev = b""
        for _ in range(n):
            start = r.pos
            found = _STRING_END.search(r.data, start)
            if found is None:
                raise r.fail("the file ends inside the string table (cut short?)", start)
            text = prev + bytes(r.data[start : found.start()])
            r.pos = found.start()
            c = r.byte("a string")
            keep, shift = c & 0x1F, 5
            while c >= 128:
                c = r.byte("a string")
                keep |= (c & 0x1F) << shift
                shift += 5
                if shift > 35:
                    raise r.fail("a string's prefix length is longer than 32 bits")
            self.strings.append(text.decode("utf-8", "replace"))
            if keep > len(text):
                raise r.fail(f"a string shares {keep} bytes with one of {len(text)}")
            prev = text[:keep]
        if r.take(4, "the end of the string table") != b"EOS\0":
            raise r.fail("the string table does not end with EOS", r.pos - 4)

    def string(self, what: str) -> str:
        at = self.r.pos
        k = self.r.uleb(what)
        if k >= len(self.strings):
            raise self.r.fail(f"{what}: string {k} of a table of {len(self.strings)}", at)
        return self.strings[k]

    def type_ref(self, what: str) -> _Type:
        at = self.r.pos
        k = self.r.uleb(what)
        if not 1 <= k <= len(self.types):
            raise self.r.fail(f"{what}: type {k} is not among the {len(self.types)} before it", at)
        return self.types[k - 1]

    def range(self) -> tuple[int, int]:
        r = self.r
        at = r.pos
        kind = r.byte("a range") & 0x7F
        if kind in (_B2, _E8):
            return r.byte("a range"), r.byte("a range")
        if kind in (_I32, _P32, _I64, _P64):
            return r.sleb("a range"), r.sleb("a range")
        if kind == _F64:
            r.take(16, "a range")
            return 0, 0
        raise r.fail(f"a range of kind {kind} (not a scalar kind)", at)

    def array_subtype(self, name: str, base: _Type) -> _Type:
        arr = base.root()
        if arr.kind != _ARRAY or arr.element is None:
            raise self.r.fail(f"array subtype {name!r} of a type that is not an array")
        t = _Type(_SUB_ARRAY, name or arr.name, base=base)
        count = 1
        for _ in range(arr.dims):
            left, right = self.range()
            t.ranges.append((left, right))
            count *= max(0, abs(right - left) + 1)
        element = arr.element
        if element.scalars < 0:
            element = self.bounds(element)
        t.element = element
        t.scalars = count * element.scalars
        if t.scalars > len(self.r.data):
            raise self.r.fail(f"array subtype {name!r} has {t.scalars} elements: more than fit")
        return t

    def record_subtype(self, name: str, base: _Type) -> _Type:
        rec = base.root() if base.kind != _SUB_URECORD else (base.base or base)
        if rec.kind != _RECORD:
            raise self.r.fail(f"record subtype {name!r} of a type that is not a record")
        t = _Type(_SUB_RECORD, name or rec.name, base=rec, scalars=0)
        for fname, ftype in rec.fields:
            ft = ftype if ftype.scalars >= 0 else self.bounds(ftype)
            t.fields.append((fname, ft))
            t.scalars += ft.scalars
        return t

    def bounds(self, base: _Type) -> _Type:
        if base.root().kind == _ARRAY:
            return self.array_subtype("", base)
        if base.kind in (_RECORD, _SUB_URECORD):
            return self.record_subtype("", base)
        raise self.r.fail(f"bounds of type kind {base.kind}, which has none")

    def types_section(self) -> None:
        r = self.r
        r.zeros("the type table")
        n = r.count("the type count")
        for _ in range(n):
            at = r.pos
            kind = r.byte("a type")
            name = self.string("a type's name")
            t: _Type
            if kind in (_B2, _E8):
                k = r.uleb("an enumeration")
                if k > len(r.data):
                    raise r.fail(f"an enumeration of {k} literals: more than fit", at)
                t = _Type(kind, name, literals=[self.string("a literal") for _ in range(k)])
            elif kind in (_E32, _I32, _I64, _F64):
                t = _Type(kind, name)
            elif kind in (_P32, _P64):
                t = _Type(kind, name)
                if self.version > 0:
                    for _ in range(r.uleb("a physical type's unit count")):
                        self.string("a unit")
                        r.sleb("a unit's value")
            elif kind == _SUB_SCALAR:
                base = self.type_ref("a scalar subtype")
                self.range()
                t = _Type(kind, name, base=base)
            elif kind == _ARRAY:
                element = self.type_ref("an array's element type")
                dims = r.uleb("an array's dimension count")
                if not 1 <= dims <= _MAX_DIMS:
                    raise r.fail(f"an array of {dims} dimensions", at)
                for _ in range(dims):
                    self.type_ref("an array's index type")
                t = _Type(kind, name, element=element, dims=dims, scalars=-1)
            elif kind == _SUB_ARRAY:
                t = self.array_subtype(name, self.type_ref("an array subtype's base"))
            elif kind == _SUB_UARRAY:
                t = _Type(kind, name, base=self.type_ref("an array subtype's base"), scalars=-1)
            elif kind == _RECORD:
                k = r.uleb("a record's field count")
                if k > len(r.data):
                    raise r.fail(f"a record of {k} fields: more than fit", at)
                t = _Type(kind, name, scalars=0)
                for _ in range(k):
                    fname = self.string("a field's name")
                    ftype = self.type_ref("a field's type")
                    t.fields.append((fname, ftype))
                    t.scalars = (
                        -1 if min(t.scalars, ftype.scalars) < 0 else t.scalars + ftype.scalars
                    )
            elif kind == _SUB_RECORD:
                t = self.record_subtype(name, self.type_ref("a record subtype's base"))
            elif kind == _SUB_URECORD:
                t = _Type(kind, name, base=self.type_ref("a record subtype's base"), scalars=-1)
            else:
                raise r.fail(f"type kind {kind} is not a GHW type kind", at)
            self.types.append(t)
        if r.byte("the end of the type table") != 0:
            raise r.fail("the type table does not end with a zero byte", r.pos - 1)

    def well_known_section(self) -> None:
        self.r.zeros("the well-known types")
        while self.r.byte("the well-known types"):
            self.type_ref("a well-known type")

    # -- hierarchy -------------------------------------------------------------------------------
    def signal_ids(self, t: _Type, what: str) -> None:
        """Read the basic signal numbers of a value of type ``t``."""
        if t.scalars < 0:
            raise self.r.fail(f"{what} has an unbounded type")
        for _ in range(t.scalars):
            at = self.r.pos
            sig = self.r.uleb(what)
            if not 1 <= sig <= self.signals:
                raise self.r.fail(f"{what}: signal number {sig} of {self.signals}", at)

    def add_names(self, path: str, t: _Type) -> None:
        """Record the ranges of the bit vectors of a signal named ``path`` of type ``t``,
        named as pywellen names them (records and arrays of non-bits are scopes; an array
        element is ``[i]``)."""
        root = t.root()
        if t.kind == _SUB_ARRAY and len(t.ranges) == 1 and t.element is not None:
            if t.element.is_bit():
                self.ranges[path] = t.ranges[0]
                return
            left, right = t.ranges[0]
            step = 1 if right >= left else -1
            if abs(right - left) < 1 << 16:  # more would be no stepper's dump
                for i in range(left, right + step, step):
                    self.add_names(f"{path}.[{i}]", t.element)
            return
        if root.kind in (_RECORD, _SUB_RECORD) or t.kind == _SUB_RECORD:
            for fname, ftype in t.fields or root.fields:
                self.add_names(f"{path}.{fname}", ftype)

    def hierarchy_section(self) -> None:
        r = self.r
        r.zeros("the hierarchy")
        r.count("the scope count")
        r.count("the signal count")
        self.signals = r.count("the basic signal count")
        scopes: list[str] = []
        while True:
            at = r.pos
            kind = r.byte("the hierarchy")
            if kind == 0:
                break
            if kind == _END_OF_SCOPE:
                if not scopes:
                    raise r.fail("the hierarchy closes a scope that is not open", at)
                scopes.pop()
                continue
            name = self.string("a hierarchy name")
            if kind == _PROCESS:
                continue
            if kind in _SCOPES:
                if kind == _FOR_GENERATE:
                    iterator = self.type_ref("a generate's iterator type")
                    name = f"{name}({self.value(iterator)})"
                scopes.append(name)
                if len(scopes) > _MAX_DEPTH:
                    raise r.fail(f"the hierarchy nests deeper than {_MAX_DEPTH}", at)
            elif kind in _SIGNALS:
                t = self.type_ref("a signal's type")
                self.signal_ids(t, f"signal {name!r}")
                self.add_names(".".join([*scopes, name]), t)
            else:
                raise r.fail(f"hierarchy entry of kind {kind} is not a GHW kind", at)

    def value(self, t: _Type) -> str:
        root = t.root()
        if root.kind in (_B2, _E8):
            v = self.r.byte("a value")
            return _lit(root.literals[v]) if v < len(root.literals) else str(v)
        if root.kind in (_I32, _P32, _I64, _P64, _E32):
            return str(self.r.sleb("a value"))
        if root.kind == _F64:
            self.r.take(8, "a value")
            return "?"
        raise self.r.fail(f"a value of type kind {root.kind}")

    def read(self) -> GhwHeader:
        r = self.r
        head = r.take(16, "the header")
        if head[:9] != MAGIC or head[9] != 16 or head[10] != 0 or head[15] != 0:
            raise r.fail("not a GHW file (its 16-byte header is not GHDL's)", 0)
        self.version = head[11]
        if head[12] not in (1, 2) or self.version > 1:
            raise r.fail(f"GHW version {self.version}, byte order {head[12]}: not known", 11)
        r.big = head[12] == 2
        sections = {
            b"STR\0": self.strings_section,
            b"TYP\0": self.types_section,
            b"WKT\0": self.well_known_section,
            b"HIE\0": self.hierarchy_section,
        }
        seen: set[bytes] = set()
        while True:
            at = r.pos
            mark = r.take(4, "a section mark")
            if mark == b"EOH\0":
                break
            if mark not in sections or mark in seen:
                raise r.fail(f"section {mark!r} is not expected in the GHW header", at)
            seen.add(mark)
            sections[mark]()
        if b"HIE\0" not in seen:
            raise r.fail("the GHW header has no hierarchy")
        return GhwHeader(self.ranges, self.signals, self.version)


def read_ghw_header(path: str | os.PathLike[str]) -> GhwHeader:
    """Read and check the header of the GHW file ``path`` (see the module docstring).

    Raises:
        CaptureError: the file cannot be opened, or its header is cut short or malformed (the
            message names the byte).
    """
    try:
        with open(path, "rb") as f:
            size = os.fstat(f.fileno()).st_size
            if size < 16:
                raise CaptureError(path, None, "is too short for a GHW file (cut short?)")
            with mmap.mmap(f.fileno(), 0, access=mmap.ACCESS_READ) as data:
                return _Header(_Reader(path, data)).read()
    except OSError as err:
        raise CaptureError(path, None, f"cannot open: {err.strerror or err}") from None
