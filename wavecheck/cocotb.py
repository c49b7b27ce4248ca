"""A live check inside cocotb tests: every STEP/DIR edge checked while the simulation runs.

::

    from wavecheck.cocotb import StepMonitor

    @cocotb.test()
    async def steps_meet_the_drv8825(dut):
        mon = StepMonitor("drv8825", step=dut.step, dir=dut.dir).start()
        await dut.done.rising_edge            # ... drive the DUT
        report = await mon.finish()          # the wavecheck Report; raises if a rule failed

The monitor watches the handles with one cocotb task each (``handle.value_change``), records
each value change at its simulation time in the simulator's precision (integer ticks: the time
base is exactly ``10**cocotb.simtime.time_precision`` s), and every ``batch`` changes (or
``batch_time`` of simulated time) turns what it gathered into an
:class:`~wavecheck.capture.blocks.EdgeBlock` with the VCD reader's edge builder (x/z/U/W/- are
unknown stretches; several changes at one time step: the last one wins) and feeds the streamed
engine (:class:`~wavecheck.engine.run.MachineCheck`). With ``fail_on_violation`` (default),
the first batch with a failed rule raises :class:`WavecheckViolation` (an ``AssertionError``) in
the monitor's task, which fails the running cocotb test at that simulation time, naming the
rule, the worst violation so far, its margin and the time. :meth:`StepMonitor.finish` checks the
rest and returns the report: the figures :func:`wavecheck.check` gives on the simulator's dump
of the same run (tests/wavecheck/cocotb).

cocotb (>= 2.0, the ``cocotb`` extra) is imported only by this module.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import dataclass, replace
from fractions import Fraction
from typing import Any, Unpack

import numpy as np

try:
    import cocotb
    import cocotb.simtime
    from cocotb.task import Task
except ImportError as err:  # pragma: no cover - the extra is part of the test install
    raise ImportError("wavecheck.cocotb needs cocotb 2: pip install 'wavecheck[cocotb]'") from err

from wavecheck.api import require_met
from wavecheck.capture.blocks import EdgeBlock
from wavecheck.capture.edges import NEVER, Capture, Channel
from wavecheck.capture.vcd.reader import EdgeBuilder
from wavecheck.drives.datasheet import Drive
from wavecheck.engine import (
    CheckOptions,
    MachineCheck,
    MachineReport,
    Report,
    RuleResult,
    machine_for,
)
from wavecheck.errors import UsageError
from wavecheck.options import CheckKeywords, options_from_keywords
from wavecheck.steps.mapping import AxisMap
from wavecheck.timebase import Timebase
from wavecheck.units import format_ns, format_time, parse_option

__all__ = ["DEFAULT_BATCH", "StepMonitor", "WavecheckViolation"]

#: Value changes gathered before they are checked (the check runs once per batch).
DEFAULT_BATCH = 8192
#: A handle's value as text → the edge builder's code (0, 1; 2 for unknown).
_CODES = {"0": 0, "1": 1, "L": 0, "H": 1, "l": 0, "h": 1}

Handle = Any  # a cocotb simulation object of one bit (LogicObject, a 1-bit LogicArrayObject)


class WavecheckViolation(AssertionError):
    """A rule failed: raised in the monitor's task (failing the cocotb test) or by
    :meth:`StepMonitor.finish`; ``report`` is the report so far (a
    :class:`~wavecheck.report.machine.MachineReport` over every axis)."""

    def __init__(self, message: str, report: MachineReport | None = None) -> None:
        super().__init__(message)
        self.report = report


@dataclass(frozen=True)
class _Watched:
    index: int
    handle: Handle
    name: str


def _drive(drive: str | os.PathLike[str] | Drive) -> Drive:
    if isinstance(drive, Drive):
        return drive
    from wavecheck.drives.library import load_drive

    return load_drive(drive)


class StepMonitor:
    """Checks a DUT's step/dir outputs against a drive as the simulation runs.

    Args:
        drive: a drive id from ``rules/`` (``"drv8825"``), a rule file, or a :class:`Drive`
            (with ``axes``: the drive of every axis that names none).
        step, dir, enable, up, down: the DUT's 1-bit handles for these roles (one axis).
        signals: more roles → handles (``{"phase-A": dut.a, ...}``), merged with the above.
        axes: several axes instead: axis name → role → handle
            (``{"x": {"step": dut.xs, "dir": dut.xd}, "y": {...}}``); an axis may give its own
            ``"drive"`` in the same table. :meth:`finish` then returns a
            :class:`~wavecheck.report.machine.MachineReport`.
        options: the options object to start from; the keywords replace what they give.
        keywords: as :func:`wavecheck.check` (for every axis; :class:`~wavecheck.options.
            CheckKeywords`), but ``block_edges``: a window per batch. With ``require``,
            :meth:`finish` raises :class:`~wavecheck.errors.RequirementError` when a rule it
            names is unchecked or indeterminate (with or without ``fail_on_violation``).
        fail_on_violation: raise :class:`WavecheckViolation` as soon as a batch has a failed
            rule (failing the test at that simulation time), and in :meth:`finish`.
        batch: value changes gathered before they are checked.
        batch_time: also check once this much simulated time has passed since the last check
            (``"100us"`` or exact seconds; None: by ``batch`` only).

    Raises:
        WavecheckError: an unknown drive; at :meth:`start`, an unusable mapping.
    """

    def __init__(
        self,
        drive: str | os.PathLike[str] | Drive | None = None,
        *,
        step: Handle | None = None,
        dir: Handle | None = None,  # noqa: A002 - the role's name
        enable: Handle | None = None,
        up: Handle | None = None,
        down: Handle | None = None,
        signals: Mapping[str, Handle] | None = None,
        axes: Mapping[str, Mapping[str, Any]] | None = None,
        fail_on_violation: bool = True,
        batch: int = DEFAULT_BATCH,
        batch_time: str | Fraction | None = None,
        options: CheckOptions | None = None,
        **keywords: Unpack[CheckKeywords],
    ) -> None:
        given = {"step": step, "dir": dir, "enable": enable, "up": up, "down": down}
        roles = {r: h for r, h in given.items() if h is not None}
        roles.update(signals or {})
        if axes and roles:
            raise UsageError("give either axes= or the roles of one axis (step=, dir=, ...)")
        if not axes and not roles:
            raise UsageError("StepMonitor needs the DUT's handles: step=dut.step, dir=dut.dir")
        tables: dict[str | None, dict[str, Any]] = (
            {name: dict(t) for name, t in axes.items()} if axes else {None: roles}
        )
        self._drives: dict[str | None, Drive] = {}
        for name, table in tables.items():
            ref = table.pop("drive", None) or drive
            if ref is None and options is not None and options.drive:
                ref = options.drive.get(name, options.drive.get(None))
            if ref is None:
                raise UsageError(f"axis {name} has no drive (give drive= or its 'drive')")
            self._drives[name] = _drive(ref)
        self._tables: dict[str | None, dict[str, Handle]] = tables
        self.several = bool(axes)
        self._options = replace(  # a bad option fails here, not at start
            options_from_keywords(self._drives, keywords=keywords, base=options),
            block_edges=1,  # a window per batch: the batches are this monitor's
        )
        self.fail_on_violation = fail_on_violation
        self.batch = max(1, batch)
        self._batch_time = (
            parse_option(batch_time, "batch_time", "time")
            if isinstance(batch_time, str)
            else batch_time
        )
        self._watched: list[_Watched] = []
        self._tasks: list[Task[None]] = []
        self._stream: MachineCheck | None = None
        self._report: MachineReport | None = None
        self._failed: set[tuple[str | None, str]] = set()

    # -- the run --------------------------------------------------------------------------------
    def start(self) -> StepMonitor:
        """Record from now on: the handles' present values, then every change (one background
        task per handle, :func:`cocotb.start_soon`). Returns the monitor."""
        if self._tasks:
            raise UsageError("this StepMonitor is already started")
        seen: dict[int, _Watched] = {}
        axes = []
        for name, table in self._tables.items():
            roles = {}
            for role, handle in table.items():
                w = seen.get(id(handle))
                if w is None:
                    w = _Watched(len(seen), handle, str(getattr(handle, "_path", role)))
                    seen[id(handle)] = w
                roles[role] = w.name
            axes.append(AxisMap(name, roles))
        self._watched = list(seen.values())
        names = [w.name for w in self._watched]
        if len(set(names)) != len(names):
            raise UsageError(f"two handles share a name: {', '.join(names)}")
        self.timebase = Timebase(Fraction(10) ** cocotb.simtime.time_precision)
        self._start = cocotb.simtime.get_sim_time("step")
        empty = np.zeros(0, np.int64)
        self._skeleton = Capture(
            path=f"cocotb:{cocotb.top._path if cocotb.top is not None else 'simulation'}",
            format="cocotb",
            timebase=self.timebase,
            resolution_ticks=0,  # the simulator's exact times
            samplerate_hz=None,
            start=self._start,
            end=self._start,
            channels=[Channel(w.name, w.index, 0, empty.copy()) for w in self._watched],
        )
        options = replace(self._options, axes=tuple(axes))
        self._stream = machine_for(self._skeleton, options, axes)
        self._builder = EdgeBuilder(len(self._watched))
        self._known = np.zeros(len(self._watched), dtype=bool)
        self._counts = [0] * len(self._watched)
        self._sig: list[int] = []
        self._t: list[int] = []
        self._v: list[int] = []
        self._now = self._start
        self._checked_to = self._start
        self._every = (
            None
            if self._batch_time is None
            else max(1, self.timebase.to_ticks(self._batch_time, "ceil"))
        )
        for w in self._watched:
            self._record(w.index, w.handle, self._start)
        self._tasks = [
            cocotb.start_soon(self._watch(w), name=f"wavecheck {w.name}") for w in self._watched
        ]
        return self

    async def _watch(self, w: _Watched) -> None:
        trigger = w.handle.value_change
        while True:
            await trigger
            t = cocotb.simtime.get_sim_time("step")
            if t != self._now:
                self._now = t
                due = len(self._t) >= self.batch
                if not due and self._every is not None:
                    due = t - self._checked_to >= self._every
                if due:
                    self._check(t)
            self._record(w.index, w.handle, t)

    def _record(self, index: int, handle: Handle, t: int) -> None:
        self._sig.append(index)
        self._t.append(t)
        self._v.append(_CODES.get(str(handle.value), 2))

    def _check(self, end: int) -> None:
        """Feed the changes gathered (all before ``end``) as one block; raise on a failure."""
        assert self._stream is not None
        b = self._builder
        if self._t:
            b.add(
                np.array(self._sig, np.int32),
                np.array(self._t, np.int64),
                np.array(self._v, np.int8),
            )
            self._sig, self._t, self._v = [], [], []
        block = EdgeBlock(end=end, start=self._start if self._checked_to == self._start else None)
        now = b.last_known >= 0
        for i in np.flatnonzero(now & ~self._known).tolist():
            block.known[i] = (int(b.known_from[i]), int(b.initial[i]))
        self._known = now
        for i in range(b.nsig):
            for pieces, into in (
                (b.edges, block.edges),
                (b.xz, block.xz_starts),
                (b.xz_end, block.xz_ends),
            ):
                if pieces[i]:
                    into[i] = np.concatenate(pieces[i]) if len(pieces[i]) > 1 else pieces[i][0]
                    pieces[i] = []
            self._counts[i] += len(block.edges.get(i, ()))
        self._checked_to = end
        self._stream.feed(block)
        if self.fail_on_violation:
            self._raise_new(end)

    def _raise_new(self, at: int) -> None:
        assert self._stream is not None
        for axis in self._stream.axes:
            name = axis.plan.name
            for r in axis.results:
                if r.violations and (name, r.rule) not in self._failed:
                    self._failed.add((name, r.rule))
                    raise WavecheckViolation(
                        self._message(
                            r,
                            axis.plan.drive.id if axis.plan.drive else "",
                            name,
                            self.timebase.seconds(at),
                        )
                    )

    def _message(self, r: RuleResult, drive: str, axis: str | None, at_s: Fraction | None) -> str:
        where = "" if axis is None else f" axis {axis}"
        when = "" if at_s is None else f" (by {format_time(at_s, 9)} of simulation)"
        worst = r.worst_violations(1)
        head = (
            f"wavecheck: {r.rule} failed against {drive}{where}: {r.violations} violation(s){when}"
        )
        if not worst:
            return head
        v = worst[0]
        if v.margin_ns is None:
            return f"{head}; first at {format_time(v.time_s, 9)}: {v.detail}"
        return (
            f"{head}; worst at {format_time(v.time_s, 9)}: measured {format_ns(v.measured_ns)}, "
            f"limit {format_ns(v.limit_ns)}, margin {format_ns(v.margin_ns, signed=True)}"
        )

    # -- the end --------------------------------------------------------------------------------
    async def finish(self) -> Report | MachineReport:
        """Stop recording, check what is left and return the report (a
        :class:`~wavecheck.report.Report`, or a
        :class:`~wavecheck.report.machine.MachineReport` with ``axes``).

        Raises:
            WavecheckViolation: with ``fail_on_violation``, a rule failed (the message names the
                first failed rule's worst violation; ``.report`` is the report).
            RequirementError: a rule of ``require`` is unchecked or indeterminate.
        """
        return self.report()

    def report(self) -> Report | MachineReport:
        """:meth:`finish` without ``await`` (from a function that is not a coroutine)."""
        if self._report is None:
            self._report = self._close()
        if self.fail_on_violation and self._report.verdict == "fail":
            bad = [(r, a) for a in self._report.axes for r in a.rules if r.verdict == "fail"]
            r, a = bad[0]
            raise WavecheckViolation(self._message(r, a.drive.id, a.axis, None), self._report)
        checked = self._report if self.several else self._report.axes[0]
        require_met(checked, self._options.require)
        return checked

    def _close(self) -> MachineReport:
        if self._stream is None:
            raise UsageError("StepMonitor.finish() before start()")
        for task in self._tasks:
            task.cancel()
        end = cocotb.simtime.get_sim_time("step")
        for w in self._watched:  # a change of this time step a watcher has not yet seen
            self._record(w.index, w.handle, end)
        fail, self.fail_on_violation = self.fail_on_violation, False
        try:
            self._check(NEVER)
        finally:
            self.fail_on_violation = fail
        return self._stream.finish(self._capture(end))

    def _capture(self, end: int) -> Capture:
        """The finished capture without edges (each channel's level, when it became known,
        its edge count)."""
        b = self._builder
        never = b.last_known < 0
        chans = [
            Channel(
                w.name,
                w.index,
                0 if never[w.index] else int(b.initial[w.index]),
                np.zeros(0, np.int64),
                known_from=end if never[w.index] else int(b.known_from[w.index]),
                never_known=bool(never[w.index]),
                counted=self._counts[w.index],
            )
            for w in self._watched
        ]
        return Capture(
            path=self._skeleton.path,
            format="cocotb",
            timebase=self.timebase,
            resolution_ticks=0,
            samplerate_hz=None,
            start=self._start,
            end=end,
            channels=chans,
        )
