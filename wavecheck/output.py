"""Write every output of both tools through one mechanism that never destroys anything.

Where a path leads decides how it is written:

- a new file, or an existing regular file: a temporary file beside it, renamed over it on
  success (whole or not at all; an existing file keeps its mode);
- a symlink: followed to its target, which is then written as above (the link stays a link);
- a device, FIFO or socket, or a process's file descriptor (``/dev/stdout``, ``/dev/fd/N``,
  ``/proc/self/fd/N``): opened and written in place, nothing renamed, no temporary file;
- a directory, a folder that is missing or cannot be written, ``-``, or an input of the same run
  (see :func:`protect_inputs`): refused with a :class:`~wavecheck.errors.UsageError` (exit 2).

The command line declares each output option with ``type=``:func:`output_file` (a figure option:
:func:`figure_file`, whose extension says the format: PNG, JPEG, SVG, PDF) and checks them all
with :func:`check_outputs` before any work is done.
"""

from __future__ import annotations

import argparse
import contextlib
import errno
import io
import os
import stat
import sys
from collections.abc import Iterable, Iterator, Mapping
from pathlib import Path
from typing import Any, BinaryIO, NamedTuple, cast

from wavecheck.errors import UsageError

__all__ = [
    "FIGURE_FORMATS",
    "OUTPUT_TYPES",
    "OutputTarget",
    "atomic_path",
    "atomic_write",
    "check_outputs",
    "figure_file",
    "figure_format",
    "gtkw_file",
    "open_stream",
    "output_file",
    "protect_inputs",
    "resolve_output",
    "same_file",
]

#: the inputs of the running command: (what it is, path, st_dev, st_ino) of each regular file.
_protected: list[tuple[str, str, int, int]] = []


class _Refused(Exception):
    """Why a path cannot be written (the caller adds the option and the path)."""


class OutputTarget(NamedTuple):
    """Where and how an output path is written (:func:`resolve_output`)."""

    path: Path  #: where the bytes go (symlinks followed)
    in_place: bool  #: opened and written; no temporary file, no rename
    fd: int | None  #: the descriptor of this process the path names (``/dev/stdout`` → 1)


def output_file(text: str) -> str:
    """argparse ``type=`` of every output option: marks it for :func:`check_outputs`.

    The value is returned unchanged; the checks need every option (inputs too), so they run
    after parsing.
    """
    return text


#: What a figure option (``--plot``) writes for each file name extension (matplotlib's format
#: names); a name without one (a device, a FIFO) gets PNG. Any other extension is refused.
FIGURE_FORMATS = {
    "": "png",
    ".png": "png",
    ".jpg": "jpg",
    ".jpeg": "jpg",
    ".svg": "svg",
    ".pdf": "pdf",
}


def figure_format(path: str | os.PathLike[str]) -> str:
    """The format a figure written to ``path`` is drawn in, by its extension
    (:data:`FIGURE_FORMATS`).

    Raises:
        UsageError: an extension no figure is written as (``out.gif``).
    """
    suffix = Path(path).suffix.lower()
    if suffix not in FIGURE_FORMATS:
        raise UsageError(
            f"{os.fspath(path)}: a figure is written as PNG, JPEG, SVG or PDF, not "
            f"{suffix.lstrip('.').upper()} (name it .png, .jpg, .svg or .pdf)"
        )
    return FIGURE_FORMATS[suffix]


def figure_file(text: str) -> str:
    """argparse ``type=`` of a figure option: an output (:func:`output_file`, checked like
    every output) whose extension says a format a figure is written in (:func:`figure_format`),
    refused before any work otherwise."""
    try:
        figure_format(text)
    except UsageError as err:
        raise argparse.ArgumentTypeError(str(err)) from None
    return text


#: Extensions GTKWave opens as a dump, never as a save file (``gtkwave FILE.vcd``).
_DUMP_EXTENSIONS = (".vcd", ".fst", ".ghw", ".lxt", ".lxt2", ".vzt", ".evcd")


def gtkw_file(text: str) -> str:
    """argparse ``type=`` of ``--gtkw``: an output (:func:`output_file`) not named like a dump,
    which GTKWave would open as one (and whose companion VCD would take its name)."""
    suffix = Path(text).suffix.lower()
    if suffix in _DUMP_EXTENSIONS:
        raise argparse.ArgumentTypeError(
            f"{text}: GTKWave opens a {suffix} file as a dump, not as a save file; name it "
            f"{Path(text).with_suffix('.gtkw').name} (its VCD, when one is written, goes beside it)"
        )
    return text


#: The ``type=`` of every output option (:func:`wavecheck.cli._main` checks them all).
OUTPUT_TYPES = (output_file, figure_file, gtkw_file)


def _fd_link(link: Path) -> int | None:
    """The descriptor number when ``link`` is one of this process's ``/proc/self/fd`` entries,
    -1 for another ``/proc`` link, None for an ordinary symlink."""
    folder = os.path.realpath(link.parent)
    if folder == os.path.realpath("/proc/self/fd") and link.name.isdigit():
        return int(link.name)
    return -1 if folder.startswith("/proc/") else None


def _follow(text: str) -> tuple[Path, int | None]:
    """Follow ``text``'s symlinks to the path they end at; stop at a ``/proc`` (fd) link."""
    p = Path(text)
    for _ in range(40):
        try:
            st = os.lstat(p)
        except FileNotFoundError:
            return p, None
        except NotADirectoryError:
            raise _Refused(f"{str(p.parent)!r} is not a folder") from None
        except OSError as err:  # a folder on the way cannot be searched, a loop …
            raise _Refused(err.strerror or str(err)) from None
        if not stat.S_ISLNK(st.st_mode):
            return p, None
        fd = _fd_link(p)
        if fd is not None:
            return p, fd
        p = Path(os.path.realpath(p.parent)) / os.readlink(p)
    raise _Refused("too many levels of symbolic links")


def _refuse_input(st: os.stat_result) -> None:
    for what, path, dev, ino in _protected:
        if (st.st_dev, st.st_ino) == (dev, ino):
            raise _Refused(
                f"is the {what} file {path}, an input of this run (refusing to overwrite it)"
            )


def _target(target: str | os.PathLike[str]) -> OutputTarget:
    """Where and how ``target`` is written; raises :class:`_Refused`."""
    text = os.fspath(target)
    if text == "":
        raise _Refused("give a file name")
    if text == "-":
        raise _Refused("'-' is not standard output here (give a file name, or /dev/stdout)")
    if text.endswith(os.sep) or os.path.basename(text) in (".", ".."):
        raise _Refused("names a folder (give a file name)")
    path, fd = _follow(text)
    if fd is not None:
        return OutputTarget(path, True, fd if fd >= 0 else None)
    try:
        st = os.stat(path)
    except FileNotFoundError:
        return OutputTarget(path, False, None)
    except NotADirectoryError:
        raise _Refused(f"{str(path.parent)!r} is not a folder") from None
    except OSError as err:
        raise _Refused(err.strerror or str(err)) from None
    if stat.S_ISDIR(st.st_mode):
        raise _Refused("is a directory (give a file name)")
    if stat.S_ISREG(st.st_mode):
        _refuse_input(st)
        return OutputTarget(path, False, None)
    return OutputTarget(path, True, None)  # device, FIFO, socket


def resolve_output(target: str | os.PathLike[str]) -> OutputTarget:
    """Where and how :func:`atomic_write` would write ``target``, without writing.

    Raises:
        UsageError: the target is refused (a directory, ``-``, an input of the run).
    """
    try:
        return _target(target)
    except _Refused as why:
        raise UsageError(f"{os.fspath(target)}: {why}") from None


def _check_folder(folder: Path, probe: bool) -> None:
    """Refuse a folder that is missing, is not a folder, or (``probe``) cannot take a new file.

    The probe creates and removes a temporary file: permission bits say nothing to root, and a
    read-only mount or ``/proc`` refuses even root.
    """
    if not folder.exists():
        raise _Refused(f"folder {str(folder)!r} does not exist (create it first)")
    if not folder.is_dir():
        raise _Refused(f"{str(folder)!r} is not a folder")
    if probe:
        try:
            fd, tmp = _new_file(folder, ".wavecheck-probe.")
        except OSError as err:
            raise _Refused(f"folder {str(folder)!r} is not writable ({err.strerror})") from None
        os.close(fd)
        os.unlink(tmp)


def _new_file(folder: Path, prefix: str, suffix: str = "") -> tuple[int, str]:
    """A file of a new random name in ``folder``, created and opened for writing, mode 0600
    (:func:`tempfile.mkstemp`'s contract, without importing :mod:`tempfile`: with its
    :mod:`shutil` and :mod:`random` ~3 ms, 1.5 % of a 20 s ``stepgen simulate``). Raises
    :class:`OSError` as ``os.open`` does."""
    flags = os.O_RDWR | os.O_CREAT | os.O_EXCL | getattr(os, "O_CLOEXEC", 0)
    for _ in range(100):  # 48 random bits a name: a clash is a stale file, not chance
        name = os.path.join(folder, f"{prefix}{os.urandom(6).hex()}{suffix}")
        try:
            return os.open(name, flags, 0o600), name
        except FileExistsError:
            continue
    raise FileExistsError(errno.EEXIST, "no unused temporary name", str(folder))


def check_outputs(
    outputs: Mapping[str, str | os.PathLike[str] | None],
    inputs: Mapping[str, Iterable[str | os.PathLike[str]]] | None = None,
) -> None:
    """Check every output option before any work: ``outputs`` maps option → path (None: not
    given), ``inputs`` maps a description (``"CAPTURE"``, ``"--hal"``) → the run's input files.

    Raises:
        UsageError: one line naming the option and the path (a directory, a missing or
            unwritable folder, an input of the run, two options naming one file).
    """
    with protect_inputs(inputs or {}):
        seen: dict[str, str] = {}
        for option, value in outputs.items():
            if value is None:
                continue
            text = os.fspath(value)
            try:
                t = _target(text)
                if not t.in_place:
                    _check_folder(t.path.parent, probe=True)
                    key = os.path.realpath(t.path)
                    if key in seen:
                        raise _Refused(
                            f"is also given to {seen[key]} (give each output its own file)"
                        )
                    seen[key] = option
            except _Refused as why:
                raise UsageError(f"{option} {text}: {why}") from None


@contextlib.contextmanager
def protect_inputs(inputs: Mapping[str, Iterable[str | os.PathLike[str]]]) -> Iterator[None]:
    """While active, any write to one of ``inputs`` (the same file by any name: a symlink, a
    hard link, another spelling) is refused. ``inputs`` maps a description → paths; paths that
    do not exist or are not regular files are ignored."""
    added: list[tuple[str, str, int, int]] = []
    for what, paths in inputs.items():
        for p in paths:
            try:
                st = os.stat(p)
            except (OSError, ValueError):
                continue
            if stat.S_ISREG(st.st_mode):
                added.append((what, os.fspath(p), st.st_dev, st.st_ino))
    _protected.extend(added)
    try:
        yield
    finally:
        for item in added:
            _protected.remove(item)


@contextlib.contextmanager
def atomic_path(target: str | os.PathLike[str]) -> Iterator[Path]:
    """Yield the path to write ``target``'s content to (see the module docstring).

    For a regular or new file it is a temporary file in the target's folder, renamed onto the
    target on success and removed on any exception, so a failure never leaves half an output.
    For a device or FIFO it is the target itself, written in place. For a descriptor of this
    process (``/dev/stdout``) it is a temporary file whose bytes are then written through the
    descriptor, at its offset: reopening ``/dev/stdout`` by its name would start at offset 0 of
    the file the shell redirected it to, over what the report wrote there.

    Raises:
        UsageError: the target is refused (a directory, an input, a missing folder …).
    """
    text = os.fspath(target)
    try:
        t = _target(text)
        if not t.in_place:
            _check_folder(t.path.parent, probe=False)
    except _Refused as why:
        raise UsageError(f"{text}: {why}") from None
    if t.in_place and t.fd is None:
        yield t.path
        return
    if t.fd is not None:  # a descriptor: written whole, at its offset, after what it carries
        import tempfile  # only here: most commands write regular files

        with tempfile.TemporaryDirectory(prefix="wavecheck-out-") as folder:
            staged = Path(folder) / t.path.name
            yield staged
            with open(staged, "rb") as f:
                while block := f.read(1 << 20):
                    _write_fd(t.fd, block)
        return

    try:
        fd, tmp = _new_file(t.path.parent, f".{t.path.name}.", ".tmp")
    except OSError as err:
        raise UsageError(
            f"{text}: folder {str(t.path.parent)!r} is not writable ({err.strerror})"
        ) from None
    os.close(fd)
    try:
        mode = stat.S_IMODE(os.stat(t.path).st_mode)  # replacing a file keeps its mode
    except FileNotFoundError:
        umask = os.umask(0)  # a new file gets what a plain open() gives: 0666 less the umask
        os.umask(umask)
        mode = 0o666 & ~umask
    os.chmod(tmp, mode)
    tmp_path = Path(tmp)
    try:
        yield tmp_path
        os.replace(tmp_path, t.path)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            tmp_path.unlink()
        raise


class _Stream(io.RawIOBase):
    """An output written as it comes, never seeked: a descriptor of this process written at
    its offset, or a device or FIFO. Told unseekable, :mod:`zipfile` streams through it (data
    descriptors) instead of seeking back, which ``/dev/null`` (whose position is always 0) and a
    shared descriptor cannot take."""

    def __init__(self, fd: int) -> None:
        super().__init__()
        self.fd = fd

    def writable(self) -> bool:
        return True

    def write(self, data: Any) -> int:
        _write_fd(self.fd, bytes(data))
        return len(data)

    def close(self) -> None:
        if not self.closed:
            os.close(self.fd)
        super().close()


def open_stream(target: str | os.PathLike[str]) -> BinaryIO:
    """An in-place output (:func:`resolve_output`: a device, FIFO or descriptor) opened to be
    written as it comes and never seeked; a descriptor (``/dev/stdout``) is written at its own
    offset, after what was written to it before.

    Raises:
        UsageError: the target is refused, is a regular file, or cannot be opened.
    """
    t = resolve_output(target)
    if not t.in_place:
        raise UsageError(f"{os.fspath(target)}: a file, not a stream (write it whole)")
    try:
        fd = os.dup(t.fd) if t.fd is not None else os.open(t.path, os.O_WRONLY)
    except OSError as err:
        raise UsageError(f"{os.fspath(target)}: cannot open ({err.strerror or err})") from None
    return cast(BinaryIO, _Stream(fd))


def same_file(a: str | os.PathLike[str] | int, b: str | os.PathLike[str] | int) -> bool:
    """True when ``a`` and ``b`` (paths or descriptors: ``/dev/stdout`` and 1) lead to one
    regular file (a device such as ``/dev/null``, a pipe or a terminal is no one file)."""

    def key(x: str | os.PathLike[str] | int) -> tuple[int, int] | None:
        try:
            st = os.fstat(x) if isinstance(x, int) else os.stat(x)
        except (OSError, ValueError):
            return None
        return (st.st_dev, st.st_ino) if stat.S_ISREG(st.st_mode) else None

    ka = key(a)
    return ka is not None and ka == key(b)


def _utf8(data: str | bytes) -> bytes:
    return data.encode("utf-8") if isinstance(data, str) else data


def _write_fd(fd: int, data: bytes) -> None:
    """Write to one of this process's descriptors at its own offset (``>>`` stays appending)."""
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(Exception):
            stream.flush()
    view = memoryview(data)
    while view:
        view = view[os.write(fd, view) :]


def atomic_write(target: str | os.PathLike[str], data: str | bytes | Iterable[str]) -> None:
    """Write ``data`` (text as UTF-8; or text in pieces, written as they come) to ``target``
    whole, or in place (see the module docstring).

    Raises:
        UsageError: the target is refused, or it cannot be written.
    """
    pieces = [data] if isinstance(data, str | bytes) else data
    text = os.fspath(target)
    fd = None
    with contextlib.suppress(_Refused):
        fd = _target(text).fd
    try:
        if fd is not None:
            for piece in pieces:
                _write_fd(fd, _utf8(piece))
            return
        with atomic_path(target) as path, open(path, "wb") as f:
            for piece in pieces:
                f.write(_utf8(piece))
    except OSError as err:
        if err.errno == errno.EPIPE:
            raise
        raise UsageError(f"{text}: cannot write ({err.strerror or err})") from None
