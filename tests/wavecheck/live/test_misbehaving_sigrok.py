"""``wavecheck watch`` against a sigrok-cli that misbehaves (issue 27): it never hangs, always
ends by the watchdog meant to end it (each says so), kills the acquisition's
whole process group, and gives one error line with exit 2 when the acquisition failed.

The fake sigrok-cli is a script first on ``PATH`` (``FAKE`` below); its misbehaviour is chosen by
``FAKE_SIGROK_MODE`` and every process it starts writes its pid to ``FAKE_SIGROK_PIDS``, so the
tests can tell that none is left running. Before the fix each mode marked "hung" ran forever
(a ``--time 200ms`` watch too), an early exit with status 0 passed, and ``--show`` garbage was a
UnicodeDecodeError traceback.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from tests.bounds import HANG_GUARD_S
from wavecheck.live.acquisition import PROBE_TIMEOUT, STOP_GRACE

REPO = Path(__file__).resolve().parents[3]

FAKE = r"""#!/usr/bin/env python3
import os, signal, subprocess, sys, time
mode = os.environ["FAKE_SIGROK_MODE"]
with open(os.environ["FAKE_SIGROK_PIDS"], "a") as f:
    f.write(f"{os.getpid()}\n")
args = sys.argv[1:]
out = sys.stdout.buffer
if "--show" in args:
    if mode == "show-garbage":
        out.write(bytes(range(256)) * 4)
    elif mode == "show-huge":
        out.write(b"demo - Fake with 1 channel: D0 " * 400_000)
    elif mode == "show-hang":
        time.sleep(1000)
    elif mode == "show-many-channels":
        out.write(("fake - Fake with 2000 channels: "
                   + " ".join(f"D{i}" for i in range(2000)) + "\n").encode())
    else:
        out.write(b"fake - Fake device with 8 channels: D0 D1 D2 D3 D4 D5 D6 D7\n")
    sys.exit(0)
if "--get" in args:
    out.write(b"9" * 40 + b"\n" if mode == "rate-40-digits" else b"200000\n")
    sys.exit(0)
chunk = bytes(1000)  # 1000 samples of 8 channels, all low: 5 ms at 200 kHz
if mode in ("silent", "ignore-stop", "ignore-samples"):
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_IGN)
if mode == "silent":
    time.sleep(1000)
if mode in ("ignore-stop", "ignore-samples"):
    while True:
        out.write(chunk)
        out.flush()
        time.sleep(0.005)
out.write(chunk * 20)
out.flush()
if mode == "orphan":  # a child keeps the pipe open after sigrok-cli has gone
    child = subprocess.Popen(["sleep", "1000"])
    with open(os.environ["FAKE_SIGROK_PIDS"], "a") as f:
        f.write(f"{child.pid}\n")
sys.exit(0)
"""
WATCH = ["watch", "--driver", "fake", "--drive", "gecko-g202", "--map", "step=D0,dir=D1"]


def _start(tmp: Path, mode: str, *args: str) -> subprocess.Popen[str]:
    (tmp / "bin").mkdir(exist_ok=True)
    fake = tmp / "bin" / "sigrok-cli"
    fake.write_text(FAKE)
    fake.chmod(0o755)
    env = {**os.environ, "PATH": f"{tmp / 'bin'}:{os.environ['PATH']}",
           "FAKE_SIGROK_MODE": mode, "FAKE_SIGROK_PIDS": str(tmp / "pids")}  # fmt: skip
    return subprocess.Popen(
        [sys.executable, "-m", "wavecheck", *WATCH, "--status", "always", *args],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=tmp, env=env,
    )  # fmt: skip


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except (OSError, IndexError):
        return False
    return state != "Z"


def _finish(tmp: Path, proc: subprocess.Popen[str]) -> tuple[int, str, str]:
    """The watch's exit code and output once it ends, and no process of the acquisition left.
    What ended it is asserted by its words (each watchdog says that it fired); the wait is only
    a guard against a hang (tests/bounds.py), not a bound on time."""
    try:
        out, err = proc.communicate(timeout=HANG_GUARD_S)
    except subprocess.TimeoutExpired:
        proc.kill()
        out, err = proc.communicate()
        pytest.fail(f"watch still running after {HANG_GUARD_S:g} s, a hang: {err[-400:]}")
    time.sleep(0.5)
    pids = [int(p) for p in (tmp / "pids").read_text().split()] if (tmp / "pids").exists() else []
    left = [p for p in pids if _alive(p)]
    for p in left:
        os.kill(p, signal.SIGKILL)
    assert not left, f"processes of the acquisition left running: {left}"
    assert "Traceback" not in err
    return proc.returncode, out, err


def _error_line(err: str) -> str:
    errors = [ln for ln in err.splitlines() if "error:" in ln]
    assert len(errors) == 1, err[-600:]
    assert err.strip().splitlines()[-1] == errors[0]
    return errors[0]


@pytest.mark.parametrize(
    ("mode", "args", "says"),
    [
        ("silent", ["--time", "200ms"], "no samples arrived"),
        ("orphan", [], "ended by itself (status 0) before it was asked to stop"),
        ("early-exit", [], "ended by itself (status 0) before it was asked to stop"),
        ("show-garbage", [], "--show lists no channels"),
        ("show-huge", [], "printed more than"),
        ("show-many-channels", [], "not a device's channel list"),
        ("show-hang", [], f"--show: no answer in {PROBE_TIMEOUT:g} s"),
        ("rate-40-digits", [], "--get samplerate says '9999"),
    ],
)
def test_a_failing_acquisition_ends_with_one_error_line(
    tmp_path: Path, mode: str, args: list[str], says: str
) -> None:
    code, out, err = _finish(tmp_path, _start(tmp_path, mode, *args))
    assert code == 2, (out, err[-600:])
    line = _error_line(err)
    assert says in line, line
    assert "--snippet-window" not in line


def _wait_for_data(proc: subprocess.Popen[str]) -> None:
    assert proc.stderr is not None
    deadline = time.monotonic() + HANG_GUARD_S  # a guard against a hang (tests/bounds.py)
    while time.monotonic() < deadline:
        line = proc.stderr.readline()
        if "samples" in line and " 0 samples" not in line:
            return
    pytest.fail("no status line with samples")


def test_ctrl_c_ends_a_sigrok_cli_that_ignores_the_stop(tmp_path: Path) -> None:
    """It keeps sending and ignores the newline and SIGINT: killed STOP_GRACE s after Ctrl-C;
    the samples up to then are the report (exit 0/1/3, not a failure), and it says so."""
    proc = _start(tmp_path, "ignore-stop")
    _wait_for_data(proc)
    proc.send_signal(signal.SIGINT)
    code, out, err = _finish(tmp_path, proc)
    assert code in (0, 1, 3), err[-600:]
    assert f"did not end within {STOP_GRACE:g} s of being asked to stop" in out
    assert "(interrupted)" in err


def test_a_second_ctrl_c_kills_at_once(tmp_path: Path) -> None:
    proc = _start(tmp_path, "ignore-stop")
    _wait_for_data(proc)
    proc.send_signal(signal.SIGINT)
    time.sleep(0.3)
    proc.send_signal(signal.SIGINT)
    code, out, err = _finish(tmp_path, proc)
    assert code in (0, 1, 3), err[-600:]
    assert "did not end within" not in out  # the second Ctrl-C ended it, not the stop grace


def test_exactly_time_s_samples_from_a_sigrok_cli_that_ignores_samples(tmp_path: Path) -> None:
    """--time 100ms is --samples 20000 at 200 kHz: the 20,000 are checked, the rest not read,
    and the acquisition that goes on is killed."""
    proc = _start(tmp_path, "ignore-samples", "--time", "100ms")
    code, out, err = _finish(tmp_path, proc)
    assert code in (0, 1, 3), err[-600:]
    assert "watched 20,000 samples" in err
    assert "did not end within" in out
