"""Each axis resolved against a capture's channels, before any edge is read.

:func:`plan_axis` turns one axis of the options (:class:`~wavecheck.engine.options.CheckOptions`)
and a capture's *skeleton* (its channels, time base and resolution: no edges are needed) into an
:class:`AxisPlan`: the step type, the channel and inversion of every role, the active edge, the
pulse level, the resolution T, the rules to measure with their limits, the configured step rates
and the notes that do not depend on the edges. The engine (:mod:`wavecheck.engine.axis`) then
feeds the plan's channels block by block.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from fractions import Fraction
from typing import TYPE_CHECKING, Literal

import numpy as np

from wavecheck.capture.edges import Capture, EdgeArray
from wavecheck.drives.datasheet import ActiveEdge, Drive, Figure
from wavecheck.drives.overrides import tune_drive
from wavecheck.engine.intervals import figure_of, planned_rules
from wavecheck.engine.options import CheckOptions, for_axis
from wavecheck.engine.rates import pulse_level
from wavecheck.errors import UsageError
from wavecheck.record import record, replace
from wavecheck.rules import RULE_IDS, Rule, applicable
from wavecheck.steps.interface import (
    StepInterface,
    build_interface,
    leaf_name,
    mapped_channel_names,
)
from wavecheck.steps.mapping import AxisMap, check_axis_names, split_invert
from wavecheck.steptypes import StepType, step_type
from wavecheck.timebase import Timebase
from wavecheck.units import format_time

if TYPE_CHECKING:  # the LinuxCNC config is read only when given
    from wavecheck.linuxcnc.stepgen_config import ConfigRates

__all__ = [
    "AxisPlan",
    "ambiguous_note",
    "auto_map",
    "default_step_type",
    "plan_axes",
    "plan_axis",
    "pulse_level_seen",
    "resolve_resolution_ns",
    "settle_level",
]


def auto_map(
    capture: Capture,
    st: StepType,
    taken: Iterable[str] = (),
    waveforms: Capture | None = None,
) -> dict[str, str]:
    """Map roles to channels named after them (``STEP``, ``dir``, ``stepgen.0.phase-A`` …).

    A role is mapped only when exactly one channel's name (its last dotted part, any case) is the
    role's name; roles the user maps explicitly take precedence over this, and a channel in
    ``taken`` (the channels the user mapped, by name) is never mapped again to another role.

    A name is a hint, not evidence: given ``waveforms`` (the capture's edges, or its first
    part), a STEP, UP or DOWN so mapped whose waveform makes no step pulses (a free-running
    clock, a bus line, not one whole pulse; :func:`wavecheck.roles.name_conflicts`) is
    refused with the reason and the lines most like a STEP.

    Raises:
        UsageError: a name the waveform contradicts.
    """
    roles = (*st.outputs, "enable")
    used = set(taken)
    mapping: dict[str, str] = {}
    for role in roles:
        hits = [c for c in capture.channels if leaf_name(c.name) == role.lower()]
        if len(hits) == 1 and hits[0].name not in used:
            mapping[role] = hits[0].name
    if waveforms is not None:
        _refuse_contradicted_names(waveforms, mapping)
    return mapping


def _refuse_contradicted_names(waveforms: Capture, mapping: Mapping[str, str]) -> None:
    """Raise a UsageError when a pulse role of ``mapping`` (role → channel name, mapped by
    name) is a line whose waveform makes no step pulses; the candidates on the lines below."""
    from wavecheck.roles import PULSE_NAMES, name_conflicts

    index = {c.name: c.index for c in waveforms.channels}
    named = {r: index[ch] for r, ch in mapping.items() if r in PULSE_NAMES and ch in index}
    refused = name_conflicts(waveforms, named) if named else ()
    if not refused:
        return
    first = refused[0]
    hint = f"{first.role}={first.others[0]}" if first.others else f"{first.role}=LINE"
    import shlex  # for the message only: not at every start

    raise UsageError(
        f"{waveforms.path}: {first.conflict.question}: give the {first.role.upper()} line "
        f"(e.g. --map {shlex.quote(hint)}), or --map {shlex.quote(f'{first.role}={first.ref}')} "
        "to check this line anyway",
        tuple(
            line
            for k, r in enumerate(refused)
            for line in (
                "candidates:" if k == 0 else f"{r.conflict.question}:",
                *(f"  - {cand}" for cand in r.conflict.candidates),
            )
        ),
    )


def _suggest_type(capture: Capture, st: StepType) -> None:
    """Raise a UsageError that suggests ``--type`` when a step/dir or up/down check meets a
    capture whose channels are named like phase outputs (``phase-A``, ``stepgen.0.phase-B``)."""
    if st.kind == "phases":
        return
    phases = sorted(c.name for c in capture.channels if leaf_name(c.name).startswith("phase-"))
    if phases:
        raise UsageError(
            f"{capture.path}: no {st.pulse_roles[0]!r} channel, but {', '.join(map(repr, phases))} "
            "look like phase outputs: give the step type (--type 2 for quadrature, 3-14 for the "
            "other phase tables, 15 with --user-step-type)"
        )


def default_step_type(drive: Drive) -> int:
    """The step type a drive implies: its ``step_type`` if given, 1 for up/down, else 0."""
    declared = getattr(drive, "step_type", None)
    if declared is not None:
        return int(declared)
    if drive.interface == "up-down":
        return 1
    if drive.interface == "phases":
        raise UsageError(
            f"drive {drive.id!r} takes phase signals: give the step type (--type 2..15)"
        )
    return 0


def _measured_step_type(capture: Capture, roles: Mapping[str, str]) -> int:
    """The step type of an axis measured without a drive: 1 when it has UP/DOWN (mapped or a
    channel so named), the one the phase outputs' waveforms walk, else 0 (step/dir)."""
    named = {leaf_name(c.name) for c in capture.channels}
    keys = {k.lower() for k in roles}
    if "step" in keys or ("step" in named and not keys & {"up", "down"}):
        return 0
    if keys & {"up", "down"} or "up" in named:
        return 1
    if any(k.startswith("phase-") for k in keys | named):
        from wavecheck.roles import propose

        found = [a.step_type for a in propose(capture).axes if a.step_type]
        if len(set(found)) == 1:
            return found[0]
        raise UsageError(
            f"{capture.path}: phase outputs but no step type: give --type (2 for quadrature, "
            "3-14 for the other phase tables, 15 with --user-step-type)"
        )
    return 0


def resolve_resolution_ns(
    capture: Capture, resolution: Fraction | None
) -> tuple[Fraction, str | None]:
    """T in exact ns, and a note for the report: the user's resolution (exact seconds) if
    given, else the capture's own (one sample period; 0 for a simulator VCD).

    The user's value is taken exactly as given, a fraction of a tick included (100 ns on a 1 us
    timescale stays 100 ns); a value finer than a sampled capture's own resolution is used too,
    with a note that the verdicts assume it.
    """
    if resolution is None:
        return capture.resolution_ns, None
    if resolution < 0:
        raise UsageError(f"--resolution must not be negative, got {format_time(resolution)}")
    ns = resolution * 10**9
    own = capture.resolution_ns
    if own and ns < own:
        return ns, (
            f"--resolution {format_time(resolution)} is finer than the capture's sample period "
            f"{format_time(own / 10**9)}: verdicts assume it"
        )
    return ns, None


def ambiguous_note(count: int, first: EdgeArray, timebase: Timebase) -> str | None:
    """The report's note on ``count`` steps of ambiguous direction, ``first[0]`` the first one's
    tick (None when there is none)."""
    if not count:
        return None
    at = format_time(timebase.seconds(int(first[0])))
    return (
        f"{count} step(s) of ambiguous direction (DIR changed at the same "
        f"sample as the active edge; first at {at}); counted as neither forward nor reverse"
    )


@record(frozen=True)
class AxisPlan:
    """One axis resolved against a capture's channels (module docstring).

    Attributes:
        name: the axis name (None: the unnamed single axis).
        drive: the drive (its figures tuned by ``--limit``/``--margin``); None: measured only.
        step_type: the LinuxCNC step type decoded.
        interface: the mapped roles (channel, index, inversion; no edges).
        active_edge: the edge that counts a step.
        forward_level: the DIR level taken as forward.
        level: the level of the generator's pulses at the drive's input (stated, seen in the
            waveform, or assumed: :attr:`level_basis`).
        level_basis: ``"stated"`` (``--pulse-level``), ``"seen"`` (the waveform shows it:
            :func:`pulse_level_seen`) or ``"assumed"`` (high at the generator's output).
        resolution_ns: T used for the verdicts, exact ns.
        user_table: the state table of step type 15.
        rules: the rules measured, in report order.
        limits: rule id → (limit in exact ns, its figure); absent for ``state_sequence`` and
            for every rule of a measured-only axis.
        not_stated: rules of this step type the drive gives no figure for.
        not_applicable: rules the drive states that this step type has no use for.
        configured: the stepgen configuration's ``config``/``latency_safe`` rates.
        notes: what the report should say that does not depend on the edges (no DIR mapped).
        resolution_note: what the report should say of a ``--resolution`` finer than the
            capture's own.
        found: how the roles were found (the waveforms' mapping), said first.
    """

    name: str | None
    drive: Drive | None
    step_type: StepType
    interface: StepInterface
    active_edge: ActiveEdge
    forward_level: int
    level: int
    resolution_ns: Fraction
    user_table: tuple[int, ...] | None
    rules: tuple[Rule, ...]
    limits: Mapping[str, tuple[Fraction, Figure]]
    not_stated: tuple[str, ...]
    not_applicable: tuple[str, ...]
    configured: ConfigRates | None
    notes: tuple[str, ...]
    resolution_note: str | None = None
    found: tuple[str, ...] = ()
    level_basis: LevelBasis = "assumed"

    @property
    def level_open(self) -> bool:
        """The pulse level was not stated and matters (a step/dir or up/down interface with one
        active edge): the waveform may show it (:func:`pulse_level_seen`)."""
        return (
            self.level_basis == "assumed"
            and self.step_type.kind != "phases"
            and self.active_edge != "both"
        )

    @property
    def channels(self) -> set[int]:
        """The capture channels the axis reads (indices)."""
        return {s.index for s in self.interface.signals.values()}


LevelBasis = Literal["stated", "seen", "assumed"]

#: Edges of each pulse line the pulse level is told from (:func:`pulse_level_seen`).
LEVEL_EDGES = 4096


def pulse_level_seen(plan: AxisPlan, capture: Capture, before: int) -> int | None:
    """The level of the pulses at the drive's input as the waveform shows it, or None when it
    does not. A step generator makes pulses of one width and varies the gaps between them with
    the speed, so the pulses are the level (after inversion) whose complete stretches spread at
    most an eighth as much as the other level's, which do spread; judged on each pulse line's
    first :data:`LEVEL_EDGES` edges before tick ``before`` (at least three stretches of each
    level; every line must agree).

    At one constant speed both levels hold still and the waveform does not decide (a burst of
    long pulses with short gaps stays the generator's own statement: high at its output)."""
    from wavecheck.steps.primitives import widths

    seen: set[int] = set()
    for role in plan.step_type.pulse_roles:
        sig = plan.interface.get(role)
        if sig is None:
            continue
        ch = capture.channel(sig.index)
        edges = ch.edges[: int(np.searchsorted(ch.edges, before, side="left"))][:LEVEL_EDGES]
        initial = ch.initial ^ int(sig.inverted)
        high = widths(initial, edges, 1).measured
        low = widths(initial, edges, 0).measured
        if min(len(high), len(low)) < 3:
            continue
        spread_high = int(high.max()) - int(high.min())
        spread_low = int(low.max()) - int(low.min())
        if 8 * spread_high <= spread_low and spread_low > 0:
            seen.add(1)
        elif 8 * spread_low <= spread_high and spread_high > 0:
            seen.add(0)
        else:
            return None
    return seen.pop() if len(seen) == 1 else None


def settle_level(plan: AxisPlan, capture: Capture, before: int) -> AxisPlan:
    """``plan`` with the pulse level the waveform shows (:func:`pulse_level_seen`), a note when
    that differs from the assumption (pulses high at the generator's output)."""
    if not plan.level_open:
        return plan
    level = pulse_level_seen(plan, capture, before)
    if level is None:
        return plan
    notes = plan.notes
    if level != plan.level:
        word = "high" if level else "low"
        notes = (
            *notes,
            f"the pulses are {word} at the drive's input (the waveform shows it: the {word} "
            "stretches of the pulse lines keep one width while the others vary), not as "
            "assumed from a generator pulsing high (--pulse-level states it)",
        )
    return replace(plan, level=level, level_basis="seen", notes=notes)


def plan_axis(
    capture: Capture,
    axis: AxisMap,
    options: CheckOptions,
    drive: Drive | None,
    invert: Iterable[str] = (),
    waveforms: Capture | None = None,
) -> AxisPlan:
    """Resolve ``axis`` against ``capture``'s channels (a skeleton is enough).

    Args:
        capture: the capture (channels, time base, resolution).
        axis: the axis's name and mapping (roles left out are mapped by channel name).
        options: the run's options (step type, forward level, active edge … per axis).
        drive: the axis's drive, tuned; None: measured only (no limit, no verdict).
        invert: the roles to invert on this axis.
        waveforms: the capture with edges (or its first part), when it was read to tell the
            roles: a measured-only axis of phase outputs takes the step type they walk.

    Raises:
        UsageError: an unknown channel or role, a bad step type, a pulse role not mapped.
    """
    explicit = dict(axis.roles)
    number = for_axis(options.step_type, axis.name)
    if number is None:
        number = axis.step_type
    if number is None:
        number = (
            _measured_step_type(waveforms or capture, explicit)
            if drive is None
            else default_step_type(drive)
        )
    st = step_type(number, options.user_table)
    full_map = auto_map(capture, st, mapped_channel_names(capture, explicit), waveforms)
    full_map.update(explicit)
    iface = build_interface(capture, full_map, [*invert, *axis.invert])
    for role in st.pulse_roles:
        if iface.get(role) is None:
            _suggest_type(capture, st)
        iface.require(role)
    edge: ActiveEdge = options.active_edge or ("rising" if drive is None else drive.active_edge)
    resolution_ns, resolution_note = resolve_resolution_ns(capture, options.resolution)
    notes = []
    if st.kind == "step-dir" and iface.get("dir") is None:
        notes.append("no DIR channel mapped: step directions are unknown, DIR rules unchecked")
    forward = for_axis(options.forward_level, axis.name)
    if drive is None:
        rules = tuple(r for r in applicable(st.kind) if r.check != "sequence")
        limits: dict[str, tuple[Fraction, Figure]] = {}
        not_stated: tuple[str, ...] = ()
        not_applicable: tuple[str, ...] = ()
    else:
        rules, not_stated = planned_rules(drive, st)
        limits = {r.id: fig for r in rules if (fig := figure_of(drive, r)) is not None}
        used = {r.id for r in applicable(st.kind)}
        not_applicable = tuple(r for r in RULE_IDS if r not in used and drive.figure(r) is not None)
    configured = None
    if options.stepgen is not None and drive is not None:
        from wavecheck.linuxcnc.stepgen_config import config_rates

        step = iface.get("step")
        configured = config_rates(
            options.stepgen,
            drive,
            options.latency_ns,
            step_inverted=step.inverted if step is not None else False,
            step_type=st.number,
        )
    return AxisPlan(
        name=axis.name,
        drive=drive,
        step_type=st,
        interface=iface,
        active_edge=edge,
        forward_level=0 if forward is None else forward,
        level=pulse_level(iface, st, 1 if options.pulse_level is None else options.pulse_level),
        level_basis="assumed" if options.pulse_level is None else "stated",
        resolution_ns=resolution_ns,
        user_table=options.user_table,
        rules=rules,
        limits=limits,
        not_stated=not_stated,
        not_applicable=not_applicable,
        configured=configured,
        notes=tuple(notes),
        resolution_note=resolution_note,
    )


def plan_axes(
    capture: Capture,
    axes: list[AxisMap],
    options: CheckOptions,
    waveforms: Capture | None = None,
) -> list[AxisPlan]:
    """Every axis of ``axes`` planned on ``capture``, each with its own drive (loaded once per
    drive and tuned by the options' ``limits`` and ``margin``); ``waveforms``: as
    :func:`plan_axis`.

    Raises:
        UsageError: an axis without a drive (when the run has drives), and what
            :func:`plan_axis` raises.
    """
    names = [a.name for a in axes]
    check_axis_names(
        {
            "--drive": options.drive,
            "--type": options.step_type,
            "--dir-forward": options.forward_level,
        },
        names,
    )
    inverts = split_invert(options.invert, names)
    tuned: dict[int, Drive] = {}
    plans = []
    for axis in axes:
        drive = None
        if not options.measure_only:
            given = for_axis(options.drive, axis.name)
            if given is None:
                raise UsageError(
                    f"--drive: axis {axis.name} has no drive (add --drive {axis.name}=ID)"
                )
            if id(given) not in tuned:
                tuned[id(given)] = (
                    tune_drive(given, options.limits, options.margin)
                    if options.limits or options.margin
                    else given
                )
            drive = tuned[id(given)]
        plans.append(plan_axis(capture, axis, options, drive, inverts[axis.name], waveforms))
    return plans


def with_found(plan: AxisPlan, found: Iterable[str]) -> AxisPlan:
    """``plan`` with the notes on how its roles were found."""
    return replace(plan, found=tuple(found))
