"""Captures from standard input or a pipe (issue 12): ``-`` and ``/dev/stdin`` work; format
detection hands on the bytes it sniffed (it swallowed the first 4 KB and the VCD reader then
blamed line 1)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from tests.bounds import HANG_GUARD_S
from tests.conftest import write_vcd
from tests.wavecheck.capture.srutil import write_sr
from wavecheck.capture.blocks import assemble
from wavecheck.capture.edges import Capture
from wavecheck.capture.open import open_capture, open_source
from wavecheck.capture.vcd.reader import VcdBlocks

REPO = Path(__file__).resolve().parents[3]


def _wavecheck(args: list[str], data: bytes) -> subprocess.CompletedProcess[bytes]:
    """``python -m wavecheck *args`` with ``data`` on standard input through a pipe."""
    return subprocess.run(
        [sys.executable, "-m", "wavecheck", *args],
        input=data,
        capture_output=True,
        timeout=120,
        cwd=REPO,
        check=False,
        env={**os.environ, "OPENBLAS_NUM_THREADS": "1"},
    )


def _big_vcd(tmp_path: Path) -> Path:
    """A VCD well past the 4 KB that format detection reads."""
    step = [t for k in range(1000) for t in (1000 + 10_000 * k, 3000 + 10_000 * k)]
    path = write_vcd(tmp_path / "big.vcd", {"STEP": (0, step), "DIR": (0, [5_000_005])})
    assert path.stat().st_size > 3 * 4096
    return path


@pytest.mark.parametrize("name", ["-", "/dev/stdin"])
def test_vcd_from_a_pipe_reads_like_the_file(tmp_path: Path, name: str) -> None:
    path = _big_vcd(tmp_path)
    proc = _wavecheck(["info", name, "--format", "json"], path.read_bytes())
    assert proc.returncode == 0, proc.stderr.decode()
    piped = json.loads(proc.stdout)
    direct = json.loads(_wavecheck(["info", str(path), "--format", "json"], b"").stdout)
    assert piped["channels"] == direct["channels"]
    assert piped["duration_s"] == direct["duration_s"]
    assert piped["path"] == ("<stdin>" if name == "-" else name)


@pytest.mark.parametrize("name", ["-", "/dev/stdin"])
def test_check_from_a_pipe_gives_the_files_verdict(tmp_path: Path, name: str) -> None:
    path = _big_vcd(tmp_path)
    args = ["--drive", "gecko-g202", "--map", "step=STEP,dir=DIR", "--format", "json"]
    direct = _wavecheck(["check", str(path), *args], b"")
    piped = _wavecheck(["check", name, *args], path.read_bytes())
    assert piped.returncode == direct.returncode, piped.stderr.decode()
    a, b = json.loads(piped.stdout), json.loads(direct.stdout)
    assert a["verdict"] == b["verdict"] and a["rules"] == b["rules"]


def test_sr_from_a_pipe(tmp_path: Path) -> None:
    """A .sr (a zip, which needs seeking) through a pipe is spooled, then read as a file."""
    raw = np.zeros(10_000, dtype=np.uint8)
    raw[100:200] = 1
    raw[5000:] |= 2
    path = write_sr(tmp_path / "x.sr", raw, probes={0: "STEP", 1: "DIR"}, total=2, chunk=4096)
    proc = _wavecheck(["info", "-", "--format", "json"], path.read_bytes())
    assert proc.returncode == 0, proc.stderr.decode()
    data = json.loads(proc.stdout)
    assert [c["edges"] for c in data["channels"]] == [2, 1] and data["samples"] == 10_000


def test_undetectable_pipe_names_stdin_and_asks_for_the_format() -> None:
    proc = _wavecheck(["info", "-"], b"a,b\n1,0\n0,1\n")
    assert proc.returncode == 2
    err = proc.stderr.decode()
    assert err.count("\n") == 1 and "<stdin>" in err and "--input-format" in err


def test_broken_vcd_from_a_pipe_blames_the_right_line(tmp_path: Path) -> None:
    """An error past the first 4 KB names its real line (detection used to eat 4 KB)."""
    text = _big_vcd(tmp_path).read_text().splitlines()
    text.insert(len(text) - 3, "garbage")
    proc = _wavecheck(["info", "-"], ("\n".join(text) + "\n").encode())
    assert proc.returncode == 2
    assert f"line {len(text) - 3}" in proc.stderr.decode(), proc.stderr.decode()


def test_open_capture_reads_a_fifo(tmp_path: Path) -> None:
    """In-process: a named pipe (FIFO) is detected without losing the sniffed bytes."""
    import threading

    src = _big_vcd(tmp_path)
    fifo = tmp_path / "pipe.vcd"
    os.mkfifo(fifo)

    def feed() -> None:
        with open(fifo, "wb") as f:
            f.write(src.read_bytes())

    got: list[Capture] = []
    writer = threading.Thread(target=feed, daemon=True)
    reader = threading.Thread(target=lambda: got.append(open_capture(fifo)), daemon=True)
    writer.start()
    reader.start()
    reader.join(timeout=30)
    if not got:  # the old reader opened the FIFO a second time and waited for a writer forever
        pytest.fail("reading a FIFO did not finish in 30 s")
    cap = got[0]
    ref = open_capture(src)
    assert cap.path == str(fifo)
    for a, b in zip(cap.channels, ref.channels, strict=True):
        assert a.edges.tolist() == b.edges.tolist()


def test_a_vcd_on_a_pipe_is_read_block_by_block(tmp_path: Path) -> None:
    """One engine (issue 23): a VCD on a pipe is a block source read from the stream, never held
    whole (its blocks are as small as the chunk asked), and its edges are the file's."""
    import threading

    src = _big_vcd(tmp_path)
    fifo = tmp_path / "pipe.vcd"
    os.mkfifo(fifo)
    writer = threading.Thread(target=lambda: fifo.write_bytes(src.read_bytes()), daemon=True)
    writer.start()
    source = open_source(fifo, chunk_bytes=1024)
    assert isinstance(source, VcdBlocks)
    blocks = list(source.blocks())
    writer.join(timeout=30)
    assert len(blocks) > 10  # about 3 edges per 1 KB of text: many blocks
    got = assemble(source.capture(), blocks)
    ref = open_capture(src)
    for a, b in zip(got.channels, ref.channels, strict=True):
        assert a.edges.tolist() == b.edges.tolist()


@pytest.mark.parametrize("command", [["info"], ["check", "--drive", "gecko-g202"]])
def test_a_fifo_without_a_writer_says_so_and_ends_on_ctrl_c(
    tmp_path: Path, command: list[str]
) -> None:
    """Issue 27: a FIFO nobody writes to blocked silently. On a terminal the wait is said, and
    Ctrl-C (SIGINT) ends it at once: exit 130, one line."""
    import pty
    import select
    import signal
    import time

    fifo = tmp_path / "capture.fifo"
    os.mkfifo(fifo)
    master, slave = pty.openpty()
    proc = subprocess.Popen(
        [sys.executable, "-m", "wavecheck", command[0], str(fifo), *command[1:]],
        stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=slave, cwd=REPO,
    )  # fmt: skip
    os.close(slave)
    seen = b""
    deadline = time.monotonic() + HANG_GUARD_S  # a guard against a hang (tests/bounds.py)
    while b"waiting for data on FIFO" not in seen and time.monotonic() < deadline:
        if select.select([master], [], [], 1.0)[0]:
            seen += os.read(master, 4096)
    assert f"waiting for data on FIFO {fifo}".encode() in seen, seen
    assert proc.poll() is None  # still waiting: nothing was made up
    proc.send_signal(signal.SIGINT)
    assert proc.wait(timeout=10) == 130
    rest = b""
    while select.select([master], [], [], 0.5)[0]:
        try:
            rest += os.read(master, 4096)
        except OSError:
            break
    os.close(master)
    assert [ln for ln in rest.decode().splitlines() if ln.strip()] == ["wavecheck: interrupted"]
