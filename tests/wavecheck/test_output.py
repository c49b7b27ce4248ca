"""Outputs are written whole or not at all, with the mode a plain open() would give; devices,
FIFOs and descriptors in place; symlinks followed; directories, missing or unwritable folders and
the run's inputs refused."""

import os
import stat
import subprocess
import sys
from pathlib import Path

import pytest

from wavecheck.errors import UsageError
from wavecheck.output import (
    atomic_path,
    atomic_write,
    check_outputs,
    output_file,
    protect_inputs,
    resolve_output,
)


def test_atomic_write_creates_file_with_umask_mode(tmp_path: Path) -> None:
    target = tmp_path / "report.json"
    old = os.umask(0o022)
    try:
        atomic_write(target, "{}")
    finally:
        os.umask(old)
    assert target.read_text() == "{}"
    assert stat.S_IMODE(target.stat().st_mode) == 0o644


def test_failure_leaves_nothing(tmp_path: Path) -> None:
    target = tmp_path / "out.vcd"
    with pytest.raises(RuntimeError), atomic_path(target) as tmp:
        tmp.write_text("half a file")
        raise RuntimeError("simulated failure mid-write")
    assert list(tmp_path.iterdir()) == []


def test_failure_keeps_previous_output(tmp_path: Path) -> None:
    target = tmp_path / "out.txt"
    target.write_text("old")
    with pytest.raises(RuntimeError), atomic_path(target) as tmp:
        tmp.write_text("new, unfinished")
        raise RuntimeError("boom")
    assert target.read_text() == "old"


def test_missing_folder_is_a_usage_error(tmp_path: Path) -> None:
    with pytest.raises(UsageError, match="does not exist"):
        atomic_write(tmp_path / "nope" / "x.txt", "x")


# -- where a path leads decides how it is written ------------------------------------------------
def _reader(path: Path) -> subprocess.Popen[bytes]:
    code = "import sys; sys.stdout.buffer.write(open(sys.argv[1], 'rb').read())"
    return subprocess.Popen([sys.executable, "-c", code, str(path)], stdout=subprocess.PIPE)


def test_fifo_is_written_in_place(tmp_path: Path) -> None:
    fifo = tmp_path / "out.txt"
    os.mkfifo(fifo)
    reader = _reader(fifo)
    try:
        atomic_write(fifo, "through the pipe")
        data, _ = reader.communicate(timeout=60)
    finally:
        if reader.poll() is None:
            reader.kill()
            reader.communicate()
    assert data == b"through the pipe"
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode)
    assert list(tmp_path.iterdir()) == [fifo]  # no temporary file beside it


@pytest.mark.parametrize("path", ["/dev/null", "/dev/zero", "/dev/stdout", "/dev/fd/1"])
def test_devices_and_descriptors_are_written_in_place(path: str) -> None:
    target = resolve_output(path)
    assert target.in_place
    assert target.fd == (1 if "std" in path or "fd" in path else None)


def test_dev_null_stays_a_device() -> None:
    assert resolve_output("/dev/null").in_place  # checked before writing: never replace it
    atomic_write("/dev/null", "gone")
    with atomic_path("/dev/null") as p:
        assert p == Path("/dev/null")
        p.write_text("gone too")
    assert stat.S_ISCHR(os.lstat("/dev/null").st_mode)


def test_dev_stdout_keeps_the_descriptor_offset(tmp_path: Path) -> None:
    """``-o /dev/stdout > file``: written through descriptor 1 at its offset, so what was
    printed before stays and what is printed after follows (reopening would truncate)."""
    code = (
        "import os, sys; from wavecheck.output import atomic_write\n"
        "print('before', flush=True); atomic_write('/dev/stdout', 'REPORT\\n'); print('after')\n"
    )
    out = tmp_path / "stdout.txt"
    with open(out, "w") as fh:
        subprocess.run([sys.executable, "-c", code], stdout=fh, check=True, timeout=60)
    assert out.read_text() == "before\nREPORT\nafter\n"


def test_symlink_is_followed_and_kept(tmp_path: Path) -> None:
    (tmp_path / "data").mkdir()
    real = tmp_path / "data" / "r.txt"
    real.write_text("old")
    os.chmod(real, 0o640)
    (tmp_path / "a").symlink_to("b")  # a chain: a → b → data/r.txt
    (tmp_path / "b").symlink_to(Path("data") / "r.txt")
    atomic_write(tmp_path / "a", "new")
    assert (tmp_path / "a").is_symlink() and (tmp_path / "b").is_symlink()
    assert real.read_text() == "new"
    assert stat.S_IMODE(real.stat().st_mode) == 0o640  # replacing keeps the file's mode
    assert sorted(p.name for p in (tmp_path / "data").iterdir()) == ["r.txt"]


def test_dangling_symlink_creates_its_target(tmp_path: Path) -> None:
    (tmp_path / "link").symlink_to("new.txt")
    atomic_write(tmp_path / "link", "made")
    assert (tmp_path / "link").is_symlink() and (tmp_path / "new.txt").read_text() == "made"


def test_symlink_into_a_missing_folder_is_refused(tmp_path: Path) -> None:
    (tmp_path / "link").symlink_to(tmp_path / "gone" / "x.txt")
    with pytest.raises(UsageError, match="does not exist"):
        atomic_write(tmp_path / "link", "x")
    assert (tmp_path / "link").is_symlink()


@pytest.mark.parametrize(
    ("name", "why"),
    [("", "give a file name"), ("-", "not standard output"), ("sub/", "names a folder")],
)
def test_names_that_are_no_file_are_refused(tmp_path: Path, name: str, why: str) -> None:
    path = str(tmp_path) + "/" + name if name.endswith("/") else name
    with pytest.raises(UsageError, match=why):
        atomic_write(path, "x")
    assert list(tmp_path.iterdir()) == []


def test_directory_is_refused_and_kept(tmp_path: Path) -> None:
    (tmp_path / "d").mkdir()
    with pytest.raises(UsageError, match="is a directory"):
        atomic_write(tmp_path / "d", "x")
    assert (tmp_path / "d").is_dir()


def test_inputs_are_protected_by_any_name(tmp_path: Path) -> None:
    capture = tmp_path / "cap.vcd"
    capture.write_text("input")
    os.link(capture, tmp_path / "hard.vcd")
    (tmp_path / "soft.vcd").symlink_to(capture)
    (tmp_path / "sub").mkdir()
    names = [
        capture,
        tmp_path / "hard.vcd",
        tmp_path / "soft.vcd",
        tmp_path / "sub" / ".." / "cap.vcd",
    ]
    with protect_inputs({"capture": [str(capture)]}):
        for name in names:
            with pytest.raises(UsageError, match="is the capture file .* an input of this run"):
                atomic_write(name, "overwritten")
            with pytest.raises(UsageError, match="an input"), atomic_path(name):
                pass
    assert capture.read_text() == "input"
    atomic_write(capture, "free again")  # only while the run lasts
    assert capture.read_text() == "free again"


# -- check_outputs: before any work --------------------------------------------------------------
def test_check_outputs_names_the_option(tmp_path: Path) -> None:
    (tmp_path / "file").write_text("x")
    cases = {
        "-o": (str(tmp_path / "no" / "r.txt"), "does not exist"),
        "--html": (str(tmp_path / "file" / "r.html"), "is not a folder"),
        "--plot": ("/proc/wavecheck-test.png", "is not writable"),  # even for root
        "--gtkw": (str(tmp_path), "is a directory"),
    }
    for option, (path, why) in cases.items():
        with pytest.raises(UsageError) as info:
            check_outputs({option: path, "--other": None})
        assert str(info.value).startswith(f"{option} {path}: ") and why in str(info.value)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file"]  # the probe leaves nothing


def test_check_outputs_refuses_inputs_and_duplicates(tmp_path: Path) -> None:
    rule = tmp_path / "drive.toml"
    rule.write_text("[drive]\n")
    with pytest.raises(UsageError, match=r"^-o .*drive.toml: is the --drive file"):
        check_outputs({"-o": str(rule)}, {"--drive": [str(rule)]})
    with pytest.raises(UsageError, match="--html .*: is also given to -o"):
        check_outputs({"-o": str(tmp_path / "r"), "--html": str(tmp_path / "." / "r")})
    check_outputs({"-o": "/dev/null", "--html": "/dev/null"})  # devices may repeat
    check_outputs({"-o": str(tmp_path / "new.txt")}, {"--drive": [str(rule)]})
    assert output_file("x.png") == "x.png"  # the argparse marker passes values through


def test_steps_csv_to_dev_stdout_keeps_the_report_beside_it(tmp_path: Path) -> None:
    """Issue 34: ``--steps-csv /dev/stdout > s.txt`` reopened /dev/stdout at offset 0 and the
    report then wrote over the CSV. Both now go through the one open stream, whole."""
    import subprocess
    import sys

    vcd = Path(__file__).resolve().parents[2] / "captures" / "golden" / "stepgen0.vcd"
    alone = tmp_path / "alone.csv"
    out = tmp_path / "s.txt"
    args = [sys.executable, "-m", "wavecheck", "check", str(vcd), "--drive", "gecko-g202"]
    subprocess.run([*args, "--steps-csv", str(alone)], check=True, capture_output=True)
    with open(out, "wb") as f:
        subprocess.run([*args, "--steps-csv", "/dev/stdout"], stdout=f, check=True)
    text = out.read_text()
    csv = alone.read_text()
    assert len(csv.splitlines()) > 1000
    assert text.startswith(csv)  # the CSV whole, then the report after it
    assert text[len(csv) :].startswith("verdict: PASS")
    # appended to what the file held (>>), as a shell redirection means
    with open(out, "ab") as f:
        subprocess.run([*args, "--steps-csv", "/dev/stdout", "-q"], stdout=f, check=True)
    assert out.read_text().startswith(text + csv)


def test_output_dash_is_refused_before_any_work(tmp_path: Path) -> None:
    from wavecheck.cli import main

    vcd = Path(__file__).resolve().parents[2] / "captures" / "golden" / "stepgen0.vcd"
    assert main(["check", str(vcd), "--drive", "gecko-g202", "-o", "-"]) == 2
    assert main(["check", str(vcd), "--drive", "gecko-g202", "--steps-csv", "-"]) == 2
