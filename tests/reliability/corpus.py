"""Generators of malformed inputs: ``.sr`` files, VCDs, rule files (issue 8).

Every generator returns :class:`Case` objects (a name, the file's bytes, a suffix and what a
correct reader must do with it). The builders are independent of wavecheck's readers: ``.sr``
files are written with wavecheck's .sr writer (or :mod:`zipfile` where they break the layout),
VCDs as text. The same functions feed the in-suite tests (``test_malformed_*.py``) and the
longer fuzz run (``fuzz.py``).
"""

from __future__ import annotations

import functools
import io
import re
import struct
import zipfile
import zlib
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np
import numpy.typing as npt

from wavecheck.capture.srzip import write_sr

Expect = Literal["error", "ok", "either"]
#: A body token longer than this many bytes is the "no whitespace" hostile shape in the corpus
#: (above the reader's 16 MiB cap, so a reader holding tokens whole is refused, not starved).
MAX_TOKEN_TEST = 17 << 20


@dataclass(frozen=True)
class Case:
    """One input file: ``expect`` is ``"error"`` (exit 2), ``"ok"`` (a result) or ``"either"``."""

    name: str
    data: bytes
    suffix: str
    expect: Expect = "error"


# ---------------------------------------------------------------------------------------------
# .sr


def samples_from_edges(
    nsamples: int, channels: Sequence[tuple[int, Sequence[int]]], unitsize: int = 1
) -> npt.NDArray[np.uint8]:
    """Raw sample bytes: channel ``i`` = bit ``i``; each edge tick toggles the level from that
    sample on (ticks must be in 1 … nsamples−1)."""
    bits = np.zeros((nsamples, 8 * unitsize), dtype=np.uint8)
    for bit, (initial, edges) in enumerate(channels):
        toggles = np.zeros(nsamples, dtype=np.int64)
        for t in edges:
            toggles[t] += 1
        bits[:, bit] = (initial ^ (np.cumsum(toggles) & 1)).astype(np.uint8)
    raw = np.packbits(bits, axis=1, bitorder="little")
    return np.ascontiguousarray(raw).reshape(-1)


def sr_metadata(
    *,
    names: Sequence[str] = ("STEP", "DIR"),
    total: int | None = None,
    samplerate: str | None = "1 MHz",
    unitsize: int | str | None = 1,
    extra: str = "",
    capturefile: str = "logic-1",
) -> str:
    lines = ["[global]", "sigrok version=0.5.2", "", "[device 1]", f"capturefile={capturefile}"]
    lines.append(f"total probes={len(names) if total is None else total}")
    if samplerate is not None:
        lines.append(f"samplerate={samplerate}")
    lines += [f"probe{i + 1}={n}" for i, n in enumerate(names)]
    lines.append("total analog=0")
    if unitsize is not None:
        lines.append(f"unitsize={unitsize}")
    return "\n".join(lines) + "\n" + extra


def sr_bytes(
    raw: bytes,
    *,
    metadata: str | None = None,
    chunk: int = 256,
    version: bytes | None = b"2",
    members: dict[str, bytes] | None = None,
    drop: Sequence[str] = (),
    compress: int = zipfile.ZIP_DEFLATED,
) -> bytes:
    """A ``.sr`` zip: ``version``, ``metadata`` and ``raw`` cut into ``logic-1-N`` chunks.

    Written by the project's .sr writer (:func:`wavecheck.capture.srzip.write_sr`), except the
    layouts it does not make — ``drop`` (a member left out), ``members`` (members named as
    given), ``version=None`` (no version member) — which are written here with :mod:`zipfile`.
    """
    meta = sr_metadata() if metadata is None else metadata
    buf = io.BytesIO()
    if members is None and not drop and version is not None:
        write_sr(
            buf,
            raw,
            metadata=meta,
            chunk_bytes=max(1, chunk),
            compression=compress,
            version=version,
        )
        return buf.getvalue()
    with zipfile.ZipFile(buf, "w") as z:
        if version is not None and "version" not in drop:
            z.writestr("version", version, compress_type=zipfile.ZIP_STORED)
        if "metadata" not in drop:
            z.writestr("metadata", meta, compress_type=zipfile.ZIP_DEFLATED)
        if members is None:
            step = max(1, chunk)
            for k, i in enumerate(range(0, len(raw), step)):
                name = f"logic-1-{k + 1}"
                if name not in drop:
                    z.writestr(name, raw[i : i + step], compress_type=compress)
        else:
            for name, data in members.items():
                z.writestr(name, data, compress_type=compress)
    return buf.getvalue()


def base_sr_raw(nsamples: int = 2000) -> bytes:
    """A small valid STEP/DIR waveform: 2 µs pulses every 10 µs at 1 MHz, one DIR change."""
    step = [t for k in range(1, nsamples // 10 - 1) for t in (10 * k, 10 * k + 2)]
    dirs = [nsamples // 2 + 5]
    return samples_from_edges(nsamples, [(0, step), (0, dirs)]).tobytes()


def _patch_central_sizes(data: bytes, member: str, file_size: int) -> bytes:
    """Rewrite ``member``'s declared uncompressed size in the local and central headers."""
    out = bytearray(data)
    name = member.encode()
    for sig, size_off, name_len_off, name_off in (
        (b"PK\x01\x02", 24, 28, 46),
        (b"PK\x03\x04", 22, 26, 30),
    ):
        pos = 0
        while (pos := out.find(sig, pos)) >= 0:
            (nlen,) = struct.unpack_from("<H", out, pos + name_len_off)
            if bytes(out[pos + name_off : pos + name_off + nlen]) == name:
                struct.pack_into("<I", out, pos + size_off, file_size)
            pos += 4
    return bytes(out)


def patch_member_header(
    data: bytes,
    member: str,
    *,
    flags: int | None = None,
    method: int | None = None,
    version: int | None = None,
) -> bytes:
    """Set ``member``'s general-purpose flags, compression method or version-needed field in both
    its local and its central directory header."""
    out = bytearray(data)
    name = member.encode()
    # (signature, name length offset, name offset, version offset, flags offset, method offset)
    for sig, nl, no, vo, fo, mo in (
        (b"PK\x01\x02", 28, 46, 6, 8, 10),
        (b"PK\x03\x04", 26, 30, 4, 6, 8),
    ):
        pos = 0
        while (pos := out.find(sig, pos)) >= 0:
            (nlen,) = struct.unpack_from("<H", out, pos + nl)
            if bytes(out[pos + no : pos + no + nlen]) == name:
                for off, value in ((vo, version), (fo, flags), (mo, method)):
                    if value is not None:
                        struct.pack_into("<H", out, pos + off, value)
            pos += 4
    return bytes(out)


ZIP_HEADER_CASES = {
    "zip-flag-encrypted": {"flags": 0x1},
    "zip-flag-patched-data": {"flags": 0x20},
    "zip-flag-strong-encryption": {"flags": 0x40},
    "zip-version-needed-8.4": {"version": 84},
    "zip-method-unknown-99": {"method": 99},
}
#: On a chunk whose deflate data is intact, these header fields may be ignored by a reader that
#: inflates the data itself (the metadata variants must still be refused, or read).
ZIP_HEADER_HARMLESS_ON_CHUNK = {
    "zip-flag-patched-data", "zip-flag-strong-encryption", "zip-version-needed-8.4"
}  # fmt: skip


def sr_cases() -> Iterator[Case]:
    """The fixed ``.sr`` corpus (truncations are generated separately)."""
    raw = base_sr_raw()
    good = sr_bytes(raw)
    yield Case("valid", good, ".sr", "ok")
    yield Case("valid-one-member", sr_bytes(raw, members={"logic-1": raw}), ".sr", "ok")
    yield Case("valid-stored", sr_bytes(raw, compress=zipfile.ZIP_STORED), ".sr", "ok")
    # members
    yield Case("no-version", sr_bytes(raw, drop=["version"]), ".sr")
    yield Case("no-metadata", sr_bytes(raw, drop=["metadata"]), ".sr")
    yield Case("version-3", sr_bytes(raw, version=b"3"), ".sr")
    yield Case("version-junk", sr_bytes(raw, version=b"\xff\xfe\x00"), ".sr")
    yield Case("missing-chunk-2", sr_bytes(raw, drop=["logic-1-2"]), ".sr")
    yield Case("missing-chunk-1", sr_bytes(raw, drop=["logic-1-1"]), ".sr")
    yield Case("no-logic-members", sr_bytes(raw, members={}), ".sr")
    yield Case("empty-chunk", sr_bytes(b"", members={"logic-1-1": b""}), ".sr")
    yield Case("odd-chunk-unitsize-2", sr_bytes(raw[:999], metadata=sr_metadata(unitsize=2)), ".sr")
    # metadata values
    for label, kw in {
        "samplerate-0": {"samplerate": "0 Hz"},
        "samplerate-0-bare": {"samplerate": "0"},
        "samplerate-negative": {"samplerate": "-1 MHz"},
        "samplerate-junk": {"samplerate": "fast"},
        "samplerate-huge": {"samplerate": "99999999999999999999999 EHz"},
        "samplerate-nan": {"samplerate": "nan Hz"},
        "unitsize-0": {"unitsize": 0},
        "unitsize-missing": {"unitsize": None},
        "unitsize-negative": {"unitsize": -1},
        "unitsize-junk": {"unitsize": "one"},
        "unitsize-huge": {"unitsize": 10**12},
        "probes-65-unitsize-1": {"total": 65},
        "probes-0": {"total": 0},
        "probes-negative": {"total": -2},
        "probes-junk": {"total": "two"},
        "probe-number-out-of-range": {"extra": "probe99=X\n"},
        "capturefile-elsewhere": {"capturefile": "nothere"},
    }.items():
        meta = sr_metadata(**kw)  # type: ignore[arg-type]
        yield Case(f"meta-{label}", sr_bytes(raw, metadata=meta), ".sr")
    # no rate: `info` lists it in samples, `check` refuses (info_then_check allows that pair)
    yield Case(
        "meta-samplerate-missing",
        sr_bytes(raw, metadata=sr_metadata(samplerate=None)),
        ".sr",
        "either",
    )
    # 65 probes that do fit (unitsize 9): a valid, if odd, file
    names65 = [f"D{i}" for i in range(65)]
    raw65 = samples_from_edges(100, [(0, [10, 20])] + [(0, [])] * 64, unitsize=9).tobytes()
    yield Case(
        "probes-65-unitsize-9",
        sr_bytes(raw65, metadata=sr_metadata(names=names65, unitsize=9), chunk=9 * 40),
        ".sr",
        "ok",
    )
    yield Case("meta-binary", sr_bytes(raw, metadata="\x00\xff\xfe garbage"), ".sr")
    yield Case("meta-not-ini", sr_bytes(raw, metadata="just some words\n"), ".sr")
    yield Case("meta-no-device", sr_bytes(raw, metadata="[global]\nsigrok version=0.5.2\n"), ".sr")
    yield Case(
        "meta-duplicate-section",
        sr_bytes(raw, metadata=sr_metadata() + sr_metadata()),
        ".sr",
        "either",
    )
    # corrupt bytes inside a deflated chunk (CRC error or inflate error)
    for label, member in (
        ("chunk-1", "logic-1-1"),
        ("chunk-4", "logic-1-4"),
        ("metadata", "metadata"),
    ):
        yield Case(f"corrupt-{label}", corrupt_member(good, member), ".sr")
    # zip header fields that Python's zipfile refuses with NotImplementedError / RuntimeError
    for label, kw in ZIP_HEADER_CASES.items():
        expect: Expect = "either" if label in ZIP_HEADER_HARMLESS_ON_CHUNK else "error"
        yield Case(label, patch_member_header(good, "logic-1-3", **kw), ".sr", expect)
        yield Case(label + "-metadata", patch_member_header(good, "metadata", **kw), ".sr")
    for member in ("logic-1-3", "metadata"):  # deflate data declared as LZMA
        yield Case(
            f"zip-method-lzma-bogus-{member}", patch_member_header(good, member, method=14), ".sr"
        )
    # a local header name that is not UTF-8 although its flag says so (UnicodeDecodeError)
    # (on a chunk the data is intact: readers that skip the local name may accept it)
    yield Case("local-name-bad-utf8", bad_utf8_local_name(good, "logic-1-2"), ".sr", "either")
    yield Case("local-name-bad-utf8-metadata", bad_utf8_local_name(good, "metadata"), ".sr")
    # bytes cut out of the middle: zipfile seeks to a negative offset (OSError EINVAL)
    yield Case("bytes-removed-middle", good[:100] + good[400:], ".sr")
    yield Case("bytes-removed-start", good[20:], ".sr")
    # zip bombs: declared too large, and lying about its size
    yield Case(
        "declared-size-2GiB",
        _patch_central_sizes(good, "logic-1-1", (2 << 30) - 1),
        ".sr",
    )
    yield Case("size-lie-inflates-more", bomb_lying_size(), ".sr")
    # hostile shapes of issue 12: a chunk number far beyond the others (a reader listing the
    # missing numbers allocated 14 GB), and 1,000 directory entries on one deflate stream
    yield Case("chunk-number-1e11", sr_far_chunk(), ".sr")
    yield Case("overlapping-entries-1000", sr_overlapping_entries(), ".sr")
    yield Case("chunk-names-not-libsigrok", sr_odd_chunk_names(), ".sr", "ok")
    # wrong file types
    yield Case("png", b"\x89PNG\r\n\x1a\n" + bytes(200), ".sr")
    yield Case("text", b"hello, this is not a capture\n", ".sr")
    yield Case("empty", b"", ".sr")
    yield Case("nul-bytes", bytes(4096), ".sr")
    yield Case(
        "zip-of-other",
        sr_bytes(b"", members={"readme.txt": b"hi"}, drop=["version", "metadata"]),
        ".sr",
    )
    yield Case("elf", b"\x7fELF\x02\x01\x01" + bytes(100), ".sr")
    yield Case("vcd-named-sr", vcd_text().encode(), ".sr", "either")
    yield Case("zip-magic-only", b"PK\x03\x04", ".sr")


def corrupt_member(data: bytes, member: str) -> bytes:
    """Flip bytes in the middle of ``member``'s compressed data (its header stays intact)."""
    with zipfile.ZipFile(io.BytesIO(data)) as z:
        info = z.getinfo(member)
    out = bytearray(data)
    (nlen, xlen) = struct.unpack_from("<HH", out, info.header_offset + 26)
    start = info.header_offset + 30 + nlen + xlen
    mid = start + max(0, info.compress_size // 2)
    for i in range(mid, min(mid + 4, start + info.compress_size)):
        out[i] ^= 0x5A
    return bytes(out)


def bomb_lying_size(inflated: int = 64 << 20) -> bytes:
    """A chunk that inflates to ``inflated`` bytes but whose headers declare 4096."""
    comp = zlib.compressobj(9, zlib.DEFLATED, -15)
    zero = bytes(1 << 20)
    body = b"".join(comp.compress(zero) for _ in range(inflated >> 20)) + comp.flush()
    raw = base_sr_raw()
    good = sr_bytes(raw[:4096], members={"logic-1-1": raw[:4096]})
    with zipfile.ZipFile(io.BytesIO(good)) as z:
        info = z.getinfo("logic-1-1")
    out = bytearray(good)
    (nlen, xlen) = struct.unpack_from("<HH", out, info.header_offset + 26)
    start = info.header_offset + 30 + nlen + xlen
    # splice in the bomb's deflate stream, keep the declared sizes of the small chunk
    spliced = bytes(out[:start]) + body + bytes(out[start + info.compress_size :])
    delta = len(body) - info.compress_size
    fixed = bytearray(spliced)
    struct.pack_into("<I", fixed, info.header_offset + 18, len(body))
    cd = fixed.find(b"PK\x01\x02", start + len(body))
    while cd >= 0:
        (n2,) = struct.unpack_from("<H", fixed, cd + 28)
        if fixed[cd + 46 : cd + 46 + n2] == b"logic-1-1":
            struct.pack_into("<I", fixed, cd + 20, len(body))
        else:
            (off,) = struct.unpack_from("<I", fixed, cd + 42)
            if off > info.header_offset:
                struct.pack_into("<I", fixed, cd + 42, off + delta)
        cd = fixed.find(b"PK\x01\x02", cd + 4)
    eocd = fixed.rfind(b"PK\x05\x06")
    (cd_off,) = struct.unpack_from("<I", fixed, eocd + 16)
    struct.pack_into("<I", fixed, eocd + 16, cd_off + delta)
    return bytes(fixed)


def sr_far_chunk(number: int = 100_000_000_000) -> bytes:
    """A tiny ``.sr`` with chunks ``logic-1-1`` and ``logic-1-<number>`` (a gap of ``number``
    missing chunks: a reader that lists the missing numbers allocates all of them)."""
    raw = base_sr_raw(200)
    return sr_bytes(raw, members={"logic-1-1": raw, f"logic-1-{number}": raw})


def sr_odd_chunk_names(names: Sequence[str] = ("logic-1-02", "logic-1-0")) -> bytes:
    """A valid ``.sr`` plus members named like chunks that libsigrok never opens (it asks for
    ``"%s-%d"`` by exact name), holding a busy waveform that would change the verdict if read."""
    raw = base_sr_raw()
    busy = samples_from_edges(len(raw), [(0, range(1, len(raw) - 1)), (0, [])]).tobytes()
    members = {"logic-1-1": raw[:1000], "logic-1-2": raw[1000:]}
    members.update({name: busy for name in names})
    return sr_bytes(raw, members=members)


@functools.lru_cache(maxsize=4)
def sr_overlapping_entries(entries: int = 1000, inflated: int = 64 << 20) -> bytes:
    """A zip bomb by overlap: ``entries`` central-directory entries ``logic-1-1`` … all point
    at one deflate stream of ``inflated`` zero bytes (the file stays small; a reader that
    trusts the directory inflates ``entries × inflated`` bytes)."""
    comp = zlib.compressobj(6, zlib.DEFLATED, -15)
    zero = bytes(1 << 20)
    body = b"".join(comp.compress(zero) for _ in range(inflated >> 20)) + comp.flush()
    crc = 0
    for _ in range(inflated >> 20):
        crc = zlib.crc32(zero, crc)
    meta = sr_metadata().encode()
    out = io.BytesIO()
    central: list[bytes] = []

    def local(name: bytes, data: bytes, method: int, size: int, crc32: int) -> int:
        offset = out.tell()
        out.write(struct.pack("<4sHHHHHIIIHH", b"PK\x03\x04", 20, 0, method, 0, 0x21,
                              crc32, len(data), size, len(name), 0))  # fmt: skip
        out.write(name + data)
        return offset

    def cd_entry(name: bytes, method: int, csize: int, size: int, crc32: int, off: int) -> bytes:
        return struct.pack("<4sHHHHHHIIIHHHHHII", b"PK\x01\x02", 20, 20, 0, method, 0, 0x21,
                           crc32, csize, size, len(name), 0, 0, 0, 0, 0, off) + name  # fmt: skip

    off = local(b"version", b"2", 0, 1, zlib.crc32(b"2"))
    central.append(cd_entry(b"version", 0, 1, 1, zlib.crc32(b"2"), off))
    mc = zlib.compressobj(6, zlib.DEFLATED, -15)
    mdata = mc.compress(meta) + mc.flush()
    off = local(b"metadata", mdata, 8, len(meta), zlib.crc32(meta))
    central.append(cd_entry(b"metadata", 8, len(mdata), len(meta), zlib.crc32(meta), off))
    off = local(b"logic-1-1", body, 8, inflated, crc)
    for k in range(1, entries + 1):
        central.append(cd_entry(f"logic-1-{k}".encode(), 8, len(body), inflated, crc, off))
    cd_start = out.tell()
    for entry in central:
        out.write(entry)
    cd_size = out.tell() - cd_start
    out.write(struct.pack("<4sHHHHIIH", b"PK\x05\x06", 0, 0, len(central), len(central),
                          cd_size, cd_start, 0))  # fmt: skip
    return out.getvalue()


def bad_utf8_local_name(data: bytes, member: str) -> bytes:
    """Set the UTF-8 flag in ``member``'s local header and make its name bytes invalid UTF-8."""
    out = bytearray(data)
    name = member.encode()
    pos = 0
    while (pos := out.find(b"PK\x03\x04", pos)) >= 0:
        (nlen,) = struct.unpack_from("<H", out, pos + 26)
        if bytes(out[pos + 30 : pos + 30 + nlen]) == name:
            (flags,) = struct.unpack_from("<H", out, pos + 6)
            struct.pack_into("<H", out, pos + 6, flags | 0x800)
            out[pos + 30] = 0xC8
        pos += 4
    return bytes(out)


def truncation_offsets(size: int, count: int = 64) -> list[int]:
    """Offsets to cut a file of ``size`` bytes at: evenly spread plus both ends."""
    offs = {0, 1, 2, 3, 4, 5, 10, 22, 30, size - 1, size - 2, size - 22, size - 23}
    offs.update(size * k // count for k in range(count))
    return sorted(o for o in offs if 0 <= o < size)


# ---------------------------------------------------------------------------------------------
# VCD


def vcd_text(
    *,
    timescale: str = "1 ns",
    step: Sequence[int] = (100, 300, 1100, 1300, 2100, 2300),
    dirs: Sequence[int] = (1600,),
    end: int = 3000,
    header_extra: str = "",
    var_lines: Sequence[str] = (),
) -> str:
    """A small simulator-style VCD with wires ``STEP`` (``!``) and ``DIR`` (``"``)."""
    lines = []
    if timescale is not None:
        lines.append(f"$timescale {timescale} $end")
    lines += ["$scope module top $end", "$var wire 1 ! STEP $end", '$var wire 1 " DIR $end']
    lines += list(var_lines)
    lines += [
        "$upscope $end",
        header_extra,
        "$enddefinitions $end",
        "#0",
        "$dumpvars",
        "0!",
        '0"',
        "$end",
    ]
    events: dict[int, list[str]] = {}
    for code, edges in (("!", step), ('"', dirs)):
        level = 0
        for t in edges:
            level ^= 1
            events.setdefault(t, []).append(f"{level}{code}")
    for t in sorted(events):
        lines.append(f"#{t}")
        lines += events[t]
    lines.append(f"#{end}")
    return "\n".join(x for x in lines if x != "") + "\n"


def vcd_id(k: int) -> str:
    """The ``k``-th VCD id code in printable ASCII ``!`` … ``~`` (as simulators number them)."""
    chars = []
    while True:
        k, r = divmod(k, 94)
        chars.append(chr(33 + r))
        if k == 0:
            return "".join(chars)
        k -= 1


def vcd_many_vars(count: int = 200_000) -> bytes:
    """A VCD declaring ``count`` 1-bit wires (plus STEP and DIR), each changing once: a header
    parser that recounts lines from the start per ``$var`` is quadratic on it."""
    ids = [vcd_id(k + 2) for k in range(count)]
    decl = "".join(f"$var wire 1 {c} w{k} $end\n" for k, c in enumerate(ids))
    head = vcd_text(var_lines=[decl.rstrip("\n")])
    changes = "#3500\n" + "".join(f"1{c}\n" for c in ids) + "#4000\n"
    return (head + changes).encode()


def vcd_no_whitespace_body(size: int = 2 << 30) -> tuple[bytes, int]:
    """A valid header and then ``size`` NUL bytes and no whitespace (as a sparse file of that
    size reads): returns (the header bytes, the total size to extend the file to)."""
    head = vcd_text().encode()
    return head, len(head) + size


def vcd_cases() -> Iterator[Case]:
    """The fixed VCD corpus (truncations are generated separately)."""
    good = vcd_text()
    yield Case("valid", good.encode(), ".vcd", "ok")
    for ts in (
        "1 xs",
        "ns",
        "0 ns",
        "1 sec",
        "-1 ns",
        "1.5 ns",
        "1e3 ns",
        "1 foo",
        "",
        "99999999999999999999 s",
        "1000 s",
        "1 zs",
    ):
        text = good.replace("$timescale 1 ns $end", f"$timescale {ts} $end")
        yield Case(f"timescale-{ts or 'empty'}", text.encode(), ".vcd")
    for ts in ("3 ns", "10 ps", "100 us", "1ns", "1 s"):
        text = good.replace("$timescale 1 ns $end", f"$timescale {ts} $end")
        yield Case(f"timescale-ok-{ts}", text.encode(), ".vcd", "ok")
    yield Case("no-timescale", vcd_text(timescale=None).encode(), ".vcd", "ok")  # type: ignore[arg-type]
    yield Case("unknown-id", good.replace("#1100\n1!", "#1100\n1?").encode(), ".vcd")
    yield Case("unknown-multichar-id", good.replace("#1100\n1!", "#1100\n1!!q").encode(), ".vcd")
    yield Case("time-backwards", good.replace("#1100", "#50").encode(), ".vcd")
    yield Case("negative-time", good.replace("#1100", "#-1100").encode(), ".vcd")
    yield Case("time-21-digits", good.replace("#3000", "#" + "9" * 21).encode(), ".vcd")
    yield Case("time-19-digits", good.replace("#3000", "#9" + "0" * 18).encode(), ".vcd", "ok")
    yield Case("time-2^63-1", good.replace("#3000", f"#{(1 << 63) - 1}").encode(), ".vcd", "ok")
    yield Case("time-2^63", good.replace("#3000", f"#{1 << 63}").encode(), ".vcd")
    yield Case("many-vars-5000", vcd_many_vars(5_000), ".vcd", "ok")  # 200,000: test_hostile
    yield Case("no-whitespace-body", good.encode() + b"\x01" * (MAX_TOKEN_TEST + 1), ".vcd")
    yield Case("time-not-number", good.replace("#1100", "#11a0").encode(), ".vcd")
    yield Case("bare-hash", good.replace("#1100", "#").encode(), ".vcd")
    yield Case(
        "duplicate-timestamp",
        good.replace("#1300\n0!", "#1100\n#1100\n0!\n1!\n#1300\n0!").encode(),
        ".vcd",
        "ok",
    )
    yield Case("xz-on-step", good.replace("#2100\n1!", "#2100\nx!").encode(), ".vcd", "either")
    yield Case("z-on-dir", good.replace('#1600\n1"', '#1600\nz"').encode(), ".vcd", "either")
    yield Case("nul-tail", good.encode() + bytes(4096), ".vcd")
    yield Case("nul-after-cut", good.encode()[: len(good) - 20] + bytes(4096), ".vcd")
    yield Case("garbage-line", good.replace("#1100", "hello world\n#1100").encode(), ".vcd")
    yield Case("no-enddefinitions", good.replace("$enddefinitions $end", "").encode(), ".vcd")
    yield Case("only-header", good.split("#0")[0].encode(), ".vcd")
    yield Case(
        "header-cut-in-var",
        b"$timescale 1 ns $end\n$scope module top $end\n$var wire 1 ! STE",
        ".vcd",
    )
    yield Case("unknown-keyword-body", good.replace("#1100", "$bogus\n#1100").encode(), ".vcd")
    yield Case("crlf", good.replace("\n", "\r\n").encode(), ".vcd", "ok")
    yield Case(
        "latin1-name",
        vcd_text(var_lines=["$var wire 1 # caf\xe9 $end"]).encode("latin-1"),
        ".vcd",
        "ok",
    )
    yield Case("utf8-bom", b"\xef\xbb\xbf" + good.encode(), ".vcd", "either")
    huge = vcd_text(var_lines=["$var wire 999999999999999999999 # huge $end"])
    yield Case("huge-declared-width", huge.encode(), ".vcd", "either")
    wide = vcd_text(var_lines=["$var wire 100000 # wide $end"]).replace(
        "#1100\n", "#1100\nb" + "1" * 100000 + " #\n"
    )
    yield Case("wide-vector-value", wide.encode(), ".vcd", "either")
    yield Case("var-width-0", vcd_text(var_lines=["$var wire 0 # w0 $end"]).encode(), ".vcd")
    # str.isdigit() is true for '¹' (byte 0xB9 read as latin-1), int() is not
    sup = vcd_text(var_lines=["$var wire 1\xb9 # sup $end"]).encode("latin-1")
    yield Case("var-width-superscript", sup, ".vcd")
    yield Case("var-width-junk", vcd_text(var_lines=["$var wire abc # wj $end"]).encode(), ".vcd")
    yield Case("var-short", vcd_text(var_lines=["$var wire 1 $end"]).encode(), ".vcd")
    yield Case(
        "id-too-long",
        vcd_text(var_lines=["$var wire 1 " + "x" * 200 + " long $end"]).encode(),
        ".vcd",
    )
    yield Case("vector-on-1bit-no-id", good.replace("#1100\n1!", "#1100\nb1").encode(), ".vcd")
    yield Case("real-on-1bit", good.replace("#1100\n1!", "#1100\nr1.5 !").encode(), ".vcd")
    yield Case(
        "comment-unterminated", good.replace("#1100", "$comment never ends\n#1100").encode(), ".vcd"
    )
    yield Case("value-without-id-at-end", good.encode() + b"1", ".vcd")
    yield Case("binary-junk", bytes(range(256)) * 4, ".vcd")
    yield Case("empty", b"", ".vcd")
    yield Case("whitespace", b"   \n\n\t ", ".vcd")
    yield Case("zip-named-vcd", sr_bytes(base_sr_raw()), ".vcd", "either")
    yield Case(
        "no-body-timestamps",
        (good.split("#0")[0] + "$dumpvars\n0!\n$end\n").encode(),
        ".vcd",
        "either",
    )


def rule_text(**override: str | None) -> str:
    """A complete, valid rule file; ``override`` replaces (or with None removes) lines by key path."""
    parts = {
        "id": 'id = "fuzz-drive"',
        "name": 'name = "Fuzz drive"',
        "kind": 'kind = "user"',
        "interface": 'interface = "step-dir"',
        "active_edge": '[active_edge]\nvalue = "rising"\nsource = "S1"\nstatus = "datasheet"',
        "step_high": '[limits.step_high]\nvalue = "2us"\nsource = "S1"\nstatus = "datasheet"',
        "step_low": '[limits.step_low]\nvalue = "2us"\nsource = "S1"\nstatus = "datasheet"',
        "dir_setup": '[limits.dir_setup]\nvalue = "1us"\nsource = "S1"\nstatus = "datasheet"',
        "dir_hold": '[limits.dir_hold]\nvalue = "1us"\nsource = "S1"\nstatus = "datasheet"',
        "max_rate": '[limits.max_rate]\nvalue = "100 kHz"\nsource = "S1"\nstatus = "datasheet"',
        "sources": '[sources]\nS1 = "made up for tests"',
    }
    for key, value in override.items():
        if value is None:
            parts.pop(key, None)
        else:
            parts[key] = value
    top = [parts[k] for k in ("id", "name", "kind", "interface") if k in parts]
    rest = [v for k, v in parts.items() if k not in ("id", "name", "kind", "interface")]
    return "\n".join(top) + "\n\n" + "\n\n".join(rest) + "\n"


def _limit(key: str, value: str, **extra: str) -> str:
    lines = [f"[limits.{key}]", f"value = {value}", 'source = "S1"', 'status = "datasheet"']
    lines += [f"{k} = {v}" for k, v in extra.items()]
    return "\n".join(lines)


def rule_cases() -> Iterator[Case]:
    """Rule files: one valid, the rest each broken in one way."""
    yield Case("valid", rule_text().encode(), ".toml", "ok")
    for key in ("id", "name", "kind", "interface", "active_edge", "sources"):
        yield Case(f"missing-{key}", rule_text(**{key: None}).encode(), ".toml")
    none = {k: None for k in ("step_high", "step_low", "dir_setup", "dir_hold", "max_rate")}
    yield Case("no-limits-at-all", rule_text(**none).encode(), ".toml")
    for label, value in {
        "negative": '"-1us"',
        "non-numeric": '"fast"',
        "unknown-unit": '"4.5 furlongs"',
        "frequency-as-time": '"10 kHz"',
        "bare-number": "4.5",
        "bare-negative": "-3",
        "boolean": "true",
        "empty-string": '""',
        "nan": '"nan us"',
        "inf": '"inf us"',
        "array": '["1us"]',
        "huge": '"1e400 us"',
    }.items():
        yield Case(
            f"step_high-{label}", rule_text(step_high=_limit("step_high", value)).encode(), ".toml"
        )
    for label, value in {
        "zero": '"0 Hz"',
        "negative": '"-5 kHz"',
        "time": '"5 us"',
        "junk": '"many"',
    }.items():
        yield Case(
            f"max_rate-{label}", rule_text(max_rate=_limit("max_rate", value)).encode(), ".toml"
        )
    yield Case(
        "limit-no-value",
        rule_text(step_high='[limits.step_high]\nsource = "S1"\nstatus = "datasheet"').encode(),
        ".toml",
    )
    yield Case(
        "limit-no-source",
        rule_text(step_high='[limits.step_high]\nvalue = "2us"\nstatus = "datasheet"').encode(),
        ".toml",
    )
    yield Case(
        "limit-unknown-source",
        rule_text(step_high=_limit("step_high", '"2us"').replace('"S1"', '"S9"')).encode(),
        ".toml",
    )
    yield Case(
        "limit-bad-status",
        rule_text(
            step_high=_limit("step_high", '"2us"').replace('"datasheet"', '"maybe"')
        ).encode(),
        ".toml",
    )
    yield Case("unknown-rule", rule_text(dir_hold=_limit("dir_wobble", '"1us"')).encode(), ".toml")
    yield Case("unknown-top-key", rule_text(name='name = "x"\ncolour = "red"').encode(), ".toml")
    yield Case("bad-interface", rule_text(interface='interface = "telepathy"').encode(), ".toml")
    yield Case(
        "bad-edge",
        rule_text(
            active_edge='[active_edge]\nvalue = "sideways"\nsource = "S1"\nstatus = "datasheet"'
        ).encode(),
        ".toml",
    )
    yield Case("bad-kind", rule_text(kind='kind = "toaster"').encode(), ".toml")
    yield Case("bad-id", rule_text(id='id = "Not An Id!"').encode(), ".toml")
    yield Case("id-number", rule_text(id="id = 7").encode(), ".toml")
    yield Case("toml-syntax", b'id = "x\nname = ', ".toml")
    yield Case("binary", bytes(range(256)), ".toml")
    yield Case("empty", b"", ".toml")
    yield Case("utf16", rule_text().encode("utf-16"), ".toml")
    yield Case("limits-not-table", (rule_text(**none) + "limits = 5\n").encode(), ".toml")


# ---------------------------------------------------------------------------------------------
# contract checks


def one_line_error(err: str, path: str) -> str | None:
    """Why ``err`` (stderr of a run that exited 2) breaks the error contract, or None if it is fine."""
    lines = [ln for ln in err.splitlines() if ln.strip()]
    if "Traceback" in err:
        return "traceback on stderr"
    if len(lines) != 1:
        return f"{len(lines)} lines on stderr, not 1: {err[:300]!r}"
    if path not in lines[0]:
        return f"message does not name the file {path!r}: {lines[0]!r}"
    return None


_ = re  # used by callers' patterns
