"""``wavecheck watch --save FILE.sr``: the stream kept as an srzip file that survives a crash.

A recording of an hour must not be lost with the process (a kill, a crash, a power cut): the
file is a complete ``.sr`` at every *checkpoint*, at most :data:`CHECKPOINT_SECONDS` of stream
apart. Between checkpoints the samples are deflated as they arrive into the next ``logic-1-N``
member, held in memory (compressed); a checkpoint closes the member, and the member, a new zip
central directory and its end record replace the previous directory on disk in **one**
``pwrite`` (followed by ``ftruncate`` and ``fdatasync``). Until that write the file on disk is
the previous checkpoint's complete zip; after it, the new one. So a ``SIGKILL`` loses at most
the samples since the last checkpoint, and the file opens in ``wavecheck`` and PulseView as it
is. Each member holds whole samples (libsigrok concatenates the members; a reader drops a
member's trailing partial sample).

The zip structure is Python's :mod:`zipfile` (``ZIP64`` when needed): it writes to
:class:`_Staged`, a file object whose bytes past the last checkpoint's directory stay in memory
until :meth:`_Staged.commit`.

Where the bytes go: a new ``FILE.sr`` is recorded in place (created exclusively, so nothing of
anyone's is replaced); an existing one is kept until the watch ends, the recording going to a
visible ``FILE.recording.sr`` beside it that replaces it then (as every output replaces a file:
whole or not at all; :mod:`wavecheck.output`); a device, FIFO or ``/dev/stdout`` is streamed
(no checkpoints: it cannot be rewritten).
"""

from __future__ import annotations

import contextlib
import os
import stat
import time
import zipfile
from pathlib import Path
from typing import IO, Any

from wavecheck.errors import UsageError
from wavecheck.output import open_stream, resolve_output

__all__ = ["CHECKPOINT_SECONDS", "SrRecorder"]

#: Wall-clock seconds between checkpoints: what a crash can lose at most.
CHECKPOINT_SECONDS = 2.0
#: Sample bytes of one member at most (a checkpoint comes earlier at a very high rate).
MAX_MEMBER_BYTES = 1 << 30


class _Staged:
    """A file as :mod:`zipfile` sees it: bytes before ``base`` are on disk and final, writes
    from ``base`` on are kept in memory until :meth:`commit` writes them in one call."""

    def __init__(self, fd: int) -> None:
        self.fd = fd
        self.base = 0  # where the staged bytes begin (the last directory's offset)
        self.size = 0  # bytes on disk
        self.staged = bytearray()
        self.pos = 0

    def seekable(self) -> bool:
        return True

    def tell(self) -> int:
        return self.pos

    def _end(self) -> int:
        """The logical end: the staged bytes replace everything on disk from ``base`` on."""
        return self.base + len(self.staged) if self.staged else self.size

    def seek(self, offset: int, whence: int = os.SEEK_SET) -> int:
        start = {os.SEEK_SET: 0, os.SEEK_CUR: self.pos, os.SEEK_END: self._end()}[whence]
        self.pos = start + offset
        return self.pos

    def read(self, n: int = -1) -> bytes:
        left = max(0, self._end() - self.pos)
        n = left if n < 0 else min(n, left)
        if self.staged and self.pos >= self.base:
            data = bytes(self.staged[self.pos - self.base : self.pos - self.base + n])
        else:  # zipfile reads only when it opens the checkpointed file (nothing staged)
            data = os.pread(self.fd, n, self.pos)
        self.pos += len(data)
        return data

    def write(self, data: Any) -> int:
        if self.pos < self.base:
            raise ValueError("a write before the last checkpoint")
        b = bytes(data)
        off = self.pos - self.base
        if off > len(self.staged):
            self.staged += bytes(off - len(self.staged))
        self.staged[off : off + len(b)] = b
        self.pos += len(b)
        return len(b)

    def truncate(self, size: int | None = None) -> int:
        size = self.pos if size is None else size
        del self.staged[max(0, size - self.base) :]
        return size

    def flush(self) -> None:
        pass

    def commit(self, next_base: int) -> None:
        """Put the staged bytes on disk in one write, and stage from ``next_base`` on."""
        view = memoryview(bytes(self.staged))
        at = self.base
        while view:  # one call unless the kernel writes less
            done = os.pwrite(self.fd, view, at)
            view, at = view[done:], at + done
        self.size = self.base + len(self.staged)
        os.ftruncate(self.fd, self.size)
        with contextlib.suppress(OSError):  # not every file system syncs (a tmpfs is fine)
            os.fdatasync(self.fd)
        self.base = next_base
        self.staged.clear()


class SrRecorder:
    """Sample bytes as they arrive → a ``.sr`` file at ``target``, complete at every checkpoint
    (see the module docstring). ``metadata`` is the srzip ``metadata`` text, ``unitsize`` the
    bytes per sample; :meth:`close` ends it, :meth:`discard` leaves no file of ours.

    Raises:
        UsageError: the target cannot be written (refused by :func:`~wavecheck.output
            .resolve_output`, or its folder cannot take a file).
    """

    def __init__(self, target: str | os.PathLike[str], metadata: str, unitsize: int) -> None:
        where = resolve_output(target)
        self.target = where.path
        self.unitsize = unitsize
        self.members = 0
        self.bytes = 0  # sample bytes taken (whole samples)
        self._partial = b""
        self._checkpoint_at = time.monotonic()
        self._member_bytes = 0
        self._stream: IO[bytes] | None = None
        self._zip: zipfile.ZipFile | None = None
        self._member: IO[bytes] | None = None
        self.path = self.target  # the file being written
        self.replaces: Path | None = None  # the existing file it replaces at the end
        if where.in_place:  # a device, FIFO or descriptor: streamed, no checkpoints
            self._stream = open_stream(target)  # never seeked (/dev/null, /dev/stdout)
            self._zip = zipfile.ZipFile(self._stream, "w")
            self._write_head(metadata)
            return
        if os.path.lexists(self.target):
            self.replaces = self.target
            self.path = self._free_sibling()
        try:
            self._fd = os.open(self.path, os.O_RDWR | os.O_CREAT | os.O_EXCL, 0o666)
        except OSError as err:
            raise UsageError(
                f"--save {target}: cannot create {self.path}: {err.strerror}"
            ) from None
        self._file = _Staged(self._fd)
        self._zip = zipfile.ZipFile(self._file, "w")  # type: ignore[call-overload]
        self._write_head(metadata)
        self._commit()

    def _free_sibling(self) -> Path:
        for k in range(1, 1000):
            p = self.target.with_name(
                f"{self.target.stem}.recording{'' if k == 1 else f'-{k}'}{self.target.suffix}"
            )
            if not os.path.lexists(p):
                return p
        raise UsageError(f"--save {self.target}: no free name for the recording beside it")

    def _write_head(self, metadata: str) -> None:
        assert self._zip is not None
        self._zip.writestr(zipfile.ZipInfo("version"), "2", compress_type=zipfile.ZIP_STORED)
        self._zip.writestr(
            zipfile.ZipInfo("metadata"), metadata, compress_type=zipfile.ZIP_DEFLATED
        )

    def _open_member(self) -> IO[bytes]:
        if self._zip is None:  # reopened on the checkpointed file: appends after its members
            self._zip = zipfile.ZipFile(
                self._file,  # type: ignore[arg-type]
                "a",
                compression=zipfile.ZIP_DEFLATED,
                compresslevel=1,
            )
        self.members += 1
        info = zipfile.ZipInfo(f"logic-1-{self.members}")
        info.compress_type = zipfile.ZIP_DEFLATED
        self._member_bytes = 0
        return self._zip.open(info, "w", force_zip64=True)

    def add(self, data: bytes) -> None:
        """Append sample bytes (any split: a partial sample waits for its rest)."""
        data = self._partial + data
        whole = len(data) - len(data) % self.unitsize
        self._partial = data[whole:]
        if whole:
            if self._member is None:
                self._member = self._open_member()
            self._member.write(data[:whole])
            self.bytes += whole
            self._member_bytes += whole
        self.tick()

    def tick(self) -> None:
        """Checkpoint when it is due (:data:`CHECKPOINT_SECONDS` since the last one, or a
        member of :data:`MAX_MEMBER_BYTES`)."""
        now = time.monotonic()
        if self._member is not None and (
            now - self._checkpoint_at >= CHECKPOINT_SECONDS
            or self._member_bytes >= MAX_MEMBER_BYTES
        ):
            self._end_member()
            self._checkpoint_at = now

    def _end_member(self) -> None:
        """Close the member being written and, on a file, checkpoint."""
        if self._member is None:
            return
        self._member.close()
        self._member = None
        if self._stream is None:
            self._commit()

    def _commit(self) -> None:
        """Write the central directory after the members and put it all on disk at once."""
        assert self._zip is not None
        next_base = self._zip.start_dir
        self._zip.close()
        self._zip = None
        self._file.commit(next_base)

    def close(self) -> Path:
        """Write the rest and end the file (replacing the file it was to replace); the path."""
        if self._stream is not None:
            if self._member is not None:
                self._member.close()
            assert self._zip is not None
            self._zip.close()
            self._stream.close()
            return self.target
        self._end_member()
        os.close(self._fd)
        if self.replaces is not None:
            with contextlib.suppress(OSError):
                os.chmod(self.path, stat.S_IMODE(os.stat(self.replaces).st_mode))
            os.replace(self.path, self.replaces)
            return self.replaces
        return self.path

    def discard(self) -> None:
        """Leave no file of ours (an existing file it was to replace is kept)."""
        if self._stream is not None:
            with contextlib.suppress(Exception):
                self._stream.close()
            return
        with contextlib.suppress(OSError):
            os.close(self._fd)
        with contextlib.suppress(OSError):
            os.unlink(self.path)
