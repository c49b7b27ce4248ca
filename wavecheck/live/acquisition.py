"""sigrok-cli as a live sample source (``wavecheck watch``).

sigrok-cli 0.7.2 facts this module relies on (``../shared/reference/sigrok.md``; measured here):

- ``-O binary`` writes the raw logic samples to standard output, ``unitsize`` bytes each, bit n =
  the n-th enabled logic channel; analog channels are written as *text* into the same stream, so
  only logic channels are ever enabled (``--channels``).
- ``--continuous`` acquires until a key is read from standard input: with standard input at its
  end it stops at once, so the input is a pipe kept open and one newline stops it cleanly
  (the samples already taken are written). ``--samples N`` stops after exactly N samples.
- The demo driver paces samples in real time (24 MHz × 8 channels: ~23 MB/s through the pipe).
- ``-d DRIVER --show`` lists the channels (``demo - Demo device with 8 channels: D0 D1 …``, and a
  ``Logic: channels …`` group when there are analog ones); ``--get samplerate`` the current rate.
- ``-g GROUP`` makes every ``--config`` apply to that channel group, so a group option (the demo's
  ``pattern``) and the device's ``samplerate`` cannot be set in one run.

The process is started from an argument list (never a shell), in its own session, so a Ctrl-C in
the terminal reaches wavecheck only, which then stops the acquisition itself. Nothing waits on it
without a bound: a probe answers within :data:`PROBE_TIMEOUT` seconds and :data:`MAX_PROBE_BYTES`
bytes; an acquisition asked to stop that has not ended :data:`STOP_GRACE` seconds later, and one
that has exited while another process still holds its pipe open, is ended by killing its whole
process group (:meth:`Acquisition.kill`).
"""

from __future__ import annotations

import collections
import contextlib
import os
import re
import select
import shutil
import signal
import subprocess
import threading
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from fractions import Fraction

from wavecheck.capture.binary import MAX_CHANNELS
from wavecheck.errors import DeviceError, UnitError, UsageError
from wavecheck.units import parse_int, shorten

__all__ = ["Acquisition", "DeviceInfo", "acquisition_command", "probe_device", "sigrok_cli"]

_HEADER = re.compile(r"^(?P<driver>\S+) - .*? with (?P<n>\d+) channels?: (?P<names>.*)$")
_LOGIC_GROUP = re.compile(r"^\s+Logic: channels (?P<names>.*)$")
#: Lines of sigrok-cli's standard error kept for the messages.
STDERR_LINES = 20
#: Seconds a probe (``--show``, ``--get``) may take.
PROBE_TIMEOUT = 10.0
#: Bytes of a probe's output read at most (``--show`` of a real device is a few hundred).
MAX_PROBE_BYTES = 1 << 16
#: Seconds an acquisition asked to stop may take to end before its process group is killed.
STOP_GRACE = 3.0
#: Seconds the sample pipe may stay open after sigrok-cli has exited (a child holding it).
EXIT_GRACE = 1.0
#: The fastest sample rate a device may state (Hz): beyond any logic analyzer.
MAX_DEVICE_RATE = 10**12


def sigrok_cli(path: str | None = None) -> str:
    """The sigrok-cli program to run (``path``, else the one on ``PATH``)."""
    found = shutil.which(path or "sigrok-cli")
    if found is None:
        raise UsageError(
            f"{path or 'sigrok-cli'}: not found (install it: apt install sigrok-cli; "
            "or give --sigrok-cli PATH)"
        )
    return found


@dataclass
class DeviceInfo:
    """What ``--show`` and ``--get samplerate`` say about a device.

    Attributes:
        logic: the logic channel names, in bit order.
        samplerate: the device's current sample rate in Hz (None: it did not say).
    """

    logic: list[str]
    samplerate: Fraction | None = None


def _kill_group(process: subprocess.Popen[bytes]) -> None:
    """SIGKILL the process group ``process`` leads (it was started in a session of its own)."""
    with contextlib.suppress(ProcessLookupError, PermissionError):
        os.killpg(process.pid, signal.SIGKILL)


def _run_bounded(cmd: list[str], what: str) -> tuple[int, str, str]:
    """Run a probe: (exit status, stdout, stderr), at most :data:`PROBE_TIMEOUT` seconds and
    :data:`MAX_PROBE_BYTES` bytes, its process group killed after; bytes that are not UTF-8
    are replaced, not raised."""
    try:
        proc = subprocess.Popen(
            cmd,
            stdin=subprocess.DEVNULL,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            start_new_session=True,
        )
    except OSError as err:
        raise DeviceError(f"{cmd[0]}: cannot run: {err.strerror or err}") from None
    assert proc.stdout is not None and proc.stderr is not None
    fds = (proc.stdout.fileno(), proc.stderr.fileno())
    bufs = {fd: bytearray() for fd in fds}
    open_fds = set(fds)
    deadline = time.monotonic() + PROBE_TIMEOUT
    why = None
    status = -1
    try:
        while open_fds and why is None:
            left = deadline - time.monotonic()
            ready = select.select(list(open_fds), [], [], left)[0] if left > 0 else []
            if not ready:
                why = f"no answer in {PROBE_TIMEOUT:g} s"
            for fd in ready:
                data = os.read(fd, 1 << 16)
                if not data:
                    open_fds.discard(fd)
                bufs[fd] += data
                if len(bufs[fd]) > MAX_PROBE_BYTES:
                    why = f"printed more than {MAX_PROBE_BYTES} bytes: not sigrok-cli's answer"
        if why is None:
            try:
                status = proc.wait(timeout=max(deadline - time.monotonic(), 0.1))
            except subprocess.TimeoutExpired:
                why = f"did not exit in {PROBE_TIMEOUT:g} s"
    finally:
        _kill_group(proc)
        proc.wait()
        proc.stdout.close()
        proc.stderr.close()
    if why is not None:
        raise DeviceError(f"{what}: {why}")
    stdout, stderr = (bytes(bufs[fd]).decode("utf-8", "replace") for fd in fds)
    return status, stdout, stderr


def _probe(program: str, driver: str, args: Sequence[str]) -> str:
    what = f"sigrok-cli -d {driver} {' '.join(args)}"
    status, stdout, stderr = _run_bounded([program, "-d", driver, *args], what)
    text = stdout + stderr
    if "No devices found" in text:
        raise DeviceError(
            f"sigrok-cli found no device for driver {driver!r} (is it plugged in, and may this "
            "user open it? see docs/watch.md)"
        )
    if status != 0:
        last = (stderr.strip().splitlines() or ["(no message)"])[-1]
        raise DeviceError(f"{what} failed: {shorten(last.strip(), 120)}")
    return stdout


def probe_device(program: str, driver: str, *, rate: bool) -> DeviceInfo:
    """The logic channels of ``driver`` (and its current sample rate when ``rate``).

    Raises:
        DeviceError: no device, sigrok-cli failing or hanging, or an answer that is not a
            device's (no channels, more than :data:`MAX_CHANNELS`, names that are not names, a
            rate beyond :data:`MAX_DEVICE_RATE`), in one line naming the probe.
    """
    names: list[str] | None = None
    for line in _probe(program, driver, ["--show"]).splitlines():
        if (g := _LOGIC_GROUP.match(line)) is not None:
            names = g["names"].split()
            break
        if names is None and (h := _HEADER.match(line)) is not None:
            names = h["names"].split()
    what = f"sigrok-cli -d {driver} --show"
    if not names:
        raise DeviceError(f"{what} lists no channels")
    bad = [n for n in names if not n.isprintable() or len(n) > 64]
    if len(names) > MAX_CHANNELS or bad or len(set(names)) != len(names):
        raise DeviceError(
            f"{what}: {len(names)} channel names, "
            + (f"such as {shorten(bad[0])!r}" if bad else "more than 512 or repeated")
            + ": not a device's channel list"
        )
    info = DeviceInfo(names)
    if rate:
        text = _probe(program, driver, ["--get", "samplerate"]).strip()
        if text.isdigit():
            try:
                hz = parse_int(
                    text, f"sigrok-cli -d {driver} --get samplerate says", limit=MAX_DEVICE_RATE
                )
            except UnitError as err:
                raise DeviceError(f"{err}: not a sample rate (give --samplerate)") from None
            info.samplerate = Fraction(hz) if hz > 0 else None
    return info


def acquisition_command(
    program: str,
    driver: str,
    channels: Sequence[str],
    *,
    samplerate: Fraction | None,
    samples: int | None,
    configs: Sequence[str] = (),
    group: str | None = None,
) -> list[str]:
    """The sigrok-cli argument list: raw samples of ``channels`` on standard output, ``samples``
    of them (None: until stopped)."""
    cmd = [program, "-d", driver, "--channels", ",".join(channels)]
    if group:
        cmd += ["-g", group]
    if samplerate is not None:
        cmd += ["--config", f"samplerate={samplerate.numerator // samplerate.denominator}"]
    for c in configs:
        cmd += ["--config", c]
    cmd += ["--samples", str(samples)] if samples is not None else ["--continuous"]
    return [*cmd, "-O", "binary"]


@dataclass
class Acquisition:
    """A running sigrok-cli: :meth:`read` its samples, :meth:`stop` (or :meth:`kill`) it,
    :meth:`close` and :meth:`failure` at the end.

    ``continuous``: the command runs until stopped (stopped with a newline on its input);
    otherwise it ends by itself after its ``--samples``.
    """

    command: list[str]
    continuous: bool
    process: subprocess.Popen[bytes] = field(init=False)
    stderr: collections.deque[str] = field(init=False)
    stopped_by_us: bool = field(init=False, default=False)
    stop_at: float | None = field(init=False, default=None)
    killed_by_us: bool = field(init=False, default=False)
    _drainer: threading.Thread = field(init=False, repr=False)

    def __post_init__(self) -> None:
        try:
            self.process = subprocess.Popen(
                self.command,
                stdin=subprocess.PIPE,
                stdout=subprocess.PIPE,
                stderr=subprocess.PIPE,
                start_new_session=True,
            )
        except OSError as err:
            raise DeviceError(f"{self.command[0]}: cannot run: {err.strerror or err}") from None
        self.stderr = collections.deque(maxlen=STDERR_LINES)
        self._drainer = threading.Thread(target=self._drain, daemon=True)
        self._drainer.start()

    def _drain(self) -> None:
        assert self.process.stderr is not None
        with contextlib.suppress(OSError, ValueError):
            while raw := self.process.stderr.readline(1 << 12):
                line = raw.decode("utf-8", "replace").strip()
                if line and not line.startswith("Press any key"):
                    self.stderr.append(shorten(line, 200))

    def read(self, size: int, timeout: float) -> bytes | None:
        """Up to ``size`` bytes; ``b""`` at the end of the data, None when none came within
        ``timeout`` seconds."""
        assert self.process.stdout is not None
        fd = self.process.stdout.fileno()
        ready, _, _ = select.select([fd], [], [], timeout)
        if not ready:
            return None
        return os.read(fd, size)

    @property
    def exited(self) -> bool:
        """sigrok-cli itself has ended (a child of it may still hold the pipe)."""
        return self.process.poll() is not None

    def stop(self) -> None:
        """Ask sigrok-cli to end the acquisition (the samples taken still arrive)."""
        if self.stopped_by_us or self.process.poll() is not None:
            return
        self.stopped_by_us = True
        self.stop_at = time.monotonic()
        try:
            if self.continuous and self.process.stdin is not None:
                self.process.stdin.write(b"\n")
                self.process.stdin.flush()
            else:
                self.process.send_signal(signal.SIGINT)
        except (BrokenPipeError, ProcessLookupError):
            pass

    def overdue(self, now: float) -> bool:
        """Asked to stop more than :data:`STOP_GRACE` seconds ago and still running."""
        return self.stop_at is not None and now - self.stop_at > STOP_GRACE

    def kill(self) -> None:
        """End the acquisition now: SIGKILL to its whole process group (sigrok-cli and any
        child of it holding the pipe)."""
        if self.process.poll() is None:  # else its own exit status stands
            self.killed_by_us = True
        _kill_group(self.process)

    def close(self, grace: float = STOP_GRACE) -> int:
        """Wait for sigrok-cli to exit (its process group killed after ``grace`` seconds);
        its exit status."""
        if self.process.stdin is not None:
            with contextlib.suppress(BrokenPipeError, OSError):
                self.process.stdin.close()
        try:
            status = self.process.wait(timeout=grace)
        except subprocess.TimeoutExpired:
            self.kill()
            status = self.process.wait()
        _kill_group(self.process)  # a child left holding the pipes ends too
        if self.process.stdout is not None:
            self.process.stdout.close()
        return status

    def failure(self, status: int) -> str | None:
        """Why the acquisition counts as failed (None: it ended as asked, or it was killed by
        us, which the caller words)."""
        self._drainer.join(timeout=2.0)  # sigrok-cli has exited: its last lines are in
        if self.killed_by_us:
            return None
        errors = [line for line in self.stderr if "rror" in line or "ailed" in line]
        if status < 0 and not (self.stopped_by_us and status == -signal.SIGINT):
            name = signal.Signals(-status).name
            return f"sigrok-cli was killed by {name}"
        if errors:
            return f"sigrok-cli reported: {errors[-1]}"
        if status > 0 and not self.stopped_by_us:
            last = self.stderr[-1] if self.stderr else "no message"
            return f"sigrok-cli exited with status {status} ({last})"
        if self.continuous and not self.stopped_by_us:
            return f"sigrok-cli ended by itself (status {status}) before it was asked to stop"
        return None
