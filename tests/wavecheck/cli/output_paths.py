"""The output-path table shared by the CLI tests of ``wavecheck check``, ``stepgen simulate`` and
``stepgen plan``: every place an output option can point at, and what must happen there.

Each case arranges a path in ``tmp`` for one output (file name ``name``, e.g. ``report.txt``),
runs the command in-process with that path, and checks the outcome: written (in place for a
FIFO or device, through a symlink to its target) or refused before any work (exit 2, one line
naming the option and the path, nothing on stdout, no file left behind).

The real ``/dev/null`` and ``/dev/stdout`` cases first ask :func:`wavecheck.output.resolve_output`
how the path would be written and stop unless in place, so a regression fails the test instead of
replacing the machine's device node (the test runs as root in CI).
"""

from __future__ import annotations

import os
import stat
import subprocess
import sys
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import pytest

#: runs a command in-process: argv → exit code (stdout/stderr captured by the caller's capfd).
Runner = Callable[[list[str]], int]
#: does this look like the output the option writes (a report, a PNG, a VCD …)?
LooksRight = Callable[[bytes], bool]

FIFO_TIMEOUT_S = 20


@dataclass(frozen=True)
class Outcome:
    code: int
    out: str
    err: str


@dataclass(frozen=True)
class Case:
    """One place an output path can lead. ``arrange(tmp, name)`` returns the path to give;
    ``refusal``: the phrase of the expected one-line error (None: the output is written)."""

    id: str
    arrange: Callable[[Path, str], str]
    refusal: str | None = None
    verify: Callable[[Path, str, Outcome, bytes, LooksRight], None] | None = None
    fifo: bool = False
    needs_root: bool = False
    stdout: bool = False  # the output goes to this process's stdout (captured by capfd)


def _fifo(tmp: Path, name: str) -> str:
    os.mkfifo(tmp / name)
    return str(tmp / name)


def _verify_fifo(tmp: Path, name: str, o: Outcome, data: bytes, ok: LooksRight) -> None:
    assert o.code in (0, 1, 3), o.err
    assert stat.S_ISFIFO(os.lstat(tmp / name).st_mode), "the FIFO was replaced"
    assert ok(data), data[:200]


def _char_device(tmp: Path, name: str) -> str:
    # a private copy of /dev/null (same major/minor): replacing it would harm nothing
    try:
        os.mknod(tmp / name, stat.S_IFCHR | 0o666, os.makedev(1, 3))
    except PermissionError:
        pytest.skip("mknod not permitted here")
    return str(tmp / name)


def _verify_char_device(tmp: Path, name: str, o: Outcome, data: bytes, ok: LooksRight) -> None:
    assert o.code in (0, 1, 3), o.err
    st = os.lstat(tmp / name)
    assert stat.S_ISCHR(st.st_mode) and st.st_rdev == os.makedev(1, 3), "device node replaced"


def _guard_in_place(path: str) -> None:
    """Refuse to run a real-device case unless the writer will write in place."""
    from wavecheck.output import resolve_output

    assert resolve_output(path).in_place, f"{path} would not be written in place: not running"


def _dev_null(tmp: Path, name: str) -> str:
    _guard_in_place("/dev/null")
    return "/dev/null"


def _dev_null_link(tmp: Path, name: str) -> str:
    # a name with the right extension (stepgen simulate picks the format from it) → /dev/null
    (tmp / name).symlink_to("/dev/null")  # replacing the link would harm nothing: no guard
    return str(tmp / name)


def _verify_dev_null(tmp: Path, name: str, o: Outcome, data: bytes, ok: LooksRight) -> None:
    assert o.code in (0, 1, 3), o.err
    st = os.lstat("/dev/null")
    assert stat.S_ISCHR(st.st_mode) and st.st_rdev == os.makedev(1, 3), "/dev/null replaced!"


def _verify_dev_null_link(tmp: Path, name: str, o: Outcome, data: bytes, ok: LooksRight) -> None:
    _verify_dev_null(tmp, name, o, data, ok)
    assert (tmp / name).is_symlink() and os.readlink(tmp / name) == "/dev/null", "link replaced"


def _dev_stdout(tmp: Path, name: str) -> str:
    _guard_in_place("/dev/stdout")
    return "/dev/stdout"


def _stdout_link(tmp: Path, name: str) -> str:
    (tmp / name).symlink_to("/proc/self/fd/1")
    return str(tmp / name)


def _verify_stdout(tmp: Path, name: str, o: Outcome, data: bytes, ok: LooksRight) -> None:
    assert o.code in (0, 1, 3), o.err
    assert ok(o.out.encode()), o.out[:200]  # the output is the start of stdout
    if os.path.lexists(tmp / name):  # the link-to-stdout case
        assert (tmp / name).is_symlink(), "the link was replaced"


def _link_to_file(tmp: Path, name: str) -> str:
    (tmp / "real").mkdir()
    (tmp / "real" / name).write_bytes(b"old content")
    (tmp / name).symlink_to(Path("real") / name)
    return str(tmp / name)


def _verify_link_to_file(tmp: Path, name: str, o: Outcome, data: bytes, ok: LooksRight) -> None:
    assert o.code in (0, 1, 3), o.err
    assert os.readlink(tmp / name) == str(Path("real") / name), "the link was replaced"
    assert ok((tmp / "real" / name).read_bytes()), "the target has not the new content"
    assert sorted(p.name for p in (tmp / "real").iterdir()) == [name]  # no temporary left


def _dangling_link(tmp: Path, name: str) -> str:
    (tmp / "real").mkdir()
    (tmp / name).symlink_to(Path("real") / name)  # the target does not exist yet
    return str(tmp / name)


def _directory(tmp: Path, name: str) -> str:
    (tmp / name).mkdir()
    return str(tmp / name)


def _trailing_slash(tmp: Path, name: str) -> str:
    return str(tmp / name) + "/"


def _file_as_folder(tmp: Path, name: str) -> str:
    (tmp / "plain.txt").write_text("a file, not a folder")
    return str(tmp / "plain.txt" / name)


def _proc_folder(tmp: Path, name: str) -> str:
    return f"/proc/{name}"  # a folder even root cannot create files in


def _missing_folder(tmp: Path, name: str) -> str:
    return str(tmp / "missing" / name)


CASES = [
    Case("fifo", _fifo, verify=_verify_fifo, fifo=True),
    Case("char-device", _char_device, verify=_verify_char_device, needs_root=True),
    Case("dev-null", _dev_null, verify=_verify_dev_null),
    Case("link-to-dev-null", _dev_null_link, verify=_verify_dev_null_link),
    Case("dev-stdout", _dev_stdout, verify=_verify_stdout, stdout=True),
    Case("link-to-stdout", _stdout_link, verify=_verify_stdout, stdout=True),
    Case("symlink-to-file", _link_to_file, verify=_verify_link_to_file),
    Case("dangling-symlink", _dangling_link, verify=_verify_link_to_file),
    Case("directory", _directory, refusal="is a directory"),
    Case("trailing-slash", _trailing_slash, refusal="names a folder"),
    Case("file-as-folder", _file_as_folder, refusal="is not a folder"),
    Case("unwritable-folder", _proc_folder, refusal="is not writable"),
    Case("missing-folder", _missing_folder, refusal="does not exist"),
]


def _read_fifo(path: str) -> subprocess.Popen[bytes]:
    """A child process that reads the FIFO to its end (so the writer never blocks)."""
    code = "import sys; sys.stdout.buffer.write(open(sys.argv[1], 'rb').read())"
    return subprocess.Popen([sys.executable, "-c", code, path], stdout=subprocess.PIPE)


def run_case(
    case: Case,
    tmp: Path,
    name: str,
    argv: Callable[[str], list[str]],
    option: str,
    looks_right: LooksRight,
    run: Runner,
    capfd: pytest.CaptureFixture[str],
) -> None:
    """Arrange ``case``, run ``argv(path)`` and check the outcome (see the module docstring)."""
    if case.needs_root and os.geteuid() != 0:
        pytest.skip("needs root")
    path = case.arrange(tmp, name)
    before = sorted(str(p) for p in tmp.rglob("*"))
    reader = _read_fifo(path) if case.fifo else None
    data = b""
    try:
        code = run(argv(path))
    finally:
        if reader is not None:
            try:
                data, _ = reader.communicate(timeout=FIFO_TIMEOUT_S)
            except subprocess.TimeoutExpired:
                reader.kill()
                reader.communicate()
                pytest.fail("nothing was written into the FIFO (was it replaced?)")
    out, err = capfd.readouterr()
    outcome = Outcome(code, out, err)
    if case.refusal is None:
        assert case.verify is not None
        case.verify(tmp, name, outcome, data, looks_right)
        return
    assert code == 2, f"exit {code}: {err}"
    assert out == "", "the refusal must come before any work"
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert f"{option} {path}:" in lines[0] and case.refusal in lines[0], lines[0]
    assert sorted(str(p) for p in tmp.rglob("*")) == before  # nothing written, nothing left
