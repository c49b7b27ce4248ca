"""Latency files cost bounded time and memory: devices that never end, huge files and endless
pipes are refused with one line naming the file (stepgen.latencyfiles.read_text: 64 MiB cap)."""

from __future__ import annotations

import os
import resource
import subprocess
import sys
from pathlib import Path

import pytest

from stepgen.latencyfiles import MAX_LATENCY_FILE_BYTES

#: Address-space limit of the child (bytes): numpy and the CLI fit easily, a 20 GB read does not.
MEMORY_LIMIT = 1 << 30
TIMEOUT_S = 60


def _limit() -> None:
    resource.setrlimit(resource.RLIMIT_AS, (MEMORY_LIMIT, MEMORY_LIMIT))


def _stepgen(*args: str) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1"}
    return subprocess.run(
        [sys.executable, "-m", "stepgen", *args],
        capture_output=True,
        text=True,
        timeout=TIMEOUT_S,
        preexec_fn=_limit,
        env=env,
    )


def _one_line(proc: subprocess.CompletedProcess[str]) -> str:
    lines = proc.stderr.strip().splitlines()
    assert proc.returncode == 2, proc.stderr[-2000:]
    assert len(lines) == 1, proc.stderr[-2000:]
    return lines[0]


@pytest.mark.skipif(not os.path.exists("/dev/zero"), reason="needs /dev/zero")
def test_plan_refuses_dev_zero_without_reading_it() -> None:
    line = _one_line(_stepgen("plan", "--drive", "gecko-g202", "--latency", "/dev/zero"))
    assert line.startswith("stepgen: error: /dev/zero: is a character device, which never ends")


@pytest.mark.skipif(not os.path.exists("/dev/zero"), reason="needs /dev/zero")
def test_histogram_model_says_what_dev_zero_is(tmp_path: Path) -> None:
    line = _one_line(
        _stepgen(
            "simulate",
            "--latency",
            "histogram:/dev/zero",
            "--mode",
            "velocity",
            "--velocity",
            "1",
            "--duration",
            "1ms",
            "-o",
            str(tmp_path / "x.vcd"),
        )
    )
    assert "/dev/zero: is a character device" in line and "not found" not in line


def test_a_file_over_the_cap_is_refused_from_its_size(tmp_path: Path) -> None:
    big = tmp_path / "huge.txt"
    with open(big, "wb") as fh:  # sparse: no disk, and nothing is read
        fh.truncate(MAX_LATENCY_FILE_BYTES + 1)
    line = _one_line(_stepgen("plan", "--drive", "gecko-g202", "--latency", str(big)))
    assert f"{big}: more than 64 MiB" in line


def test_an_endless_pipe_is_read_only_up_to_the_cap(tmp_path: Path) -> None:
    fifo = tmp_path / "latency.fifo"
    os.mkfifo(fifo)
    writer = subprocess.Popen(  # noqa: S603 - a fixed command
        [
            sys.executable,
            "-c",
            "import sys\nb = b'T: 0 ( 1) P:80 I:1000 C: 1 Min: 1 Act: 2 Avg: 2 Max: 9\\n' * 4096\n"
            "o = open(sys.argv[1], 'wb')\ntry:\n    while True: o.write(b)\nexcept BrokenPipeError:\n    pass",
            str(fifo),
        ],
        stderr=subprocess.DEVNULL,
    )
    try:
        line = _one_line(_stepgen("plan", "--drive", "gecko-g202", "--latency", str(fifo)))
    finally:
        writer.kill()
        writer.wait(timeout=TIMEOUT_S)
    assert f"{fifo}: more than 64 MiB" in line
