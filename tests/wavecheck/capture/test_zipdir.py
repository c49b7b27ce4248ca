"""The zip directory reader (capture/zipdir.py) against CPython's zipfile: the same entries for
every real .sr and for zips zipfile writes (stored/deflated, empty, ZIP64, comments, extra
fields, data descriptors, non-ASCII names, prepended data); damaged copies give zipfile's
entries, or zipfile's own error, never another exception, reading a bounded number of bytes."""

from __future__ import annotations

import io
import os
import struct
import warnings
import zipfile
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from tests.conftest import REPO, SHARED_CAPTURES
from wavecheck.capture import zipdir
from wavecheck.capture.zipdir import Archive, ZipError, read_directory

FIELDS = ("filename", "header_offset", "compress_size", "file_size", "CRC", "compress_type",
          "flag_bits")  # fmt: skip
REAL_SR = sorted({*SHARED_CAPTURES.rglob("*.sr"), *(REPO / "captures").rglob("*.sr")})


def _row(info: Any) -> tuple[Any, ...]:
    return tuple(getattr(info, f) for f in FIELDS)


def _refusal(err: BaseException) -> tuple[str, str]:
    """What Archive must raise for an exception of zipfile's (its refusals become ZipError)."""
    import lzma

    refused = (zipfile.BadZipFile, NotImplementedError, RuntimeError, ValueError, lzma.LZMAError)
    return ("ZipError" if isinstance(err, refused) else type(err).__name__, str(err))


def _zipfile_view(path: Path) -> tuple[Any, ...]:
    """zipfile's entries, start of directory and members (or the error of each)."""
    try:
        with zipfile.ZipFile(path) as zf:
            members: dict[str, Any] = {}
            for name in zf.namelist():
                try:
                    members[name] = zf.read(name)
                except Exception as err:  # noqa: BLE001 - compared with ours below
                    members[name] = _refusal(err)
            return [_row(i) for i in zf.infolist()], zf.start_dir, members
    except Exception as err:  # noqa: BLE001
        return (_refusal(err),)


def _archive_view(path: Path) -> tuple[Any, ...]:
    try:
        with Archive(path) as zf:
            members: dict[str, Any] = {}
            for name in zf.namelist():
                try:
                    members[name] = zf.read(name)
                except Exception as err:  # noqa: BLE001
                    members[name] = (type(err).__name__, str(err))
            return [_row(e) for e in zf.infolist()], zf.start_dir, members
    except Exception as err:  # noqa: BLE001
        return ((type(err).__name__, str(err)),)


class _Counted(io.BytesIO):
    """A file that counts the bytes read from it."""

    read_bytes = 0

    def read(self, size: int | None = -1) -> bytes:
        data = super().read(size)
        self.read_bytes += len(data)
        return data


def _ours(data: bytes) -> tuple[Any, ...] | None:
    f = _Counted(data)
    found = read_directory(f)
    # one look at the end record (≤ 64 KiB + 22 bytes), the ZIP64 records, the directory once
    assert f.read_bytes <= (1 << 16) + 22 + 22 + 20 + 56 + len(data)
    if found is None:
        return None
    entries, start_dir = found
    return [_row(e) for e in entries], start_dir


def _check(path: Path, *, ordinary: bool = False) -> None:
    theirs = _zipfile_view(path)
    ours = _ours(path.read_bytes())
    if ours is not None:
        assert len(theirs) == 3, f"zipfile refuses what zipdir reads: {theirs}"
        assert ours == theirs[:2]
    elif ordinary and len(theirs) == 3:
        pytest.fail("an ordinary zip zipfile reads was left to zipfile")
    assert _archive_view(path) == theirs


@pytest.mark.parametrize("path", REAL_SR, ids=lambda p: p.name)
def test_every_real_sr_gives_zipfiles_directory_and_members(path: Path) -> None:
    _check(path, ordinary=True)


def test_the_real_corpus_is_there() -> None:
    if os.environ.get("CI") == "true" or SHARED_CAPTURES.exists():
        assert len(REAL_SR) >= 60  # 66 .sr files on 29 Nov 2026


class _Unseekable(io.RawIOBase):
    """An output zipfile cannot seek back in: it writes data descriptors (flag bit 3)."""

    def __init__(self) -> None:
        self.buf = io.BytesIO()

    def writable(self) -> bool:
        return True

    def write(self, b: Any) -> int:
        return self.buf.write(b)


_names = st.text(
    st.characters(blacklist_categories=("Cs",), blacklist_characters="\0"), min_size=1, max_size=8
)
_member = st.tuples(
    _names | st.sampled_from(["version", "metadata", "logic-1-1", "logic-1-2"]),
    st.binary(max_size=600) | st.just(b""),
    st.sampled_from([zipfile.ZIP_STORED, zipfile.ZIP_DEFLATED]),
    st.booleans(),  # written through a stream (sizes known at the end only)
    st.booleans(),  # force ZIP64
    st.binary(max_size=12),  # payload of an extra field of ours
)


@st.composite
def zips(draw: st.DrawFn) -> bytes:
    members = draw(st.lists(_member, min_size=0, max_size=6))
    out: Any = _Unseekable() if draw(st.booleans()) else io.BytesIO()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # duplicate names
        with zipfile.ZipFile(out, "w") as zf:
            for name, data, method, streamed, zip64, payload in members:
                info = zipfile.ZipInfo(name)
                info.compress_type = method
                info.extra = struct.pack("<HH", 0xCAFE, len(payload)) + payload
                if streamed:
                    with zf.open(info, "w", force_zip64=zip64) as fh:
                        fh.write(data)
                else:
                    zf.writestr(info, data)
            zf.comment = comment = draw(st.binary(max_size=80) | st.just(b"PK\x05\x06" * 3))
    data = (out.buf if isinstance(out, _Unseekable) else out).getvalue()
    if draw(st.booleans()):
        data = _zip64_end(data, len(comment))
    return draw(st.binary(max_size=40)) + data  # data before the zip (a self-extractor's stub)


def _zip64_end(data: bytes, comment_len: int = 0) -> bytes:
    """The zip with ZIP64 end records, as zipfile writes them past 65535 entries or 4 GiB: the
    ZIP64 record and locator, then an end record saying 0xFFFF / 0xFFFFFFFF."""
    at = len(data) - 22 - comment_len
    _, _, _, _, count, size, offset, _ = zipdir._EOCD.unpack_from(data, at)
    rec64 = zipdir._EOCD64.pack(b"PK\x06\x06", 44, 45, 45, 0, 0, count, count, size, offset)
    locator = zipdir._LOCATOR64.pack(b"PK\x06\x07", 0, at, 1)
    end = zipdir._EOCD.pack(b"PK\x05\x06", 0, 0, 0xFFFF, 0xFFFF, 0xFFFF_FFFF, 0xFFFF_FFFF,
                            comment_len)  # fmt: skip
    return data[:at] + rec64 + locator + end + data[at + 22 :]


@settings(max_examples=150, suppress_health_check=[HealthCheck.too_slow])
@given(data=zips())
def test_zips_zipfile_writes_give_zipfiles_directory(data: bytes, tmp_path_factory: Any) -> None:
    path = tmp_path_factory.mktemp("z") / "a.zip"
    path.write_bytes(data)
    _check(path, ordinary=True)


@st.composite
def damaged(draw: st.DrawFn) -> bytes:
    data = bytearray(draw(zips()))
    assume(data)
    for _ in range(draw(st.integers(1, 3))):
        kind = draw(st.sampled_from(["cut", "flip", "overwrite"]))
        if not data:
            break
        at = draw(st.integers(0, len(data) - 1))
        if kind == "cut":
            del data[at:]
        elif kind == "flip":
            data[at] ^= draw(st.integers(1, 255))
        else:
            patch = draw(st.binary(min_size=1, max_size=8))
            data[at : at + len(patch)] = patch
    return bytes(data)


@settings(max_examples=300, suppress_health_check=[HealthCheck.too_slow])
@given(data=damaged())
def test_damaged_zips_give_zipfiles_directory_or_its_error(
    data: bytes, tmp_path_factory: Any
) -> None:
    path = tmp_path_factory.mktemp("z") / "a.zip"
    path.write_bytes(data)
    _check(path)


def _utf8_flag_cleared(data: bytes) -> bytes:
    """The zip with the UTF-8 name flag cleared in every header (names then read as cp437)."""
    out = bytearray(data)
    for sig, at in ((b"PK\x01\x02", 8), (b"PK\x03\x04", 6)):
        pos = out.find(sig)
        while pos >= 0:
            flags = struct.unpack_from("<H", out, pos + at)[0]
            struct.pack_into("<H", out, pos + at, flags & ~0x800)
            pos = out.find(sig, pos + 4)
    return bytes(out)


def _central(data: bytes, at: int, value: int) -> bytes:
    """The zip with the 16-bit field at ``at`` of its first directory entry set to ``value``."""
    out = bytearray(data)
    struct.pack_into("<H", out, out.find(b"PK\x01\x02") + at, value)
    return bytes(out)


def _zip(**members: bytes) -> bytes:
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED) as zf:
        for name, data in members.items():
            zf.writestr(name, data)
    return buf.getvalue()


@pytest.mark.parametrize(
    ("what", "data"),
    [
        ("a cp437 name beyond ASCII", _utf8_flag_cleared(_zip(**{"é": b"x", "version": b"2"}))),
        ("a NUL in a name", _zip(aQb=b"x").replace(b"aQb", b"a\0b")),
        ("an encrypted entry", _central(_zip(version=b"2"), 8, 0x1)),  # flag bit 0
        ("bzip2", _central(_zip(version=b"2"), 10, zipfile.ZIP_BZIP2)),
        ("a later zip version", _central(_zip(version=b"2"), 6, 64)),
    ],
    ids=lambda v: v if isinstance(v, str) else "",
)
def test_what_zipdir_does_not_take_is_left_to_zipfile(
    what: str, data: bytes, tmp_path: Path
) -> None:
    path = tmp_path / "a.zip"
    path.write_bytes(data)
    assert _ours(data) is None
    _check(path)  # zipfile's entries and members, or its error


def test_a_member_with_a_bad_crc_gives_zipfiles_error(tmp_path: Path) -> None:
    data = bytearray(_zip(version=b"2", metadata=b"[device 1]\n"))
    at = data.find(b"PK\x01\x02") + 16  # the CRC-32 in the directory
    data[at] ^= 0xFF
    path = tmp_path / "a.zip"
    path.write_bytes(bytes(data))
    with Archive(path) as zf:
        assert not zf.by_zipfile
        with pytest.raises(ZipError, match="Bad CRC-32 for file 'version'"):
            zf.read("version")
    _check(path)


@pytest.mark.parametrize("comment", [b"", b"a comment"])
def test_a_zip64_archive_is_read_here(comment: bytes, tmp_path: Path) -> None:
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as zf:
        for n in range(3):
            with zf.open(f"logic-1-{n + 1}", "w", force_zip64=True) as fh:  # ZIP64 extra fields
                fh.write(bytes(100))
        zf.comment = comment
    data = b"stub" + _zip64_end(buf.getvalue(), len(comment))
    path = tmp_path / "a.zip"
    path.write_bytes(data)
    entries = _ours(data)
    assert entries is not None and len(entries[0]) == 3 and entries[0][0][1] == 4
    _check(path, ordinary=True)


def test_a_directory_larger_than_the_bound_is_left_to_zipfile(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    data = _zip(version=b"2", metadata=b"[device 1]\n")
    monkeypatch.setattr(zipdir, "MAX_DIRECTORY_BYTES", 50)
    assert _ours(data) is None
    path = tmp_path / "a.zip"
    path.write_bytes(data)
    _check(path)


def test_a_directory_offset_past_its_place_gives_zipfiles_reading(tmp_path: Path) -> None:
    """The end record puts the directory 10 bytes later than it is: zipfile takes the 10 bytes
    as missing from the front, so the first local header is at -10; its read is zipfile's."""
    data = bytearray(_zip(version=b"2", metadata=b"[device 1]\n"))
    at = len(data) - 22 + 16  # the directory's offset in the end record
    struct.pack_into("<L", data, at, struct.unpack_from("<L", data, at)[0] + 10)
    path = tmp_path / "a.zip"
    path.write_bytes(bytes(data))
    ours = _ours(bytes(data))
    assert ours is not None and ours[0][0][1] == -10
    _check(path)
