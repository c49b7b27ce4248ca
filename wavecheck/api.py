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
from dataclasses import dataclass, replace
from fractions import Fraction
from typing import Unpack

from wavecheck.capture.blocks import BlockSource, MemorySource
from wavecheck.capture.edges import Capture
from wavecheck.drives.datasheet import Drive
from wavecheck.engine import CheckOptions, MachineReport, Report, check_source
from wavecheck.errors import RequirementError, UsageError
from wavecheck.options import CheckKeywords, options_from_keywords
from wavecheck.steps.mapping import AxisMap, axes_from_tables
from wavecheck.units import SAMPLE_RATE, parse_frequency, parse_option

__all__ = ["Axis", "check", "check_axes", "require_met"]

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
    capture: PathOrText | Capture,
    drive: PathOrText | Drive | None = None,
    *,
    map: Mapping[str, str] | None = None,  # noqa: A002 - mirrors the CLI's --map
    samplerate: str | Fraction | None = None,
    input_format: str | None = None,
    options: CheckOptions | None = None,
    **keywords: Unpack[CheckKeywords],
) -> Report:
    """Check a capture against a drive and return the :class:`~wavecheck.report.Report`.

    Args:
        capture: a file path (read with :func:`wavecheck.capture.open.open_capture`) or a
            :class:`~wavecheck.capture.edges.Capture`.
        drive: a drive id from ``rules/``, a rule file path, or a :class:`Drive`.
        map: role → channel name or index (``{"step": "STEP (Y axis)"}``).
        samplerate: sample rate for a file without one (``"12MHz"`` or exact Hz).
        input_format: force a reader (``"sr"``, ``"vcd"``, a sigrok-cli format).
        options: the options object to start from (``wavecheck check``'s, say); ``drive``,
            ``map`` and the keywords replace what they give.
        keywords: the options of :class:`~wavecheck.options.CheckKeywords` (``invert``,
            ``step_type``, ``resolution``, ``limit``, ``ini``, ``latency``, ``require`` …;
            every spelling of each: :data:`wavecheck.options.OPTIONS`).

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
    if drive is None and (options is None or not options.drive):
        raise UsageError("check needs a drive (drive= or options=)")
    options = options_from_keywords(
        None if drive is None else {None: _drive(drive)},
        None if map is None else ((AxisMap(None, dict(map)),) if map else ()),
        keywords,
        base=options,
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
    samplerate: str | Fraction | None = None,
    input_format: str | None = None,
    options: CheckOptions | None = None,
    **keywords: Unpack[CheckKeywords],
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
        samplerate, input_format, options: as :func:`check`.
        keywords: as :func:`check`, for every axis; ``invert``, ``step_type`` and
            ``forward_level`` for every axis that does not give its own.

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
        if ref is None and options is not None and options.drive:
            continue  # the options' drive
        if ref is None:
            raise UsageError(f"axis {name} has no drive (give drive= or Axis(..., drive=...))")
        if isinstance(ref, Drive):
            drives[name] = ref
            continue
        key = os.fspath(ref)
        if key not in loaded:
            loaded[key] = _drive(ref)
        drives[name] = loaded[key]
    invert = keywords.get("invert")
    step_type: dict[str | None, int | None] = {None: keywords.get("step_type")}
    step_type.update((n, a.step_type) for n, a in given.items())
    forward: dict[str | None, int | None] = {None: keywords.get("forward_level")}
    forward.update((n, a.forward_level) for n, a in given.items())
    per_axis = ("invert", "step_type", "forward_level")
    shared = {k: v for k, v in keywords.items() if k not in per_axis}
    base = {} if options is None else dict(options.drive)
    options = options_from_keywords({**base, **drives}, tuple(maps), shared, base=options)
    inverted = [
        f"{n}.{role}"
        for n, a in given.items()
        for role in (a.invert if a.invert is not None else invert or ())
    ]
    options = replace(
        options,
        invert=(options.invert if invert is None else ()) + tuple(inverted),
        step_type={**options.step_type, **{n: t for n, t in step_type.items() if t is not None}},
        forward_level={
            **options.forward_level,
            **{n: f for n, f in forward.items() if f is not None},
        },
    )
    machine = check_source(_source(capture, samplerate, input_format), options)
    require_met(machine, options.require)
    return machine
