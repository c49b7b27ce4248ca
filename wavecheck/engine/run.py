"""The engine's entry: a block source and the options in, one report per axis out.

:func:`check_source` reads a :class:`~wavecheck.capture.blocks.BlockSource` once: it finds the axes
(the options' mapping; else channels named after their roles; else the roles told from the
waveforms of the first :attr:`~wavecheck.engine.options.CheckOptions.infer_edges` edges, which are
then checked like the rest), plans each axis on the source's skeleton
(:mod:`wavecheck.engine.resolve`), feeds every block to every axis (:mod:`wavecheck.engine.axis`) and
returns a :class:`~wavecheck.engine.outcome.MachineReport`. A capture already in memory is a
source of one block (:func:`check_capture`). With several axes, a note says whether their steps lie
on one common periodic lattice (one thread or timer makes them), judged on the first
:data:`TIMER_TICKS` step times of them all.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Iterator, Sequence
from fractions import Fraction

import numpy as np

from wavecheck.capture.blocks import BlockSource, EdgeBlock, MemorySource, assemble
from wavecheck.capture.edges import NEVER, Capture, EdgeArray
from wavecheck.engine.axis import AxisCheck
from wavecheck.engine.options import CheckOptions
from wavecheck.engine.outcome import MachineReport
from wavecheck.engine.resolve import LEVEL_EDGES, AxisPlan, plan_axes, settle_level, with_found
from wavecheck.engine.sinks import IntervalSink, StepSink, TimerSample
from wavecheck.errors import UsageError
from wavecheck.steps.interface import leaf_name
from wavecheck.steps.mapping import AxisMap
from wavecheck.units import format_time

__all__ = [
    "TIMER_TICKS",
    "MachineCheck",
    "axes_from_waveforms",
    "check_capture",
    "check_source",
    "common_timer",
    "axes_for",
    "machine_for",
    "names_give_roles",
    "needs_waveforms",
    "start",
]

#: Step times the several-axes common-timer note reads: the first of the axes' steps merged (a
#: bound on its cost; a thread or timer that makes them all shows in any stretch of them).
TIMER_TICKS = 1 << 14
#: Fewest step times from which the note tells anything.
TIMER_MIN = 64

#: The roles that carry an axis's motion: an axis mapping none of them takes its pulse line by
#: a channel's name.
_PULSE_ROLES = frozenset({"step", "up", "down", *(f"phase-{x}" for x in "abcde")})

StepSinks = Callable[[AxisPlan], Sequence[StepSink]]
IntervalSinks = Callable[[AxisPlan], IntervalSink | None]


def names_give_roles(capture: Capture) -> bool:
    """Whether a channel is named after a pulse role (``step``, ``up``, ``phase-A``, as the
    last part of a hierarchical name): then roles are mapped by name, not told from waveforms."""
    from wavecheck.roles.names import named_kind

    return named_kind([c.name for c in capture.channels]) is not None


def axes_from_waveforms(capture: Capture) -> tuple[list[AxisMap], list[str]]:
    """The axes the waveforms of ``capture`` show (:func:`wavecheck.roles.propose`) and a note on
    how they were found.

    Raises:
        UsageError: the waveforms do not settle the roles: a capture without step signals says
            what its lines look like instead (one line); an ambiguous one lists the questions
            and candidates on the lines below the error.
    """
    from wavecheck.roles import propose

    proposal = propose(capture)
    if not proposal.axes and not proposal.ambiguous:
        hint = (
            f"; {proposal.hint()}" if proposal.suggested else "; give --map to check a line anyway"
        )
        raise UsageError(
            f"{capture.path}: no step signal found: the lines look like {proposal.summary()}{hint}"
        )
    if not proposal.unambiguous:
        example = proposal.map_args() if proposal.axes else ""
        if not example and proposal.candidates:
            import shlex  # for the message only: not at every start

            example = f"--map step={shlex.quote(proposal.candidates[0])}"
        hint = f" (e.g. {example})" if example else ""
        details = tuple(
            line
            for c in proposal.ambiguous
            for line in (f"{c.question}:", *(f"  - {cand}" for cand in c.candidates))
        )
        n = len(proposal.ambiguous)
        raise UsageError(
            f"{capture.path}: the channels' roles cannot be told from the waveforms "
            f"({n} question{'s' if n != 1 else ''} below); give --map{hint}",
            details,
        )
    single = len(proposal.axes) == 1
    axes = [
        AxisMap(None if single else a.name, dict(a.mapping), a.step_type or None, a.inverted)
        for a in proposal.axes
    ]
    found = f"channels mapped from their waveforms: {proposal.map_args()} {proposal.type_args()}"
    return axes, [found.rstrip()]


def common_timer(ticks: Sequence[EdgeArray], capture: Capture, resolution_ns: Fraction) -> str:
    """One line: do the axes' steps (``ticks``, one array per axis, each the axis's first steps)
    lie on one common periodic lattice (one thread or timer)? Read from the first
    :data:`TIMER_TICKS` step times of them all by :func:`wavecheck.lattice.common_period`."""
    from wavecheck.lattice import common_period
    from wavecheck.linuxcnc.worstcase import union

    stepping = [t for t in ticks if len(t)]
    if len(stepping) < 2:
        return "fewer than two axes step: no common timer to look for"
    times = union(*stepping)
    if len(times) < TIMER_MIN:
        return (
            f"too few steps ({len(times)} step times) to tell whether one common periodic "
            "lattice (one thread or timer) makes them"
        )
    sample = times[:TIMER_TICKS]
    period, why = common_period(sample, capture.timebase.tick_ns, resolution_ns)
    bound = f" (from the first {len(sample)} step times)" if len(sample) < len(times) else ""
    if period is not None:
        return (
            f"the steps of every axis lie on one common periodic lattice{bound}: one base "
            f"thread or timer makes them (P = {float(period) / 1000:.6g} us, as `wavecheck "
            "latency` reads these step times)"
        )
    return f"the axes' steps are not on one common periodic lattice ({why}){bound}"


class MachineCheck:
    """Every axis of one capture, fed the same blocks: :meth:`feed`, then :meth:`finish`.

    Args:
        skeleton: the capture's skeleton.
        plans: the axes, planned on it.
        options: the run's options (block size, violations kept, pictures).
        step_sinks: each axis's extra step sinks (``--steps-csv``, ``compare`` …).
        interval_sinks: each axis's interval sink (``measure``).
    """

    def __init__(
        self,
        skeleton: Capture,
        plans: Sequence[AxisPlan],
        options: CheckOptions,
        *,
        step_sinks: StepSinks | None = None,
        interval_sinks: IntervalSinks | None = None,
    ) -> None:
        self.options = options
        self.block_edges = options.block_edges
        several = len(plans) > 1 or (len(plans) == 1 and plans[0].name is not None)
        self.timers = [TimerSample(TIMER_TICKS) for _ in plans] if several else []
        self.axes = [
            AxisCheck(
                p,
                skeleton,
                keep_violations=options.keep_violations,
                pictures=options.pictures,
                step_sinks=[
                    *(step_sinks(p) if step_sinks is not None else ()),
                    *self.timers[k : k + 1],
                ],
                interval_sink=None if interval_sinks is None else interval_sinks(p),
            )
            for k, p in enumerate(plans)
        ]

    @property
    def channels(self) -> set[int]:
        """The channels every axis reads (indices)."""
        return {i for a in self.axes for i in a.plan.channels}

    def feed(self, block: EdgeBlock) -> None:
        """Take one block (every axis)."""
        for a in self.axes:
            a.feed(block, self.block_edges)

    def flush(self, end: int) -> None:
        """Check now what has gathered up to ``end`` (a live check's figures stay current)."""
        for a in self.axes:
            a.flush(end)

    def settled(self, end: int) -> int:
        """The tick before which every axis has handed all its steps to its sinks, once the
        blocks up to ``end`` are fed (an axis with edges waiting holds it at its last window)."""
        return min((a.t0 if a.pending else end for a in self.axes), default=end)

    def close(self) -> None:
        """Check the last window of every axis."""
        for a in self.axes:
            a.close()

    def finish(self, capture: Capture) -> MachineReport:
        """Close every axis and give the reports (``capture``: the finished skeleton)."""
        self.close()
        reports = [a.report(capture) for a in self.axes if a.plan.drive is not None]
        notes = []
        if self.timers:
            res = reports[0].resolution_ns if reports else capture.resolution_ns
            notes.append(common_timer([t.ticks for t in self.timers], capture, res))
        return MachineReport(capture, reports, notes)


def axes_for(options: CheckOptions, capture: Capture) -> tuple[list[AxisMap], list[str]]:
    """The axes to check on ``capture`` and the notes on how they were found: the options'
    mapping; else the channels named after their roles; else the roles its waveforms show
    (``capture`` then holds edges: the whole capture, or its first part).

    Raises:
        UsageError: the waveforms do not settle the roles.
    """
    if options.axes:
        return list(options.axes), []
    if names_give_roles(capture):
        from wavecheck.roles.names import axes_by_scope

        scoped = axes_by_scope([c.name for c in capture.channels])
        if scoped is None:
            return [AxisMap(None, {})], []
        import shlex  # for the message only: not at every start

        args = " ".join(
            "--map " + ",".join(f"{name}.{role}={shlex.quote(ch)}" for role, ch in roles.items())
            for name, roles in scoped
        )
        found = f"channels mapped by their names, one axis per scope: {args}"
        return [AxisMap(name, roles) for name, roles in scoped], [found]
    return axes_from_waveforms(capture)


def needs_waveforms(options: CheckOptions, skeleton: Capture) -> bool:
    """Whether the axes must be told from the waveforms (no mapping, no channel named after a
    role; or, measured without a drive or step type, phase outputs: the step type they walk) or
    the names judged against them (an axis whose pulse line is left to a channel's name:
    :func:`wavecheck.engine.resolve.auto_map`): the edges of every channel are needed first."""
    named = names_give_roles(skeleton)
    if not options.axes and not named:
        return True
    axes = options.axes or [AxisMap(None)]
    if named and any(not {r.lower() for r in a.roles} & _PULSE_ROLES for a in axes):
        return True
    phases = any(leaf_name(c.name).startswith("phase-") for c in skeleton.channels)
    return options.measure_only and phases and not options.step_type


def machine_for(
    skeleton: Capture,
    options: CheckOptions,
    axes: Sequence[AxisMap],
    found: Sequence[str] = (),
    *,
    waveforms: Capture | None = None,
    step_sinks: StepSinks | None = None,
    interval_sinks: IntervalSinks | None = None,
) -> MachineCheck:
    """Every axis of ``axes`` planned on ``skeleton`` (``found``: how they were found, a note of
    each report; ``waveforms``: the capture read to find them) and ready to be fed."""
    plans = [with_found(p, found) for p in plan_axes(skeleton, list(axes), options, waveforms)]
    return MachineCheck(
        skeleton, plans, options, step_sinks=step_sinks, interval_sinks=interval_sinks
    )


def start(
    source: BlockSource,
    options: CheckOptions,
    *,
    step_sinks: StepSinks | None = None,
    interval_sinks: IntervalSinks | None = None,
) -> tuple[MachineCheck, Iterator[EdgeBlock]]:
    """The axes of ``source`` planned and ready to be fed, and the source's blocks to feed them.

    Without a mapping or role names, the roles are told from the waveforms of the first
    :attr:`~wavecheck.engine.options.CheckOptions.infer_edges` edges (every channel read); an
    axis whose pulse level is not stated takes the one its pulse lines show
    (:func:`wavecheck.engine.resolve.settle_level`) in their first edges. The blocks read for
    either come first among the blocks returned. What is decided from a first part depends on
    the capture's edges only, never on how its reader cuts it into blocks."""
    skeleton = source.skeleton
    read: list[EdgeBlock] = []
    it: Iterator[EdgeBlock] | None = None
    waveforms = None
    if needs_waveforms(options, skeleton):
        source.want(range(len(skeleton.channels)))
        it = source.blocks()
        _read_until(it, read, lambda edges: edges >= options.infer_edges)
        before = _tick_of_edge(assemble(skeleton, read), options.infer_edges)
        waveforms = assemble(skeleton, read, before=before)
        axes, found = axes_for(options, waveforms)
        if before < NEVER and found:
            at = format_time(skeleton.timebase.seconds(before))
            found = [f"{found[0]} (told from the first {options.infer_edges} edges, to {at})"]
    else:
        axes, found = axes_for(options, skeleton)
    plans = [with_found(p, found) for p in plan_axes(skeleton, list(axes), options, waveforms)]
    open_level = [p for p in plans if p.level_open]
    if open_level:
        channels = {i for p in plans for i in p.channels}
        if it is None:  # planned first: a bit of a vector is a channel of the source
            source.want(channels)
            it = source.blocks()
        roles = [(p.interface.signals[r].index) for p in open_level
                 for r in p.step_type.pulse_roles if r in p.interface.signals]  # fmt: skip
        counts = dict.fromkeys(roles, 0)
        for block in read:
            for i in counts:
                counts[i] += len(block.edges.get(i, ()))

        def enough(edges: int) -> bool:
            return edges >= options.infer_edges or min(counts.values()) >= LEVEL_EDGES

        _read_until(it, read, enough, counts)
        seen = assemble(skeleton, read)
        before = _tick_of_edge(seen, options.infer_edges, channels)
        plans = [settle_level(p, seen, before) for p in plans]
    machine = MachineCheck(
        skeleton, plans, options, step_sinks=step_sinks, interval_sinks=interval_sinks
    )
    source.want(machine.channels)
    blocks = source.blocks() if it is None else itertools.chain(_handed_on(read), it)
    return machine, blocks


def _handed_on(read: list[EdgeBlock]) -> Iterator[EdgeBlock]:
    """The blocks of ``read``, each let go of once handed on (the first part read to tell the
    roles is not held while the rest of the capture is checked)."""
    read.reverse()
    while read:
        yield read.pop()


def _read_until(
    it: Iterator[EdgeBlock],
    read: list[EdgeBlock],
    done: Callable[[int], bool],
    counts: dict[int, int] | None = None,
) -> None:
    """Read blocks of ``it`` into ``read`` until ``done(edges read so far)`` or the end;
    ``counts``: channel → its edges so far, kept up to date."""
    edges = sum(len(e) for b in read for e in b.edges.values())
    if done(edges):
        return
    for block in it:
        read.append(block)
        for i, e in block.edges.items():
            edges += len(e)
            if counts is not None and i in counts:
                counts[i] += len(e)
        if done(edges):
            return


def _tick_of_edge(capture: Capture, n: int, channels: set[int] | None = None) -> int:
    """The tick of the ``n``-th edge of ``capture`` (over ``channels``, default all), counted in
    time order: what came before it does not depend on how blocks were cut; NEVER when there
    are fewer."""
    arrays = [c.edges for c in capture.channels if channels is None or c.index in channels]
    total = sum(len(a) for a in arrays)
    if total < n or not arrays:
        return NEVER
    ticks = np.concatenate(arrays)
    return int(np.partition(ticks, n - 1)[n - 1]) + 1


def check_source(
    source: BlockSource,
    options: CheckOptions,
    *,
    step_sinks: StepSinks | None = None,
    interval_sinks: IntervalSinks | None = None,
) -> MachineReport:
    """Check every axis of ``source`` (read once) with ``options``.

    Raises:
        WavecheckError: an unreadable source, a mapping or option that does not fit its
            channels, roles that cannot be told from the waveforms.
    """
    machine, blocks = start(source, options, step_sinks=step_sinks, interval_sinks=interval_sinks)
    for block in blocks:
        machine.feed(block)
    return machine.finish(source.capture())


def check_capture(
    capture: Capture,
    options: CheckOptions,
    *,
    step_sinks: StepSinks | None = None,
    interval_sinks: IntervalSinks | None = None,
) -> MachineReport:
    """:func:`check_source` on a capture already in memory (one block)."""
    return check_source(
        MemorySource(capture), options, step_sinks=step_sinks, interval_sinks=interval_sinks
    )
