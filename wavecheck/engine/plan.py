"""Check one capture against one drive: map → decode → measure every rule → report.

:func:`run_check` is the library entry point the CLI (and later the HTML/JUnit/plot outputs,
several captures, INI/HAL configurations) build on; it does no I/O. :func:`check_machine` checks
every axis of one capture (each against its own drive) from the same edge arrays; ``check``,
``compare``, :func:`wavecheck.check_axes` and the pytest plugin all go through it.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import replace
from fractions import Fraction

from wavecheck.axes import AxisMap
from wavecheck.capture.edges import Capture, EdgeArray
from wavecheck.drives.model import ActiveEdge, Drive
from wavecheck.engine.decode import decode
from wavecheck.engine.interface import build_interface, mapped_channel_names
from wavecheck.engine.intervals import run_rules
from wavecheck.engine.rates import max_step_rates
from wavecheck.engine.rates import pulse_level as generator_pulse_level
from wavecheck.errors import UsageError
from wavecheck.linuxcnc.config import LinuxCNCConfig, config_rates
from wavecheck.linuxcnc.steptypes import StepType, step_type
from wavecheck.report.machine import MachineReport, common_timer
from wavecheck.report.model import Report
from wavecheck.timebase import Timebase
from wavecheck.units import format_time, parse_time

__all__ = [
    "ambiguous_note",
    "auto_map",
    "check_machine",
    "default_step_type",
    "resolve_resolution_ns",
    "run_check",
]


def _leaf(name: str) -> str:
    """``"stepgen.0.phase-A"`` → ``"phase-a"``; ``"top.STEP"`` → ``"step"``."""
    return name.strip().rsplit(".", 1)[-1].strip().lower().replace("_", "-")


def auto_map(capture: Capture, st: StepType, taken: Iterable[str] = ()) -> dict[str, str]:
    """Map roles to channels named after them (``STEP``, ``dir``, ``stepgen.0.phase-A`` …).

    A role is mapped only when exactly one channel's name (its last dotted part, any case) is the
    role's name; roles the user maps explicitly take precedence over this, and a channel in
    ``taken`` (the channels the user mapped, by name) is never mapped again to another role.
    """
    roles = (*st.outputs, "enable")
    used = set(taken)
    mapping: dict[str, str] = {}
    for role in roles:
        hits = [c for c in capture.channels if _leaf(c.name) == role.lower()]
        if len(hits) == 1 and hits[0].name not in used:
            mapping[role] = hits[0].name
    return mapping


def _suggest_type(capture: Capture, st: StepType) -> None:
    """Raise a UsageError that suggests ``--type`` when a step/dir or up/down check meets a
    capture whose channels are named like phase outputs (``phase-A``, ``stepgen.0.phase-B``)."""
    if st.kind == "phases":
        return
    phases = sorted(c.name for c in capture.channels if _leaf(c.name).startswith("phase-"))
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


def resolve_resolution_ns(
    capture: Capture, resolution: str | Fraction | None
) -> tuple[Fraction, str | None]:
    """T in exact ns, and a note for the report: the user's ``--resolution`` (a time such as
    ``"500ns"``, or exact seconds as a Fraction) if given, else the capture's own (one sample
    period; 0 for a simulator VCD).

    The user's value is taken exactly as given, a fraction of a tick included (100 ns on a 1 us
    timescale stays 100 ns); a value finer than a sampled capture's own resolution is used too,
    with a note that the verdicts assume it.
    """
    if resolution is None:
        return capture.resolution_ns, None
    seconds = parse_time(resolution) if isinstance(resolution, str) else Fraction(resolution)
    if seconds < 0:
        raise UsageError(f"--resolution must not be negative, got {format_time(seconds)}")
    ns = seconds * 10**9
    own = capture.resolution_ns
    if own and ns < own:
        return ns, (
            f"--resolution {format_time(seconds)} is finer than the capture's sample period "
            f"{format_time(own / 10**9)}: verdicts assume it"
        )
    return ns, None


def ambiguous_note(count: int, first: EdgeArray, timebase: Timebase) -> str | None:
    """The report's note on ``count`` steps of ambiguous direction, ``first[0]`` the first one's
    tick (None when there is none); shared with the streamed engine (:mod:`wavecheck.stream`)."""
    if not count:
        return None
    at = format_time(timebase.seconds(int(first[0])))
    return (
        f"{count} step(s) of ambiguous direction (DIR changed at the same "
        f"sample as the active edge; first at {at}); counted as neither forward nor reverse"
    )


def run_check(
    capture: Capture,
    drive: Drive,
    mapping: Mapping[str, str] | None = None,
    invert: Iterable[str] = (),
    step_type_number: int | None = None,
    resolution: str | Fraction | None = None,
    *,
    forward_level: int = 0,
    active_edge: ActiveEdge | None = None,
    user_table: tuple[int, ...] | None = None,
    stepgen: LinuxCNCConfig | None = None,
    latency_ns: Fraction | None = None,
    pulse_level: int = 1,
    axis: str | None = None,
) -> Report:
    """Check ``capture`` against ``drive``.

    Args:
        capture: the capture (edges in ticks).
        drive: the drive's rules.
        mapping: role → channel name or index; roles missing here are mapped by name when a
            channel is called after the role (see :func:`auto_map`).
        invert: roles to invert so that levels are the drive's input levels.
        step_type_number: LinuxCNC step type 0–15; default the drive's (its ``step_type``, else
            1 for an up/down drive, else 0).
        resolution: T override (``"500ns"`` or exact seconds); default the capture's.
        forward_level: DIR level meaning forward (default 0: DIR high = reverse, as LinuxCNC
            and grbl drive it).
        active_edge: override the drive's active edge.
        user_table: state table for step type 15.
        stepgen: a LinuxCNC stepgen configuration (INI/HAL, options) for the ``config`` and
            ``latency_safe`` step rates; the STEP pin counts as inverted between stepgen and the
            drive when ``invert`` holds ``step``.
        latency_ns: the worst base-thread latency ``J`` for ``latency_safe`` (ns).
        axis: the axis name in a run of several axes (kept on the report).
        pulse_level: the level of the generator's step pulses at its output (1 high, as LinuxCNC,
            grbl, Marlin, Klipper and Smoothieware make them by default; 0 low); with ``invert``
            the drive sees the other level.

    Raises:
        WavecheckError: unusable input (unknown channel or role, bad type, bad resolution).
    """
    st = step_type(
        default_step_type(drive) if step_type_number is None else step_type_number, user_table
    )
    explicit = dict(mapping or {})
    full_map = auto_map(capture, st, mapped_channel_names(capture, explicit))
    full_map.update(explicit)
    iface = build_interface(capture, full_map, invert)
    edge: ActiveEdge = active_edge or drive.active_edge
    for role in st.pulse_roles:
        if iface.get(role) is None:
            _suggest_type(capture, st)
        iface.require(role)
    resolution_ns, resolution_note = resolve_resolution_ns(capture, resolution)
    steps = decode(
        iface, st.number, active_edge=edge, forward_level=forward_level, user_table=user_table
    )
    if pulse_level not in (0, 1):
        raise UsageError(f"pulse level must be 0 (low) or 1 (high), got {pulse_level!r}")
    level = generator_pulse_level(iface, st, pulse_level)
    ruleset = run_rules(iface, st, steps, drive, resolution_ns, edge, level)
    own = next(
        (r for r in ruleset.results if r.rule == ("step_high" if level else "step_low")), None
    )
    rates = max_step_rates(
        iface,
        st,
        steps,
        drive,
        edge,
        capture.timebase,
        level=level,
        pulse_verdict=None if own is None else own.verdict,
    )
    if stepgen is not None:
        configured = config_rates(
            stepgen,
            drive,
            latency_ns,
            step_inverted=iface.signals["step"].inverted if "step" in iface.signals else False,
            step_type=st.number,
        )
        rates = replace(rates, configured=configured)
    notes = list(capture.notes)
    if st.kind == "step-dir" and iface.get("dir") is None:
        notes.append("no DIR channel mapped: step directions are unknown, DIR rules unchecked")
    amb = ambiguous_note(steps.ambiguous_count, steps.ambiguous, capture.timebase)
    if amb:
        notes.append(amb)
    if resolution_note:
        notes.append(resolution_note)
    return Report(
        capture=capture,
        drive=drive,
        step_type=st,
        interface=iface,
        active_edge=edge,
        forward_level=forward_level,
        resolution_ns=resolution_ns,
        steps=steps,
        rules=ruleset.results,
        not_stated=ruleset.not_stated,
        not_applicable=ruleset.not_applicable,
        rates=rates,
        notes=notes,
        axis=axis,
    )


def check_machine(
    capture: Capture,
    axes: Sequence[AxisMap],
    drives: Mapping[str | None, Drive],
    resolution: str | Fraction | None = None,
    *,
    step_types: Mapping[str | None, int] | None = None,
    forward_levels: Mapping[str | None, int] | None = None,
    invert: Mapping[str | None, Iterable[str]] | None = None,
    active_edge: ActiveEdge | None = None,
    user_table: tuple[int, ...] | None = None,
    stepgen: LinuxCNCConfig | None = None,
    latency_ns: Fraction | None = None,
    pulse_level: int = 1,
    cross_axis: bool = True,
) -> MachineReport:
    """Check every axis of ``capture`` with :func:`run_check`, from the same edge arrays.

    Args:
        capture: the capture, read once.
        axes: the axes (:func:`wavecheck.axes.parse_axes`, :func:`wavecheck.axes.axes_from_tables`;
            one unnamed axis for a single-axis run).
        drives: axis name → its drive (every axis needs one).
        resolution: T for every axis (as :func:`run_check`).
        step_types: axis → LinuxCNC step type; an axis not listed takes the type found with its
            roles (:attr:`AxisMap.step_type`), else its drive's.
        forward_levels: axis → DIR level meaning forward (default 0).
        invert: axis → roles to invert, on top of the roles found inverted with its mapping.
        active_edge, user_table, stepgen, latency_ns, pulse_level: as :func:`run_check`, for
            every axis.
        cross_axis: add the common-timer note (:func:`wavecheck.report.machine.common_timer`)
            when there are several axes.

    Raises:
        WavecheckError: an axis without a drive, or what :func:`run_check` raises.
    """
    types = step_types or {}
    forward = forward_levels or {}
    inverts = invert or {}
    reports = []
    for axis in axes:
        if axis.name not in drives:
            raise UsageError(f"axis {axis.name} has no drive")
        reports.append(
            run_check(
                capture,
                drives[axis.name],
                axis.roles,
                [*inverts.get(axis.name, ()), *axis.invert],
                types.get(axis.name, axis.step_type),
                resolution,
                forward_level=forward.get(axis.name, 0),
                active_edge=active_edge,
                user_table=user_table,
                stepgen=stepgen,
                pulse_level=pulse_level,
                latency_ns=latency_ns,
                axis=axis.name,
            )
        )
    several = bool(reports) and (len(reports) > 1 or reports[0].axis is not None)
    return MachineReport(
        capture, reports, [common_timer(reports)] if cross_axis and several else []
    )
