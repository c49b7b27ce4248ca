"""The one VCD writer: 1-bit wires given as exact edge arrays (and optional integer vectors).

Every VCD the project writes goes through :func:`write_vcd`: stepgen's traces, GTKWave companion
files, crosscheck's input for sigrok-cli and the test fixtures. The input is arrays, not one call
per change, so a vectorised writer can replace pyvcd behind the same function.

Output (pyvcd's ``VCDWriter``): ``$comment``, ``$timescale``, ``$version`` when given (no
``$date``: the bytes depend only on the input), one scope, the wires then the vectors in the
order given (id codes ``!``, ``"``, … in that order), ``#0 $dumpvars`` with the initial values
(changes at time 0 replace them), then the changes in time order, at one time in variable order,
and a final ``#end``. A wire's edges each toggle its level; several edges at one time are all
written (the last one wins for a reader).

Two paths, byte for byte the same file (tests/wavecheck/capture/vcd/test_writer.py compares them
on hypothesis inputs): the header and the ``$dumpvars`` section (the values after the changes at
time 0) are written as pyvcd writes them (:func:`_header`; by pyvcd itself for a timescale, a
scope or names outside the plain cases, so pyvcd is imported only then: ~6 ms); the changes
after time 0 are then formatted all at once with numpy (timestamps 8 digits
per ``uint32`` division, vector values from ``unpackbits``, each piece scattered to its offset),
~20× faster than one ``VCDWriter.change`` call per change. pyvcd writes everything itself
(:func:`_write_pyvcd`, the reference) when the fast path does not cover the input: more than
``_FAST_MAX_VARS`` variables, a wire whose initial level is not 0/1, a vector of 1 bit (pyvcd
writes it as a scalar) or wider than 62 bits
or of a type pyvcd does not write as bits, or a value that does not fit its vector (pyvcd then
raises its ``ValueError``).
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, TextIO

import numpy as np

from wavecheck.output import atomic_path
from wavecheck.progress import current

if TYPE_CHECKING:
    import numpy.typing as npt

__all__ = ["VcdVector", "VcdWire", "write_vcd"]

_REPORT_EVERY = 1 << 16  # value changes between two progress reports
_FAST_MAX_VARS = 256  # more variables: pyvcd (the fast path loops over the variables)
_FAST_MAX_BITS = 62  # wider vectors: pyvcd
_FAST_BLOCK = _REPORT_EVERY  # changes formatted at a time (memory stays bounded)
# _BYTE_CHARS[b]: the 8 characters "0"/"1" of byte b, most significant first, as the
# little-endian uint64 that puts them in that order in memory
_BITS = (np.arange(256, dtype=np.uint64)[:, None] >> np.arange(7, -1, -1, dtype=np.uint64)) & 1
_BYTE_CHARS = ((_BITS + 48) << (8 * np.arange(8, dtype=np.uint64))).sum(axis=1, dtype=np.uint64)
_POW10 = np.array([10**k for k in range(19)], dtype=np.int64)
_VECTOR_TYPES = {"integer", "reg", "wire", "tri", "wor", "wand", "supply0", "supply1", "time"}
_UNITS = ("s", "ms", "us", "ns", "ps", "fs")  # timescale units :func:`_header` writes itself


@dataclass(frozen=True)
class VcdWire:
    """A 1-bit wire: its level before the first edge and the times it toggles (timescale units,
    non-decreasing, ≥ 0)."""

    name: str
    initial: int
    edges: npt.NDArray[np.int64]


@dataclass(frozen=True)
class VcdVector:
    """A vector variable (e.g. an ``integer``): its value from time 0 and its changes."""

    name: str
    times: npt.NDArray[np.int64]  # timescale units, non-decreasing, ≥ 0
    values: npt.NDArray[np.int64]  # the value from each time on
    size: int = 32
    var_type: str = "integer"
    initial: int = 0


def _variables(
    wires: Sequence[VcdWire], vectors: Sequence[VcdVector]
) -> list[tuple[npt.NDArray[np.int64], npt.NDArray[np.int64] | None]]:
    """Each variable's change times and values (None for a wire: each edge toggles), checked.

    Raises:
        ValueError: times that go backwards, or a vector's times and values of other lengths.
    """
    out: list[tuple[npt.NDArray[np.int64], npt.NDArray[np.int64] | None]] = []
    for w in wires:
        e = np.asarray(w.edges, dtype=np.int64)
        if len(e) > 1 and bool((e[1:] < e[:-1]).any()):
            raise ValueError(f"wire {w.name!r}: edge times go backwards")
        out.append((e, None))
    for vec in vectors:
        t = np.asarray(vec.times, dtype=np.int64)
        if len(t) != len(vec.values):
            raise ValueError(f"vector {vec.name!r}: {len(t)} times but {len(vec.values)} values")
        if len(t) > 1 and bool((t[1:] < t[:-1]).any()):
            raise ValueError(f"vector {vec.name!r}: times go backwards")
        out.append((t, np.asarray(vec.values, dtype=np.int64)))
    return out


def _wire_levels(initial: int, a: int, b: int) -> npt.NDArray[np.int64]:
    """A wire's level after each of its edges ``a`` … ``b − 1`` (each edge toggles)."""
    return (int(initial) ^ (np.arange(a + 1, b + 1) & 1)).astype(np.int64)


def _changes(
    wires: Sequence[VcdWire], vectors: Sequence[VcdVector]
) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.int64], npt.NDArray[np.int64]]:
    """Every value change sorted by (time, variable): time, variable index, new value."""
    variables = _variables(wires, vectors)
    if not variables:
        empty = np.zeros(0, dtype=np.int64)
        return empty, empty, empty
    return _merged(variables, [w.initial for w in wires], [(0, len(t)) for t, _ in variables])


def _merged(
    variables: Sequence[tuple[npt.NDArray[np.int64], npt.NDArray[np.int64] | None]],
    initials: Sequence[int],
    spans: Sequence[tuple[int, int]],
) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.int64], npt.NDArray[np.int64]]:
    """The changes ``spans[i]`` (a slice) of each variable merged by (time, variable): each
    variable's are in time order, so a stable sort by time of them one variable after the
    other (numpy's timsort merges the runs) keeps a variable's order within one time."""
    ts, vs, xs = [], [], []
    for i, ((times, values), (a, b)) in enumerate(zip(variables, spans, strict=True)):
        ts.append(times[a:b])
        vs.append(np.full(b - a, i, dtype=np.int64))
        xs.append(_wire_levels(initials[i], a, b) if values is None else values[a:b])
    t, v, x = np.concatenate(ts), np.concatenate(vs), np.concatenate(xs)
    order = np.argsort(t, kind="stable")
    return t[order], v[order], x[order]


def write_vcd(
    path: str | os.PathLike[str],
    wires: Sequence[VcdWire],
    *,
    timescale: str,
    end: int,
    scope: str,
    vectors: Sequence[VcdVector] = (),
    comment: str = "",
    version: str = "",
) -> int:
    """Write a VCD at ``path`` (atomically); returns the number of value changes written.

    Args:
        path: the file to write.
        wires: the 1-bit wires, in declaration order.
        timescale: the ``$timescale``, e.g. ``"1 ns"`` or ``"10 us"``.
        end: the final timestamp (≥ every change), marking the end of the recorded span.
        scope: the module scope every variable is declared in.
        vectors: vector variables declared after the wires.
        comment: the ``$comment`` (none when empty).
        version: the ``$version`` (none when empty).

    Raises:
        ValueError: a time goes backwards (within a signal, or ``end`` before a change), a
            negative time, or a value that does not fit its variable.
    """
    variables = _variables(wires, vectors)
    firsts = [int(tv[0][0]) for tv in variables if len(tv[0])]
    lasts = [int(tv[0][-1]) for tv in variables if len(tv[0])]
    if firsts and (min(firsts) < 0 or max(lasts) > end):
        raise ValueError(f"changes at {min(firsts)} … {max(lasts)} fall outside 0 … end {end}")
    fast = _fast_covers(wires, vectors)
    with atomic_path(path) as tmp, open(tmp, "w", encoding="utf-8", newline="\n") as fh:
        if fast:
            _write_fast(fh, wires, vectors, timescale, end, scope, comment, version)
        else:
            t, v, x = _changes(wires, vectors)
            _write_pyvcd(fh, wires, vectors, t, v, x, timescale, end, scope, comment, version)
    return sum(len(tv[0]) for tv in variables)


def _register(
    fh: TextIO,
    wires: Sequence[VcdWire],
    vectors: Sequence[VcdVector],
    timescale: str,
    scope: str,
    comment: str,
    version: str,
) -> tuple[Any, list[Any]]:
    """A pyvcd ``VCDWriter`` on ``fh`` with the wires then the vectors registered."""
    from vcd import VCDWriter

    writer = VCDWriter(fh, timescale=timescale, date="", comment=comment, version=version)
    variables = [
        writer.register_var(scope, w.name, "wire", size=1, init=int(w.initial)) for w in wires
    ]
    variables += [
        writer.register_var(scope, vec.name, vec.var_type, size=vec.size, init=vec.initial)
        for vec in vectors
    ]
    return writer, variables


def _write_pyvcd(
    fh: TextIO,
    wires: Sequence[VcdWire],
    vectors: Sequence[VcdVector],
    t: npt.NDArray[np.int64],
    v: npt.NDArray[np.int64],
    x: npt.NDArray[np.int64],
    timescale: str,
    end: int,
    scope: str,
    comment: str,
    version: str,
    upto: int | None = None,
) -> Any:
    """The reference: one ``VCDWriter.change`` per change, then ``close(end)``. With ``upto``,
    only the first ``upto`` changes, and the writer is returned open instead of closed."""
    writer, variables = _register(fh, wires, vectors, timescale, scope, comment, version)
    change = writer.change
    report = current()
    n = len(t) if upto is None else upto
    for a in range(0, n, _REPORT_EVERY):
        b = min(a + _REPORT_EVERY, n)
        for ti, vi, xi in zip(t[a:b].tolist(), v[a:b].tolist(), x[a:b].tolist(), strict=True):
            change(variables[vi], ti, xi)
        report(b, len(t))
    if upto is not None:
        return writer, variables
    writer.close(end)
    return None


def _fast_covers(wires: Sequence[VcdWire], vectors: Sequence[VcdVector]) -> bool:
    """Whether :func:`_write_fast` writes exactly what pyvcd would for this input."""
    if not 0 < len(wires) + len(vectors) <= _FAST_MAX_VARS:
        return False
    if any(int(w.initial) not in (0, 1) for w in wires):
        return False
    for vec in vectors:
        if vec.var_type not in _VECTOR_TYPES or not 2 <= vec.size <= _FAST_MAX_BITS:
            return False
        vals = np.asarray(vec.values, dtype=np.int64)
        lo, hi = -(1 << (vec.size - 1)), 1 << vec.size  # what pyvcd accepts
        if len(vals) and (int(vals.min()) < lo or int(vals.max()) >= hi):
            return False
        if not lo <= int(vec.initial) < hi:
            return False
    return True


def _write_fast(
    fh: TextIO,
    wires: Sequence[VcdWire],
    vectors: Sequence[VcdVector],
    timescale: str,
    end: int,
    scope: str,
    comment: str,
    version: str,
) -> None:
    """pyvcd up to time 0 (header, ``$dumpvars``), then numpy for the changes after it, a
    block of about ``_FAST_BLOCK`` changes at a time merged from the variables' own arrays (no
    copy of every change is made)."""
    variables = _variables(wires, vectors)
    initials = [int(w.initial) for w in wires]
    at0 = [int(np.searchsorted(t, 0, side="right")) for t, _ in variables]
    n0, total = sum(at0), sum(len(t) for t, _ in variables)
    # each variable's value after its changes at time 0 (what $dumpvars shows)
    last0 = [initials[j] ^ (at0[j] & 1) for j in range(len(wires))] + [
        int(vec.values[a - 1]) if a else int(vec.initial)
        for vec, a in zip(vectors, at0[len(wires) :], strict=True)
    ]
    head = _header(wires, vectors, last0, timescale, scope, comment, version)
    if head is None:  # pyvcd writes the header, $dumpvars and the changes at time 0
        t, v, x = _merged(variables, initials, [(0, a) for a in at0])
        if n0 == total:  # nothing after time 0: all pyvcd
            _write_pyvcd(fh, wires, vectors, t, v, x, timescale, end, scope, comment, version)
            return
        writer, registered = _write_pyvcd(
            fh, wires, vectors, t, v, x, timescale, end, scope, comment, version, upto=n0
        )
        writer.flush()  # the header and "#0 $dumpvars … $end", as the first later change would
    else:
        fh.write(head)
    fh.flush()
    if n0 == total:  # what pyvcd's close(end) adds
        if end:
            fh.buffer.write(b"#%d\n" % end)
        return
    idents = [_ident(j + 1).encode("ascii") for j in range(len(variables))]
    sizes = [0] * len(wires) + [vec.size for vec in vectors]
    # after time 0, each variable's own changes; pyvcd writes a change only when the value
    # differs from the variable's last one: always for a wire's edges (each toggles), not for a
    # vector value repeated
    rest: list[tuple[npt.NDArray[np.int64], npt.NDArray[np.int64] | None]] = []
    for j, ((times, values), a) in enumerate(zip(variables, at0, strict=True)):
        if values is None:
            rest.append((times[a:], None))
            continue
        vals = values[a:]
        prev = np.concatenate(([last0[j]], vals[:-1]))
        keep = vals != prev
        rest.append((times[a:][keep], vals[keep]) if not keep.all() else (times[a:], vals))
    for j in range(len(wires)):  # a wire's level after its time-0 edges; its edges renumbered
        initials[j] = int(wires[j].initial) ^ (at0[j] & 1)
    last_ts = 0  # the "#0" before $dumpvars
    report = current()
    done = n0
    for spans in _block_spans([times for times, _ in rest]):
        t, v, x = _merged(rest, initials, spans)
        if not len(t):
            continue
        text, last_ts = _format_changes(t, v, x, idents, sizes, last_ts)
        fh.buffer.write(text)
        done += len(t)
        report(done, total)
    if end != last_ts:
        fh.buffer.write(b"#%d\n" % end)


def _ident(number: int) -> str:
    """The id code of the ``number``-th variable (from 1) as pyvcd makes it: base 94 in the
    printable characters ``!`` … ``~``, least significant first."""
    code = ""
    while number:
        number -= 1
        code += chr(number % 94 + 33)
        number //= 94
    return code


def _timescale(text: str) -> str | None:
    """pyvcd's form of a timescale (``Timescale.from_str``, then ``"1 ns"``) when its magnitude
    is 1, 10 or 100 and its unit one of ``_UNITS``; None otherwise (pyvcd then decides)."""
    if text in _UNITS:
        return f"1 {text}"
    digits = len(text) - len(text.lstrip("0123456789"))
    if not digits or int(text[:digits]) not in (1, 10, 100):
        return None
    unit = text[digits:].lstrip(" ")
    return f"{int(text[:digits])} {unit}" if unit in _UNITS else None


def _header(
    wires: Sequence[VcdWire],
    vectors: Sequence[VcdVector],
    last0: Sequence[int],
    timescale: str,
    scope: str,
    comment: str,
    version: str,
) -> str | None:
    """The text pyvcd's ``VCDWriter`` writes up to the end of ``$dumpvars`` (``last0``: each
    variable's value there), or None where pyvcd itself is to write it: a timescale outside
    :func:`_timescale`, a nested or empty scope, two variables of one name (pyvcd raises)."""
    ts = _timescale(timescale)
    names = [w.name for w in wires] + [vec.name for vec in vectors]
    if ts is None or not scope or "." in scope or len(set(names)) != len(names):
        return None
    lines = []
    for keyword, value in (("$comment", comment), ("$timescale", ts), ("$version", version)):
        if value:  # pyvcd: the keywords sorted, no $date here, several lines indented
            parts = value.split("\n")
            if len(parts) == 1:
                lines.append(f"{keyword} {value} $end")
            else:
                lines += [keyword, *(f"\t{part}" for part in parts), "$end"]
    lines.append(f"$scope module {scope} $end")
    idents = [_ident(j + 1) for j in range(len(names))]
    lines += [f"$var wire 1 {idents[j]} {w.name} $end" for j, w in enumerate(wires)]
    dump = [f"{last0[j]}{idents[j]}" for j in range(len(wires))]
    for j, vec in enumerate(vectors, len(wires)):
        lines.append(f"$var {vec.var_type} {vec.size} {idents[j]} {vec.name} $end")
        number = last0[j] + (1 << vec.size) if last0[j] < 0 else last0[j]
        dump.append(f"b{number:b} {idents[j]}")
    lines += ["$upscope $end", "$enddefinitions $end", "#0", "$dumpvars", *dump, "$end", ""]
    return "\n".join(lines)


def _block_spans(times: Sequence[npt.NDArray[np.int64]]) -> list[list[tuple[int, int]]]:
    """Slices of each variable's (sorted) times, block by block in time order: a block ends
    before a time at which some variable has had ``_FAST_BLOCK`` more changes, so it holds at
    most that many changes of each variable (more only where one variable changes that often
    at one time), ~``_FAST_BLOCK`` on average."""
    cuts = np.sort(np.concatenate([t[_FAST_BLOCK::_FAST_BLOCK] for t in times]))
    new = np.ones(len(cuts), dtype=bool)
    new[1:] = cuts[1:] != cuts[:-1]
    cuts = cuts[new]  # np.unique would import numpy.ma (8 ms)
    at = [np.concatenate(([0], np.searchsorted(t, cuts), [len(t)])) for t in times]
    return [[(int(a[k]), int(a[k + 1])) for a in at] for k in range(len(cuts) + 1)]


def _format_changes(
    t: npt.NDArray[np.int64],
    v: npt.NDArray[np.int64],
    x: npt.NDArray[np.int64],
    idents: list[bytes],
    sizes: list[int],
    last_ts: int,
) -> tuple[memoryview, int]:
    """The VCD text of changes (all written, times > 0, non-decreasing) as pyvcd writes them:
    ``#t`` on its own line before the first change at each new time, then ``0!``/``1!`` for a
    wire, ``b101 #`` for a vector. Returns the text and the last timestamp written."""
    n = len(t)
    newt = np.empty(n, dtype=bool)
    newt[0] = int(t[0]) != last_ts
    np.not_equal(t[1:], t[:-1], out=newt[1:])
    stamp_rows = np.flatnonzero(newt)
    stamps = t[stamp_rows]
    ndig = _decimal_digits(stamps)
    # each variable's rows; the length of each change's value piece
    by_var = [
        np.flatnonzero(v == j) if len(idents) > 1 else np.arange(n) for j in range(len(idents))
    ]
    wire_rows = [(j, r) for j, r in enumerate(by_var) if len(r) and sizes[j] == 0]
    vec_rows = [(j, r) for j, r in enumerate(by_var) if len(r) and sizes[j] > 0]
    width = np.empty(n, dtype=np.int64)
    for j, rows in wire_rows:
        width[rows] = 1 + len(idents[j]) + 1  # "1!\n"
    if vec_rows:  # all vectors at once: their rows one vector after the other
        vrows = np.concatenate([r for _, r in vec_rows])
        size = np.concatenate([np.full(len(r), sizes[j]) for j, r in vec_rows])
        unsigned = np.where(x[vrows] < 0, x[vrows] + (np.int64(1) << size), x[vrows])
        nbits = _bit_length(unsigned)
        ident_len = np.concatenate([np.full(len(r), len(idents[j])) for j, r in vec_rows])
        width[vrows] = 1 + nbits + 1 + ident_len + 1  # "b101 #\n"
    length = width.copy()
    length[stamp_rows] += ndig + 2  # "#123\n"
    start = np.zeros(n + 1, dtype=np.int64)
    np.cumsum(length, out=start[1:])
    out = np.empty(int(start[-1]), dtype=np.uint8)
    # timestamps: "#", the digits, "\n"; the change follows
    at = start[stamp_rows]
    out[at] = ord("#")
    _put_digits(out, at + 1, stamps, ndig)
    out[at + 1 + ndig] = ord("\n")
    piece = start[:-1].copy()
    piece[stamp_rows] += ndig + 2
    for j, rows in wire_rows:  # "1!\n"
        p = piece[rows]
        out[p] = (x[rows] + ord("0")).astype(np.uint8)
        _put_ident(out, p + 1, idents[j])
    if vec_rows:  # "b101 #\n"
        p = piece[vrows]
        out[p] = ord("b")
        _put_bits(out, p + 1, unsigned, nbits)
        p = p + 1 + nbits
        out[p] = ord(" ")
        offset = 0
        for j, rows in vec_rows:
            _put_ident(out, p[offset : offset + len(rows)] + 1, idents[j])
            offset += len(rows)
    return out.data, int(stamps[-1]) if len(stamps) else last_ts


def _put_ident(out: npt.NDArray[np.uint8], at: npt.NDArray[np.int64], ident: bytes) -> None:
    """Write ``ident`` and a newline at each ``out[at:]``."""
    for k, byte in enumerate(ident):
        out[at + k] = byte
    out[at + len(ident)] = ord("\n")


def _decimal_digits(values: npt.NDArray[np.int64]) -> npt.NDArray[np.int64]:
    """Number of decimal digits of each value (non-decreasing values ≥ 0; 0 has one digit)."""
    bounds = np.searchsorted(values, _POW10[1:])  # first value with k + 1 digits or more
    counts = np.diff(np.concatenate(([0], bounds, [len(values)])))
    return np.repeat(np.arange(1, len(_POW10) + 1, dtype=np.int64), counts)


def _put_digits(
    out: npt.NDArray[np.uint8],
    at: npt.NDArray[np.int64],
    values: npt.NDArray[np.int64],
    ndig: npt.NDArray[np.int64],
) -> None:
    """Write each value's ``ndig`` decimal digits at ``out[at : at + ndig]`` (values
    non-decreasing, so the ones with more than ``c`` digits are a tail).

    The value is split into 8-digit parts (int64 divisions by 10^8), whose digits come from
    ``uint32`` divisions by 10 (numpy divides by a constant with SIMD, ~50× faster than int64
    ``divmod``); digit ``c`` from the right goes to ``at + ndig − 1 − c``.
    """
    if not len(values):
        return
    end = at + ndig - 1
    parts = [values]
    if int(values[-1]) >= 10**8:
        high = values // 10**8
        parts = [values - high * 10**8, high]
        if int(high[-1]) >= 10**8:
            top = high // 10**8
            parts = [parts[0], high - top * 10**8, top]
    col = 0
    pos = end.copy()  # where each value's digit ``col`` goes
    for part in parts:
        q = part.astype(np.uint32)
        for _ in range(8):
            first = int(np.searchsorted(ndig, col, side="right"))  # rows with > col digits
            if first == len(values):
                return
            nq = q // np.uint32(10)
            digit = (q - nq * np.uint32(10)).astype(np.uint8)
            digit += np.uint8(ord("0"))
            out[pos[first:]] = digit[first:]
            pos -= 1
            q = nq
            col += 1


def _bit_length(values: npt.NDArray[np.int64]) -> npt.NDArray[np.int64]:
    """Binary digits of each value (0 … 2^62; 0 has one, as ``format(0, "b")``): the exponent
    from ``frexp``, corrected by one where the float rounded the value up to a power of two."""
    u = values.astype(np.uint64)
    n = np.frexp(values.astype(np.float64))[1].astype(np.int64)
    n = np.maximum(n, 1)
    n -= (u >> (n - 1).astype(np.uint64)) == 0  # rounded up: one digit fewer (or 0 → 0)
    return np.maximum(n, 1)


def _put_bits(
    out: npt.NDArray[np.uint8],
    at: npt.NDArray[np.int64],
    values: npt.NDArray[np.int64],
    nbits: npt.NDArray[np.int64],
) -> None:
    """Write each value's ``nbits`` binary digits (most significant first) at ``out[at:]``.

    Whole bytes of the value (from the right) are written as 8 characters at once from a
    256-entry table, through a ``uint64`` view of ``out`` with a 1-byte stride; the 0 … 7 digits
    of the leading partial byte one column at a time.
    """
    u = values.astype(np.uint64)
    end = at + nbits  # one past the last digit
    whole = nbits // 8
    nwhole = int(whole.max()) if len(whole) else 0
    if nwhole:  # then out holds at least 8 bytes
        words = np.ndarray((len(out) - 7,), dtype=np.uint64, buffer=out, strides=(1,))
    for j in range(nwhole):
        rows = np.flatnonzero(whole > j) if int(whole.min()) <= j else slice(None)
        byte = (u[rows] >> np.uint64(8 * j)) & np.uint64(0xFF)
        words[end[rows] - 8 * (j + 1)] = _BYTE_CHARS[byte.astype(np.intp)]
    lead = nbits - 8 * whole
    if not len(lead) or not int(lead.max()):
        return
    # the leading partial byte's bits, lowest first, of the values that have one; a value
    # leaves the set when its bits are written (lead is how many it has)
    rows = np.flatnonzero(lead)
    top = u[rows] >> (8 * whole[rows]).astype(np.uint64)
    at_bit = end[rows] - 8 * whole[rows] - 1
    left = lead[rows]
    while len(rows):
        out[at_bit] = (top & np.uint64(1)).astype(np.uint8) + np.uint8(ord("0"))
        top >>= np.uint64(1)
        at_bit -= 1
        left -= 1
        more = left > 0
        if not more.all():
            rows, top, at_bit, left = rows[more], top[more], at_bit[more], left[more]
