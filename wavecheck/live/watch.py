"""The live loop of ``wavecheck watch``: samples from sigrok-cli, checked as they arrive.

Each piece read from the pipe goes, in this order, to the ``--save`` recorder, the snippet ring,
the sample scanner (:class:`~wavecheck.capture.binary.SampleBlocks`) and the engine
(:class:`~wavecheck.engine.run.MachineCheck`). At most every :data:`FLUSH_SECONDS` the engine
checks what has gathered (so the figures are current whatever the step rate), the violations it
found are handed to the snippets, and the status line is redrawn.

The end: ``--time`` (sigrok-cli's ``--samples``: exactly that many samples, and no more even
from a sigrok-cli that ignores ``--samples``), Ctrl-C or SIGTERM (the acquisition is stopped and
the samples already taken are checked; a second Ctrl-C kills it at once), ``--stop-on-fail``, or
the data ending by itself. sigrok-cli dying, reporting an error, giving fewer samples than asked,
or ending by itself when it was to run until stopped is a failure of the acquisition
(:class:`~wavecheck.errors.DeviceError` at the CLI, exit 2), and the report still covers every
sample that arrived; nothing is bridged over a gap.

Nothing waits without a bound: with ``--time T`` the watch ends by ``T`` + :data:`START_GRACE`
seconds of wall-clock time whatever sigrok-cli does (short of the samples: a failure); an
acquisition asked to stop is killed (its process group) when it has not ended
:data:`~wavecheck.live.acquisition.STOP_GRACE` seconds later; and a sigrok-cli that has exited while
a child of it keeps the pipe open is ended :data:`~wavecheck.live.acquisition.EXIT_GRACE` seconds
after the last data.
"""

from __future__ import annotations

import signal
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from fractions import Fraction
from types import FrameType

from wavecheck.capture.binary import SampleBlocks
from wavecheck.engine import MachineCheck, MachineReport
from wavecheck.errors import DeviceError
from wavecheck.live import START_GRACE
from wavecheck.live.acquisition import EXIT_GRACE, STOP_GRACE, Acquisition
from wavecheck.live.learn import RoleLearner
from wavecheck.live.record import SrRecorder
from wavecheck.live.snippets import Snippets
from wavecheck.units import format_ns, format_time

__all__ = ["FLUSH_SECONDS", "READ_BYTES", "Watch", "WatchResult", "status_line"]

#: Wall-clock seconds between checks of what has gathered (and status redraws).
FLUSH_SECONDS = 0.25
#: Bytes read from the pipe at a time.
READ_BYTES = 1 << 20


@dataclass
class WatchResult:
    """How a watch ended.

    Attributes:
        report: every axis's report over the samples that arrived.
        ended: why it ended (``"time"``, ``"interrupted"``, ``"failure"``, ``"end of data"``).
        failure: what went wrong with the acquisition (None: nothing).
        samples: samples checked.
        wall_s: seconds from start to end.
        cpu_s: processor seconds wavecheck spent (sigrok-cli's not counted).
        snippets: the snippet files written.
        snippet_summary: violations seen against snippets written, and why
            (:meth:`~wavecheck.live.snippets.Snippets.summary`; empty without ``--snippets``).
    """

    report: MachineReport
    ended: str
    failure: str | None
    samples: int
    wall_s: float
    cpu_s: float
    snippets: list[str] = field(default_factory=list)
    snippet_summary: str = ""


def status_line(machine: MachineCheck, samples: int, rate: Fraction, wall_s: float) -> str:
    """One line: elapsed capture time, samples, and per axis its steps, violations so far and
    the closest rule with its margin."""
    parts = [f"{format_time(Fraction(samples) / rate)} captured", f"{samples:,} samples"]
    for a in machine.axes:
        fails = sum(s.fails for s in a.results)
        margins = [(s.min_margin_ns, s.rule) for s in a.results if s.min_margin_ns is not None]
        closest = ""
        if margins:
            m, rule = min(margins)
            closest = f", closest {rule} {format_ns(m, signed=True)}"
        name = f"{a.plan.name}: " if a.plan.name else ""
        parts.append(f"{name}{a.steps.count} steps, {fails} violation(s){closest}")
    return f"[{wall_s:6.1f} s] " + " · ".join(parts)


class Watch:
    """One live check (see the module docstring)."""

    def __init__(
        self,
        acquisition: Acquisition,
        scanner: SampleBlocks,
        machine: MachineCheck | RoleLearner,
        *,
        limit: int | None = None,
        stop_on_fail: bool = False,
        snippets: Snippets | None = None,
        recorder: SrRecorder | None = None,
        status: Callable[[str], None] | None = None,
        status_seconds: float = 0.5,
    ) -> None:
        self.acq = acquisition
        self.scanner = scanner
        self.learner = machine if isinstance(machine, RoleLearner) else None
        self.machine = machine if isinstance(machine, MachineCheck) else None
        self.limit = limit
        self.stop_on_fail = stop_on_fail
        self.snippets = snippets
        self.recorder = recorder
        self.status = status
        self.status_seconds = status_seconds
        self.why: str | None = None
        self.notes: list[str] = []
        if self.machine is not None:
            self._start(self.machine)

    def _start(self, machine: MachineCheck) -> None:
        """Check with ``machine`` from now on (the kept samples first, when learning)."""
        self.machine = machine
        if self.snippets is not None:
            for a in machine.axes:
                for s in a.results:
                    s.fresh = []
        self.scanner.want(machine.channels)
        if self.learner is not None:
            self.learner.replay(machine)
            self.learner = None

    def _signal(self, signum: int, frame: FrameType | None) -> None:
        if self.why == "interrupted":  # a second Ctrl-C: end now
            self.acq.kill()
        if self.why is None:
            self.why = "interrupted"
        self.acq.stop()

    def _take(self, data: bytes) -> None:
        """Hand one piece of the stream to the recorder, the snippet ring and the check."""
        if self.recorder is not None:
            self.recorder.add(data)
        if self.snippets is not None:
            self.snippets.ring.add(data)
        if self.machine is not None:
            self.machine.feed(self.scanner.scan(data))
        else:
            assert self.learner is not None
            self.learner.add(data)

    def _watchdog(self, now: float, deadline: float | None, quiet_since: float) -> str | None:
        """Why the acquisition must be killed now (None: it may go on)."""
        if self.acq.overdue(now):
            self.notes.append(
                f"sigrok-cli did not end within {STOP_GRACE:g} s of being asked to stop: its "
                "process group was killed"
            )
            return None
        if deadline is not None and now > deadline and not self.acq.stopped_by_us:
            assert self.limit is not None
            return (
                f"sigrok-cli gave {self.scanner.nsamples:,} of the {self.limit:,} samples asked "
                f"for within --time + {START_GRACE:g} s; stopped"
            )
        if self.acq.exited and now - quiet_since > EXIT_GRACE:
            self.notes.append(
                "sigrok-cli exited, but a process it started kept the sample pipe open: its "
                "process group was killed"
            )
        return None

    def _check_now(self, final: bool = False) -> None:
        if self.learner is not None:
            machine = self.learner.attempt(final)
            if machine is None:
                return
            self._start(machine)
        assert self.machine is not None
        end = self.scanner.nsamples
        self.machine.flush(end)
        failed = False
        for a in self.machine.axes:
            for s in a.results:
                failed = failed or s.fails > 0
                if self.snippets is not None and s.fresh:
                    for start, stop in s.fresh:
                        self.snippets.add(a.plan.name, s.rule, start, stop)
                    s.fresh.clear()
        if self.snippets is not None:
            self.snippets.due(end)
        if failed and self.stop_on_fail and self.why is None:
            self.why = "stop on fail"
            self.acq.stop()

    def _status(self, wall_s: float) -> str:
        if self.machine is not None:
            return status_line(self.machine, self.scanner.nsamples, self.scanner.rate, wall_s)
        assert self.learner is not None
        kept = Fraction(self.learner.samples) / self.scanner.rate
        return f"[{wall_s:6.1f} s] telling the channels' roles from {format_time(kept)} of samples"

    def run(self) -> WatchResult:
        """Watch until the end; the report and how it ended."""
        old = {s: signal.signal(s, self._signal) for s in (signal.SIGINT, signal.SIGTERM)}
        t_start = time.monotonic()
        cpu_start = time.process_time()
        last_check = last_status = quiet_since = t_start
        asked = None if self.limit is None else self.limit * self.scanner.unitsize  # bytes
        deadline = None
        if self.limit is not None:
            deadline = t_start + float(self.limit / self.scanner.rate) + START_GRACE
        taken = 0
        cut_short: str | None = None
        try:
            while True:
                data = self.acq.read(READ_BYTES, FLUSH_SECONDS)
                if data == b"":
                    break
                now = time.monotonic()
                if self.recorder is not None:
                    self.recorder.tick()  # a checkpoint is due also when nothing comes
                if data:
                    quiet_since = now
                    if asked is not None and taken + len(data) > asked:  # beyond --samples
                        data = data[: asked - taken]
                        self.acq.stop()
                    taken += len(data)
                    if data:
                        self._take(data)
                notes = len(self.notes)
                cut_short = self._watchdog(now, deadline, quiet_since)
                if cut_short is not None or len(self.notes) > notes:
                    self.acq.kill()
                    break
                if now - last_check >= FLUSH_SECONDS:
                    self._check_now()
                    last_check = now
                if self.status is not None and now - last_status >= self.status_seconds:
                    self.status(self._status(now - t_start))
                    last_status = now
        except BaseException:
            self.acq.kill()
            raise
        finally:
            for s, handler in old.items():
                signal.signal(s, handler)
            code = self.acq.close()
        failure = cut_short or self.acq.failure(code)
        if self.learner is not None and (failure or not self.learner.samples):
            raise DeviceError(
                f"{self.scanner.label}: {failure or 'no samples arrived'}, before the channels' "
                "roles could be told (nothing was checked)"
            )
        self._check_now(final=True)
        assert self.machine is not None
        n = self.scanner.nsamples
        if failure is None and self.limit is not None and self.why is None and n < self.limit:
            failure = f"sigrok-cli ended after {n:,} of the {self.limit:,} samples asked for"
        if self.scanner.partial:
            self.scanner.notes.append(
                f"the stream ended inside a sample ({self.scanner.partial} byte(s)): dropped"
            )
        summary = ""
        if self.snippets is not None:
            self.snippets.due(n, final=True)
            seen = sum(s.fails for a in self.machine.axes for s in a.results)
            summary = self.snippets.summary(seen)
        capture = self.scanner.capture()
        capture.notes += self.notes
        if summary:
            capture.notes.append(summary)
        if self.why == "interrupted":
            capture.notes.append(
                f"watch interrupted after {format_time(Fraction(n) / self.scanner.rate)}: "
                "every sample that arrived was checked"
            )
        report = self.machine.finish(capture)
        ended = "failure" if failure else (self.why or ("time" if self.limit else "end of data"))
        return WatchResult(
            report,
            ended,
            failure,
            n,
            time.monotonic() - t_start,
            time.process_time() - cpu_start,
            [str(p) for p in self.snippets.written] if self.snippets else [],
            summary,
        )
