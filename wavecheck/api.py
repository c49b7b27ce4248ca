"""The typed Python API: ``wavecheck.check(capture, drive, ...) -> Report`` for one axis and
``wavecheck.check_axes(capture, axes, ...) -> MachineReport`` for several.

>>> report = wavecheck.check("run.sr", "gecko-g202", map={"step": "5", "dir": "6"})  # doctest: +SKIP
>>> report.verdict, report.rule("dir_hold").min_margin_ns                              # doctest: +SKIP
>>> machine = wavecheck.check_axes("run.sr", {"x": {"step": "5", "dir": "6"},          # doctest: +SKIP
...                                           "y": Axis({"step": "3", "dir": "4"}, drive="leadshine-dm542")},
...                                drive="gecko-g202")
>>> machine.verdict, machine.axis("y").rule("dir_hold").verdict                       # doctest: +SKIP
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from fractions import Fraction

from wavecheck.capture.blocks import BlockSource, MemorySource
from wavecheck.capture.edges import Capture
from wavecheck.drives.datasheet import ActiveEdge, Drive
from wavecheck.engine import (
    DEFAULT_BLOCK_EDGES,
    DEFAULT_KEEP,
    AxisMap,
    CheckOptions,
    MachineReport,
    Report,
    axes_from_tables,
    check_source,
)
from wavecheck.errors import RequirementError, UsageError
from wavecheck.linuxcnc.stepgen_config import LinuxCNCConfig
from wavecheck.units import SAMPLE_RATE, parse_frequency, parse_option
from wavecheck.verdict import require_list

__all__ = ["Axis", "build_options", "check", "check_axes", "require_met"]

PathOrText = str | os.PathLike[str]


@dataclass(frozen=True)
class Axis:
    """One axis of :func:`check_axes`: its roles, and what it does not share with the run.

    Attributes:
        map: role → channel name or index (``{"step": "5", "dir": "6"}``).
        drive: its drive (id, rule file or :class:`Drive`); None: the run's ``drive``.
        invert: roles to invert; None: the run's ``invert``.
        step_type: LinuxCNC step type; None: the run's, else the drive's.
        forward_level: DIR level meaning forward (0 or 1); None: the run's.
    """

    map: Mapping[str, str]
    drive: PathOrText | Drive | None = None
    invert: Iterable[str] | None = None
    step_type: int | None = None
    forward_level: int | None = None


def _source(
    capture: PathOrText | Capture, samplerate: str | Fraction | None, input_format: str | None
) -> BlockSource:
    """``capture`` itself as one block, or the file as a block source (``samplerate`` text needs
    its unit)."""
    if isinstance(capture, Capture):
        return MemorySource(capture)
    from wavecheck.capture.open import open_source

    rate = None
    if isinstance(samplerate, str):  # text needs its unit (docs/reference.md "Numbers and units")
        rate = parse_option(samplerate, "samplerate", "frequency", SAMPLE_RATE)
    elif samplerate is not None:
        rate = parse_frequency(samplerate, default_unit="Hz")
    return open_source(capture, samplerate=rate, input_format=input_format)


def _drive(drive: PathOrText | Drive) -> Drive:
    if isinstance(drive, Drive):
        return drive
    from wavecheck.drives.library import load_drive

    return load_drive(drive)


def _stepgen(
    ini: PathOrText | None, hal: PathOrText | Sequence[PathOrText] | None, channel: int
) -> LinuxCNCConfig | None:
    if ini is None and hal is None:
        return None
    from wavecheck.linuxcnc.stepgen_config import read_config

    hals = [hal] if isinstance(hal, (str, os.PathLike)) else list(hal or [])
    return read_config(ini, hals, channel)


def _latency_ns(latency: str | Fraction | None) -> Fraction | None:
    if latency is None:
        return None
    seconds = (
        parse_option(latency, "latency", "time") if isinstance(latency, str) else Fraction(latency)
    )
    return seconds * 10**9


def _resolution(resolution: str | Fraction | None) -> Fraction | None:
    if isinstance(resolution, str):
        return parse_option(resolution, "resolution", "time")
    return None if resolution is None else Fraction(resolution)


def build_options(
    drive: Mapping[str | None, Drive],
    axes: tuple[AxisMap, ...] = (),
    *,
    invert: Iterable[str] = (),
    step_type: Mapping[str | None, int] | None = None,
    forward_level: Mapping[str | None, int] | None = None,
    user_table: tuple[int, ...] | None = None,
    pulse_level: int | None = None,
    active_edge: ActiveEdge | None = None,
    resolution: str | Fraction | None = None,
    limit: Iterable[str] = (),
    margin: str | None = None,
    ini: PathOrText | None = None,
    hal: PathOrText | Sequence[PathOrText] | None = None,
    channel: int = 0,
    latency: str | Fraction | None = None,
    pictures: bool = False,
    keep_violations: int = DEFAULT_KEEP,
    block_edges: int = DEFAULT_BLOCK_EDGES,
    require: str | Iterable[str] = (),
) -> CheckOptions:
    """The :class:`~wavecheck.engine.options.CheckOptions` of the Python entry points'
    arguments (:func:`check`, :func:`check_axes`, :class:`wavecheck.cocotb.StepMonitor`):
    times as text with their unit or exact seconds, LinuxCNC files read."""
    return CheckOptions(
        drive=drive,
        axes=axes,
        invert=tuple(invert),
        step_type=dict(step_type or {}),
        forward_level=dict(forward_level or {}),
        user_table=None if user_table is None else tuple(user_table),
        pulse_level=pulse_level,
        active_edge=active_edge,
        resolution=_resolution(resolution),
        limits=tuple(limit),
        margin=margin,
        stepgen=_stepgen(ini, hal, channel),
        latency_ns=_latency_ns(latency),
        pictures=pictures,
        keep_violations=keep_violations,
        block_edges=block_edges,
        require=require_list(require),
    )


def require_met(checked: Report | MachineReport, require: Sequence[str]) -> None:
    """Raise :class:`~wavecheck.errors.RequirementError` (holding the report) when a rule of
    ``require`` was not decided (unchecked or indeterminate; :mod:`wavecheck.report.claims`)."""
    if not require:
        return
    from wavecheck.report.claims import requirement_line, unmet

    missing = unmet(checked, require)
    if missing:
        path = checked.capture.path
        raise RequirementError(f"{path}: {requirement_line(checked, require)}", checked, missing)


def check(
    capture: str | os.PathLike[str] | Capture,
    drive: str | os.PathLike[str] | Drive,
    *,
    map: Mapping[str, str] | None = None,  # noqa: A002 - mirrors the CLI's --map
    invert: Iterable[str] = (),
    step_type: int | None = None,
    resolution: str | Fraction | None = None,
    samplerate: str | Fraction | None = None,
    input_format: str | None = None,
    forward_level: int = 0,
    pulse_level: int | None = None,
    active_edge: ActiveEdge | None = None,
    user_table: tuple[int, ...] | None = None,
    ini: str | os.PathLike[str] | None = None,
    hal: str | os.PathLike[str] | Sequence[str | os.PathLike[str]] | None = None,
    channel: int = 0,
    latency: str | Fraction | None = None,
    limit: Iterable[str] = (),
    margin: str | None = None,
    pictures: bool = False,
    keep_violations: int = DEFAULT_KEEP,
    block_edges: int = DEFAULT_BLOCK_EDGES,
    require: str | Iterable[str] = (),
) -> Report:
    """Check a capture against a drive and return the :class:`~wavecheck.report.Report`.

    Args:
        capture: a file path (read with :func:`wavecheck.capture.open.open_capture`) or a
            :class:`~wavecheck.capture.edges.Capture`.
        drive: a drive id from ``rules/``, a rule file path, or a :class:`Drive`.
        map: role → channel name or index (``{"step": "STEP (Y axis)"}``).
        invert: roles to invert.
        step_type: LinuxCNC step type 0–15 (default: the drive's, else 0).
        resolution: T, a time (``"500ns"``) or exact seconds; default the capture's.
        samplerate: sample rate for a file without one (``"12MHz"`` or exact Hz).
        input_format: force a reader (``"sr"``, ``"vcd"``, a sigrok-cli format).
        forward_level: DIR level that means forward (0 or 1).
        pulse_level: level of the generator's step pulses at its output (1 high, 0 low;
            None: as the waveform shows it, else high).
        active_edge: override the drive's active edge.
        user_table: the state table of step type 15.
        ini: a LinuxCNC INI file (BASE_PERIOD) for the ``config`` and ``latency_safe`` rates.
        hal: LinuxCNC HAL file(s) with the stepgen settings.
        channel: the stepgen channel of the HAL files.
        latency: the worst base-thread latency ``J`` (``"11us"`` or exact seconds) for
            ``latency_safe`` (needs ``ini``/``hal``).
        limit: ``"RULE=T"`` figures replacing the drive's (``--limit``).
        margin: ``"2x"`` or ``"+500ns"`` tightening every figure (``--margin``).
        pictures: keep what :func:`wavecheck.report.plot.render_plot` and the HTML/GTKWave
            outputs draw (signal windows around the worst places, a thinned step trace).
        keep_violations: the worst violations kept per rule (the counts are exact).
        block_edges: edges gathered before a window is checked (memory follows it).
        require: rules that must be decided (``"dir_setup,dir_hold"``, ``["all"]``: every rule
            the drive gives a figure for), as ``--require``.

    Raises:
        RequirementError: a rule of ``require`` is unchecked or indeterminate (exit code 4;
            ``.report`` is the report, ``.unmet`` the rules and why).
        WavecheckError: unreadable capture or rule file, unknown channel, bad option.
    """
    if map and any("." in role for role in map):
        raise UsageError(
            f"map {dict(map)}: roles named after an axis (x.step) are several axes: "
            "use wavecheck.check_axes(capture, {'x': {'step': ...}, ...})"
        )
    options = build_options(
        {None: _drive(drive)},
        (AxisMap(None, dict(map)),) if map else (),
        invert=invert,
        step_type=None if step_type is None else {None: step_type},
        forward_level={None: forward_level},
        user_table=user_table,
        pulse_level=pulse_level,
        active_edge=active_edge,
        resolution=resolution,
        limit=limit,
        margin=margin,
        ini=ini,
        hal=hal,
        channel=channel,
        latency=latency,
        pictures=pictures,
        keep_violations=keep_violations,
        block_edges=block_edges,
        require=require,
    )
    machine = check_source(_source(capture, samplerate, input_format), options)
    if len(machine.axes) != 1 or machine.axes[0].axis is not None:
        raise UsageError(
            f"{machine.capture.path}: the waveforms show {len(machine.axes)} axes: "
            "use wavecheck.check_axes, or give map="
        )
    require_met(machine.axes[0], options.require)
    return machine.axes[0]


def check_axes(
    capture: PathOrText | Capture,
    axes: Mapping[str, Axis | Mapping[str, str]],
    drive: PathOrText | Drive | None = None,
    *,
    map: Mapping[str, str] | None = None,  # noqa: A002 - mirrors the CLI's --map
    invert: Iterable[str] = (),
    step_type: int | None = None,
    resolution: str | Fraction | None = None,
    samplerate: str | Fraction | None = None,
    input_format: str | None = None,
    forward_level: int = 0,
    pulse_level: int | None = None,
    active_edge: ActiveEdge | None = None,
    user_table: tuple[int, ...] | None = None,
    ini: PathOrText | None = None,
    hal: PathOrText | Sequence[PathOrText] | None = None,
    channel: int = 0,
    latency: str | Fraction | None = None,
    limit: Iterable[str] = (),
    margin: str | None = None,
    pictures: bool = False,
    keep_violations: int = DEFAULT_KEEP,
    block_edges: int = DEFAULT_BLOCK_EDGES,
    require: str | Iterable[str] = (),
) -> MachineReport:
    """Check every axis of a capture, read once, each against its drive (``wavecheck check
    --map x.step=5,x.dir=6 --map y.step=3,y.dir=4``); the report has one
    :class:`~wavecheck.report.Report` per axis (``.axis("x")``) and the worst verdict.

    Args:
        capture: a file path or a :class:`~wavecheck.capture.edges.Capture`.
        axes: axis name → its roles (``{"step": "5", "dir": "6"}``) or an :class:`Axis` with its
            own drive and options.
        drive: the drive of every axis that does not name its own.
        map: roles shared by every axis (only ``enable``: one ENABLE line for the machine).
        invert, step_type, forward_level: for every axis that does not give its own.
        resolution, samplerate, input_format, pulse_level, active_edge, user_table, ini, hal,
            channel, latency, limit, margin, pictures, keep_violations, block_edges, require: as
            :func:`check`, for every axis.

    Raises:
        RequirementError: a rule of ``require`` is unchecked or indeterminate on an axis.
        WavecheckError: an axis without a drive, a bad axis name or mapping (a channel in two
            axes, a shared role other than enable), and what :func:`check` raises.
    """
    given = {name: a if isinstance(a, Axis) else Axis(a) for name, a in axes.items()}
    maps = axes_from_tables({n: a.map for n, a in given.items()}, map)
    loaded: dict[str, Drive] = {}
    drives: dict[str | None, Drive] = {}
    for name, a in given.items():
        ref = a.drive if a.drive is not None else drive
        if ref is None:
            raise UsageError(f"axis {name} has no drive (give drive= or Axis(..., drive=...))")
        if isinstance(ref, Drive):
            drives[name] = ref
            continue
        key = os.fspath(ref)
        if key not in loaded:
            loaded[key] = _drive(ref)
        drives[name] = loaded[key]
    types = {n: a.step_type if a.step_type is not None else step_type for n, a in given.items()}
    options = build_options(
        drives,
        tuple(maps),
        invert=[
            f"{n}.{role}"
            for n, a in given.items()
            for role in (invert if a.invert is None else a.invert)
        ],
        step_type={n: t for n, t in types.items() if t is not None},
        forward_level={
            n: forward_level if a.forward_level is None else a.forward_level
            for n, a in given.items()
        },
        user_table=user_table,
        pulse_level=pulse_level,
        active_edge=active_edge,
        resolution=resolution,
        limit=limit,
        margin=margin,
        ini=ini,
        hal=hal,
        channel=channel,
        latency=latency,
        pictures=pictures,
        keep_violations=keep_violations,
        block_edges=block_edges,
        require=require,
    )
    machine = check_source(_source(capture, samplerate, input_format), options)
    require_met(machine, options.require)
    return machine
