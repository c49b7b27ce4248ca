"""A zip archive's directory and small members, read without :mod:`zipfile` when it is ordinary.

Importing ``zipfile`` costs a check of a ``.sr`` about 3 ms of CPU (it brings ``threading``,
``bz2``, ``lzma``, ``binascii``, ``encodings.cp437``; ``python -X importtime``), a share of the
~6 ms issue 38 needed. The reader here gives the values ``zipfile`` gives (CPython 3.11's
``_EndRecData``, ``_EndRecData64``, ``_RealGetContents``, ``ZipInfo._decodeExtra``; the same
entries as 3.12's and 3.13's zipfile on 4000 random and damaged zips each) for what a
``.sr`` holds: one disk, stored or deflated members, ASCII or UTF-8-flagged names, ZIP64 records
and extra fields, an archive comment, data prepended to the archive. Anything else (more disks,
encryption, other methods, a name in cp437 beyond ASCII or with a NUL, a record that does not add
up) is left to ``zipfile`` itself, so the result or the error is exactly what ``zipfile`` says;
its errors reach the caller as :class:`ZipError` with ``zipfile``'s message.

Work and memory are bounded by the file: the directory is read once (at most
:data:`MAX_DIRECTORY_BYTES`, else ``zipfile`` reads it), every entry takes 46 bytes or more of
it, and a member is inflated to at most its stated size plus one byte.
"""

from __future__ import annotations

import os
import struct
import zlib
from collections.abc import Iterator
from typing import TYPE_CHECKING, Any, BinaryIO

if TYPE_CHECKING:
    import zipfile

__all__ = ["ZIP_DEFLATED", "ZIP_STORED", "Archive", "Entry", "ZipError", "read_directory"]

ZIP_STORED = 0
ZIP_DEFLATED = 8
#: Central directories larger than this are left to ``zipfile`` (a .sr has a few hundred bytes).
MAX_DIRECTORY_BYTES = 1 << 24

_EOCD = struct.Struct("<4s4H2LH")  # end of central directory
_LOCATOR64 = struct.Struct("<4sLQL")  # ZIP64 end of central directory locator
_EOCD64 = struct.Struct("<4sQ2H2L4Q")  # ZIP64 end of central directory record
_CENTRAL = struct.Struct("<4s4B4HL2L5H2L")  # central directory file header
_LOCAL = struct.Struct("<4s2B4HL2L2H")  # local file header
_MAX_EXTRACT_VERSION = 63  # zipfile refuses entries that need a later version
_UTF8_NAME = 0x800
_UNSUPPORTED_FLAGS = 0x1 | 0x20 | 0x40  # encrypted, patched data, strong encryption
_UNICODE_PATH_EXTRA = 0x7075  # newer zipfiles take the name from it: left to zipfile
#: The values that say "in the ZIP64 extra field" (``ZipInfo._decodeExtra``'s tests, kept as is)
_UNKNOWN = {
    "file_size": (0xFFFF_FFFF_FFFF_FFFF, 0xFFFF_FFFF),
    "compress_size": (0xFFFF_FFFF,),
    "header_offset": (0xFFFF_FFFF,),
}


class ZipError(Exception):
    """The archive or a member cannot be read (``zipfile``'s message where it said so)."""


class Entry:
    """One central directory entry, with :class:`zipfile.ZipInfo`'s attribute names."""

    __slots__ = ("CRC", "compress_size", "compress_type", "file_size", "filename",
                 "flag_bits", "header_offset", "end_offset", "info")  # fmt: skip

    def __init__(self, filename: str, header_offset: int, compress_size: int, file_size: int,
                 crc: int, compress_type: int, flag_bits: int) -> None:  # fmt: skip
        self.filename = filename
        self.header_offset = header_offset
        self.compress_size = compress_size
        self.file_size = file_size
        self.CRC = crc
        self.compress_type = compress_type
        self.flag_bits = flag_bits
        self.end_offset = 0
        """Where the entry's room ends: the next entry's local header, or the directory."""
        self.info: Any = None
        """``zipfile``'s ``ZipInfo`` of the entry when ``zipfile`` read the directory."""

    def __repr__(self) -> str:
        return f"<Entry {self.filename!r} at {self.header_offset}>"


def _end_record(f: BinaryIO, size: int) -> tuple[tuple[Any, ...], int] | None:
    """The end of central directory record and its offset, found as ``zipfile`` finds it: at the
    very end (no comment), else the last signature within the last 64 KiB + 22 bytes."""
    if size < _EOCD.size:
        return None
    f.seek(size - _EOCD.size)
    tail = f.read(_EOCD.size)
    if tail[:4] == b"PK\x05\x06" and tail[-2:] == b"\0\0":
        return _EOCD.unpack(tail), size - _EOCD.size
    start = max(size - (1 << 16) - _EOCD.size, 0)
    f.seek(start)
    data = f.read()
    at = data.rfind(b"PK\x05\x06")
    if at < 0 or len(data) - at < _EOCD.size:
        return None
    return _EOCD.unpack_from(data, at), start + at


def _zip64(f: BinaryIO, eocd_at: int) -> tuple[tuple[Any, ...] | None, bool]:
    """The ZIP64 record (just before its locator, just before the end record: ``zipfile``'s
    assumption) or None; False when ``zipfile`` must decide (more disks, a short file)."""
    if eocd_at < _LOCATOR64.size:
        return None, True
    f.seek(eocd_at - _LOCATOR64.size)
    loc = f.read(_LOCATOR64.size)
    if len(loc) < _LOCATOR64.size or loc[:4] != b"PK\x06\x07":
        return None, True
    _, disk, _, disks = _LOCATOR64.unpack(loc)
    at = eocd_at - _LOCATOR64.size - _EOCD64.size
    if disk != 0 or disks > 1 or at < 0:
        return None, False
    f.seek(at)
    rec = f.read(_EOCD64.size)
    if len(rec) < _EOCD64.size or rec[:4] != b"PK\x06\x06":
        return None, True
    return _EOCD64.unpack(rec), True


def _name(raw: bytes, flags: int) -> str | None:
    """The entry name as ``zipfile`` decodes it, or None where that is left to ``zipfile``."""
    if flags & _UTF8_NAME:
        try:
            name = raw.decode("utf-8")
        except UnicodeDecodeError:
            return None
    elif raw.isascii():
        name = raw.decode("ascii")  # cp437 is ASCII below 0x80
    else:
        return None
    return None if "\0" in name else name


def _apply_extra(entry: Entry, extra: bytes) -> bool:
    """Take the ZIP64 sizes and offset from the extra fields (``ZipInfo._decodeExtra``); False
    where ``zipfile`` would refuse them or may read them otherwise."""
    while len(extra) >= 4:
        tp, ln = struct.unpack_from("<HH", extra)
        if ln + 4 > len(extra) or tp == _UNICODE_PATH_EXTRA:
            return False
        if tp == 1:
            data = extra[4 : ln + 4]
            for field in ("file_size", "compress_size", "header_offset"):
                if getattr(entry, field) in _UNKNOWN[field]:
                    if len(data) < 8:
                        return False
                    setattr(entry, field, int.from_bytes(data[:8], "little"))
                    data = data[8:]
        extra = extra[ln + 4 :]
    return True


def read_directory(f: BinaryIO) -> tuple[list[Entry], int] | None:
    """The entries of the zip file ``f`` in directory order and where the directory starts;
    None when the archive is not one this reader takes (``zipfile`` then says what it is)."""
    size = f.seek(0, os.SEEK_END)
    found = _end_record(f, size)
    if found is None:
        return None
    (_, disk, disk_dir, _, _, size_cd, offset_cd, _), eocd_at = found
    rec64, ours = _zip64(f, eocd_at)
    if not ours:
        return None
    concat = eocd_at - size_cd - offset_cd
    if rec64 is not None:
        disk, disk_dir, size_cd, offset_cd = rec64[4], rec64[5], rec64[8], rec64[9]
        concat = eocd_at - size_cd - offset_cd - _EOCD64.size - _LOCATOR64.size
    start_dir = offset_cd + concat
    if disk or disk_dir or start_dir < 0 or size_cd > MAX_DIRECTORY_BYTES:
        return None
    if start_dir + size_cd > size:
        return None
    f.seek(start_dir)
    data = f.read(size_cd)
    entries: list[Entry] = []
    pos = 0
    while pos < size_cd:
        if size_cd - pos < _CENTRAL.size:
            return None
        head = _CENTRAL.unpack_from(data, pos)
        name_len, extra_len, comment_len = head[12:15]
        name_at = pos + _CENTRAL.size
        end = name_at + name_len + extra_len + comment_len
        flags, method = head[5], head[6]
        if (head[0] != b"PK\x01\x02" or end > size_cd or head[3] > _MAX_EXTRACT_VERSION
                or flags & _UNSUPPORTED_FLAGS or method not in (ZIP_STORED, ZIP_DEFLATED)):  # fmt: skip
            return None
        name = _name(data[name_at : name_at + name_len], flags)
        if name is None:
            return None
        entry = Entry(name, head[18], head[10], head[11], head[9], method, flags)
        if not _apply_extra(entry, data[name_at + name_len : name_at + name_len + extra_len]):
            return None
        entry.header_offset += concat
        entries.append(entry)
        pos = end
    _set_end_offsets(entries, start_dir)
    return entries, start_dir


def _set_end_offsets(entries: list[Entry], start_dir: int) -> None:
    """Each entry's room ends at the next local header up, or the directory (as ``zipfile``
    sets ``ZipInfo._end_offset``; of entries at one offset, the one listed first gets the room)."""
    end = start_dir
    for entry in sorted(entries, key=lambda e: e.header_offset, reverse=True):
        entry.end_offset = end
        end = entry.header_offset


def read_member(f: BinaryIO, entry: Entry) -> bytes | None:
    """The bytes of a stored or deflated member whose local header, room, length and CRC-32 are
    all right; None otherwise (``zipfile`` then reads it, or says why it cannot)."""
    if entry.header_offset < 0:  # data prepended less than the directory says: zipfile's error
        return None
    f.seek(entry.header_offset)
    head = f.read(_LOCAL.size)
    if len(head) < _LOCAL.size or head[:4] != b"PK\x03\x04":
        return None
    fields = _LOCAL.unpack(head)
    name_len, extra_len = fields[10], fields[11]
    if _name(f.read(name_len), fields[3]) != entry.filename:
        return None
    start = entry.header_offset + _LOCAL.size + name_len + extra_len
    if start + entry.compress_size > entry.end_offset:
        return None
    f.seek(start)
    comp = f.read(entry.compress_size)
    if len(comp) != entry.compress_size:
        return None
    if entry.compress_type == ZIP_STORED:
        data = comp
    else:
        inflater = zlib.decompressobj(-15)
        try:
            data = inflater.decompress(comp, entry.file_size + 1)
        except zlib.error:
            return None
        if not inflater.eof:
            return None
    if len(data) != entry.file_size or zlib.crc32(data) != entry.CRC:
        return None
    return data


def _refusals() -> tuple[type[BaseException], ...]:
    """What ``zipfile`` raises for a corrupt or exotic archive: ``BadZipFile``, and for
    encryption, flag bits 5/6, "version needed", unknown methods, a non-UTF-8 name under the
    UTF-8 flag or bogus LZMA data ``RuntimeError``, ``NotImplementedError``, ``ValueError``,
    ``LZMAError``."""
    import lzma
    import zipfile

    return (zipfile.BadZipFile, NotImplementedError, RuntimeError, ValueError, lzma.LZMAError)


class Archive:
    """A zip file open for reading: its entries (:class:`Entry`), named members' bytes and
    members' blocks; read here when ordinary (:func:`read_directory`), else by ``zipfile``.

    Raises (from every method): :class:`ZipError` with ``zipfile``'s message where it refused,
    ``OSError`` (opening the file), ``EOFError`` or ``zlib.error`` (``zipfile``'s reads)."""

    def __init__(self, path: str | os.PathLike[str]) -> None:
        self.path = path
        self.raw: BinaryIO = open(path, "rb")
        self._zf: zipfile.ZipFile | None = None
        try:
            found = read_directory(self.raw)
            self.by_zipfile = found is None
            """True when ``zipfile`` read the directory (not an ordinary archive)."""
            if found is None:
                found = self._from_zipfile()
        except BaseException:
            self.close()
            raise
        self.entries, self.start_dir = found
        self._by_name = {e.filename: e for e in self.entries}  # the last of a name, as zipfile

    def _zipfile(self) -> zipfile.ZipFile:
        if self._zf is None:
            import zipfile

            try:
                self._zf = zipfile.ZipFile(self.path)
            except _refusals() as err:
                raise ZipError(str(err)) from None
        return self._zf

    def _from_zipfile(self) -> tuple[list[Entry], int]:
        zf = self._zipfile()
        entries = []
        for info in zf.infolist():
            entry = Entry(info.filename, info.header_offset, info.compress_size, info.file_size,
                          info.CRC, info.compress_type, info.flag_bits)  # fmt: skip
            entry.info = info
            entries.append(entry)
        _set_end_offsets(entries, zf.start_dir)
        return entries, zf.start_dir

    def infolist(self) -> list[Entry]:
        return self.entries

    def namelist(self) -> list[str]:
        return [e.filename for e in self.entries]

    def getinfo(self, name: str) -> Entry:
        """The entry named ``name`` (the last one of that name). Raises KeyError."""
        return self._by_name[name]

    def read(self, name: str) -> bytes:
        """The bytes of member ``name`` (``zipfile.ZipFile.read``)."""
        entry = self._by_name[name]
        if not self.by_zipfile:
            data = read_member(self.raw, entry)
            if data is not None:
                return data
        try:
            return self._zipfile().read(name)
        except _refusals() as err:
            raise ZipError(str(err)) from None

    def blocks(self, entry: Entry, step: int) -> Iterator[bytes]:
        """The bytes of member ``entry`` through ``zipfile``, ``step`` at a time (encrypted,
        bzip2 or LZMA members; a refusal says "cannot be unpacked")."""
        zf = self._zipfile()
        refusals = _refusals()
        try:
            with zf.open(entry.info if entry.info is not None else entry.filename) as fh:
                while data := fh.read(step):
                    yield data
        except refusals[0] as err:
            raise ZipError(str(err)) from None
        except refusals[1:] as err:
            raise ZipError(f"cannot be unpacked: {err}") from None

    def reopen(self) -> Archive:
        """This archive (closed) with its file opened again; the directory is not read again."""
        self.close()
        self.raw = open(self.path, "rb")
        return self

    def close(self) -> None:
        if self._zf is not None:
            self._zf.close()
            self._zf = None
        self.raw.close()

    def __enter__(self) -> Archive:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
