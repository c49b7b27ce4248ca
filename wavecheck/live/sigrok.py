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
the terminal reaches wavecheck only, which then stops the acquisition itself.
"""

from __future__ import annotations

import collections
import os
import re
import select
import shutil
import signal
import subprocess
import threading
from collections.abc import Sequence
from dataclasses import dataclass, field
from fractions import Fraction

from wavecheck.errors import DeviceError, UsageError

__all__ = ["Acquisition", "DeviceInfo", "acquisition_command", "probe_device", "sigrok_cli"]

_HEADER = re.compile(r"^(?P<driver>\S+) - .*? with (?P<n>\d+) channels?: (?P<names>.*)$")
_LOGIC_GROUP = re.compile(r"^\s+Logic: channels (?P<names>.*)$")
#: Lines of sigrok-cli's standard error kept for the messages.
STDERR_LINES = 20
#: Seconds a probe (``--show``, ``--get``) may take.
PROBE_TIMEOUT = 30.0


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


def _probe(program: str, driver: str, args: Sequence[str]) -> str:
    cmd = [program, "-d", driver, *args]
    try:
        done = subprocess.run(
            cmd, capture_output=True, text=True, timeout=PROBE_TIMEOUT, stdin=subprocess.DEVNULL
        )
    except subprocess.TimeoutExpired:
        raise DeviceError(
            f"sigrok-cli -d {driver} {' '.join(args)}: no answer in {PROBE_TIMEOUT:g} s"
        ) from None
    except OSError as err:
        raise DeviceError(f"{program}: cannot run: {err.strerror or err}") from None
    text = done.stdout + done.stderr
    if "No devices found" in text:
        raise DeviceError(
            f"sigrok-cli found no device for driver {driver!r} (is it plugged in, and may this "
            "user open it? see README 'Watching a running machine')"
        )
    if done.returncode != 0:
        last = (done.stderr.strip().splitlines() or ["(no message)"])[-1]
        raise DeviceError(f"sigrok-cli -d {driver} {' '.join(args)} failed: {last}")
    return done.stdout


def probe_device(program: str, driver: str, *, rate: bool) -> DeviceInfo:
    """The logic channels of ``driver`` (and its current sample rate when ``rate``)."""
    names: list[str] | None = None
    for line in _probe(program, driver, ["--show"]).splitlines():
        if (g := _LOGIC_GROUP.match(line)) is not None:
            names = g["names"].split()
            break
        if names is None and (h := _HEADER.match(line)) is not None:
            names = h["names"].split()
    if not names:
        raise DeviceError(f"sigrok-cli -d {driver} --show lists no channels")
    info = DeviceInfo(names)
    if rate:
        text = _probe(program, driver, ["--get", "samplerate"]).strip()
        if text.isdigit() and int(text) > 0:
            info.samplerate = Fraction(int(text))
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
    """A running sigrok-cli: :meth:`read` its samples, :meth:`stop` it, :meth:`outcome` at the end.

    ``continuous``: the command runs until stopped (stopped with a newline on its input);
    otherwise it ends by itself after its ``--samples``.
    """

    command: list[str]
    continuous: bool
    process: subprocess.Popen[bytes] = field(init=False)
    stderr: collections.deque[str] = field(init=False)
    stopped_by_us: bool = field(init=False, default=False)
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
        for raw in self.process.stderr:
            line = raw.decode("utf-8", "replace").strip()
            if line and not line.startswith("Press any key"):
                self.stderr.append(line)

    def read(self, size: int, timeout: float) -> bytes | None:
        """Up to ``size`` bytes; ``b""`` at the end of the data, None when none came within
        ``timeout`` seconds."""
        assert self.process.stdout is not None
        fd = self.process.stdout.fileno()
        ready, _, _ = select.select([fd], [], [], timeout)
        if not ready:
            return None
        return os.read(fd, size)

    def stop(self) -> None:
        """Ask sigrok-cli to end the acquisition (the samples taken still arrive)."""
        if self.stopped_by_us or self.process.poll() is not None:
            return
        self.stopped_by_us = True
        try:
            if self.continuous and self.process.stdin is not None:
                self.process.stdin.write(b"\n")
                self.process.stdin.flush()
            else:
                self.process.send_signal(signal.SIGINT)
        except (BrokenPipeError, ProcessLookupError):
            pass

    def close(self, grace: float = 5.0) -> int:
        """Wait for sigrok-cli to exit (killed after ``grace`` seconds); its exit status."""
        if self.process.stdin is not None:
            try:
                self.process.stdin.close()
            except BrokenPipeError:
                pass
        try:
            return self.process.wait(timeout=grace)
        except subprocess.TimeoutExpired:
            self.process.kill()
            return self.process.wait()

    def failure(self, status: int) -> str | None:
        """Why the acquisition counts as failed (None: it ended as asked)."""
        self._drainer.join(timeout=2.0)  # sigrok-cli has exited: its last lines are in
        errors = [line for line in self.stderr if "rror" in line or "ailed" in line]
        if status < 0 and not (self.stopped_by_us and status == -signal.SIGINT):
            name = signal.Signals(-status).name
            return f"sigrok-cli was killed by {name}"
        if errors:
            return f"sigrok-cli reported: {errors[-1]}"
        if status > 0 and not self.stopped_by_us:
            last = self.stderr[-1] if self.stderr else "no message"
            return f"sigrok-cli exited with status {status} ({last})"
        return None
