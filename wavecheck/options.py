"""Every check option as its users spell it, declared once: :data:`OPTIONS`.

One option has up to five spellings: the :class:`~wavecheck.engine.CheckOptions` field it sets
(what the engine takes), the keyword of :func:`wavecheck.check`, :func:`wavecheck.check_axes`
and :class:`wavecheck.cocotb.StepMonitor` (:class:`CheckKeywords`), the flags of ``wavecheck
check``, the key of a ``wavecheck.toml`` entry (the pytest plugin) and the option of the
PulseView decoder; and where the JSON report shows what was applied. The Python keywords are
turned into the options object here (:func:`options_from_keywords`), once for every Python entry
point; the CLI's flags are read by :func:`wavecheck.cli._axis_args.check_options`. A test holds
each entry point to this table (``tests/wavecheck/test_options.py``: every option's CLI spelling
and Python keyword give the same options object and the same report).
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, replace
from fractions import Fraction
from typing import Any, TypedDict

from wavecheck.drives.datasheet import ActiveEdge, Drive
from wavecheck.engine import CheckOptions
from wavecheck.errors import UsageError
from wavecheck.steps.mapping import AxisMap
from wavecheck.units import parse_option
from wavecheck.verdict import require_list

__all__ = ["OPTIONS", "CheckKeywords", "Option", "options_from_keywords"]

PathOrText = str | os.PathLike[str]


@dataclass(frozen=True)
class Option:
    """One check option and its spellings (an empty one: that entry point has none).

    Attributes:
        name: the option's name: its Python keyword where it has one.
        field: the :class:`~wavecheck.engine.CheckOptions` field it sets; ``""``: how the
            capture is read (not an engine option).
        keyword: the keyword of :func:`wavecheck.check` (and ``check_axes``, ``StepMonitor``).
        cli: the flags of ``wavecheck check`` that set it.
        toml: the key of a ``wavecheck.toml`` ``[[capture]]`` entry (pytest plugin).
        decoder: the option of the PulseView decoder (``wavecheck-step``).
        report: where the JSON report (``--format json``) shows the value applied.
    """

    name: str
    field: str
    keyword: str = ""
    cli: tuple[str, ...] = ()
    toml: str = ""
    decoder: str = ""
    report: str = ""


#: The options of a check. ``drive`` and ``map`` are parameters of their own in the Python
#: entry points (their shape differs between one axis and several).
OPTIONS: tuple[Option, ...] = (
    Option("drive", "drive", "drive", ("--drive",), "drive", "drive", "drive.id"),
    Option("map", "axes", "map", ("--map",), "map", "", "capture.mapping"),
    Option("invert", "invert", "invert", ("--invert",), "invert", "invert", "capture.inverted"),
    Option("step_type", "step_type", "step_type", ("--type",), "type", "type", "steps.step_type"),
    Option("forward_level", "forward_level", "forward_level", ("--dir-forward",),
           "dir_forward", "dir_forward"),
    Option("user_table", "user_table", "user_table", ("--user-step-type",), "user_step_type",
           "user_table"),
    Option("pulse_level", "pulse_level", "pulse_level", ("--pulse-level",), "pulse_level",
           "pulse_level"),
    Option("active_edge", "active_edge", "active_edge", ("--active-edge",), "active_edge",
           "active_edge", "drive.active_edge"),
    Option("resolution", "resolution", "resolution", ("--resolution",), "resolution",
           "resolution", "capture.resolution_ns"),
    Option("samplerate", "", "samplerate", ("--samplerate",), "samplerate", "",
           "capture.samplerate_hz"),
    Option("input_format", "", "input_format", ("--input-format",), "input_format", "",
           "capture.format"),
    Option("limit", "limits", "limit", ("--limit",), "limit", "limit", "rules[].limit_ns"),
    Option("margin", "margin", "margin", ("--margin",), "margin", "margin", "rules[].limit_ns"),
    Option("ini", "stepgen", "ini", ("--ini",), "ini"),
    Option("hal", "stepgen", "hal", ("--hal",), "hal"),
    Option("channel", "stepgen", "channel", ("--channel",), "channel"),
    Option("base_period", "stepgen", "", ("--base-period",)),
    Option("steplen", "stepgen", "", ("--steplen",)),
    Option("stepspace", "stepgen", "", ("--stepspace",)),
    Option("dirsetup", "stepgen", "", ("--dirsetup",)),
    Option("dirhold", "stepgen", "", ("--dirhold",)),
    Option("latency", "latency_ns", "latency", ("--latency",), "latency"),
    Option("pictures", "pictures", "pictures", ("--plot", "--html", "--gtkw", "--pulseview")),
    Option("keep_violations", "keep_violations", "keep_violations", ("--max-violations",)),
    Option("block_edges", "block_edges", "block_edges", ("--block-edges", "--no-stream")),
    Option("require", "require", "require", ("--require",), "require", "", "required"),
)  # fmt: skip


class CheckKeywords(TypedDict, total=False):
    """The keywords of :func:`wavecheck.check`, :func:`wavecheck.check_axes` and
    :class:`wavecheck.cocotb.StepMonitor` that every one of them takes alike (the rows of
    :data:`OPTIONS` with a keyword, but ``drive``, ``map``, ``samplerate`` and
    ``input_format``).

    Attributes:
        invert: roles to invert.
        step_type: LinuxCNC step type 0–15 (default: the drive's, else 0).
        forward_level: DIR level that means forward (0 or 1; default 0).
        user_table: the state table of step type 15.
        pulse_level: level of the generator's step pulses at its output (1 high, 0 low;
            None: as the waveform shows it, else high).
        active_edge: override the drive's active edge.
        resolution: T, a time (``"500ns"``) or exact seconds; default the capture's.
        limit: ``"RULE=T"`` figures replacing the drive's (``--limit``).
        margin: ``"2x"`` or ``"+500ns"`` tightening every figure (``--margin``).
        ini: a LinuxCNC INI file (BASE_PERIOD) for the ``config`` and ``latency_safe`` rates.
        hal: LinuxCNC HAL file(s) with the stepgen settings.
        channel: the stepgen channel of the HAL files.
        latency: the worst base-thread latency ``J`` (``"11us"`` or exact seconds) for
            ``latency_safe`` (needs ``ini``/``hal``).
        pictures: keep what :func:`wavecheck.report.plot.render_plot` and the HTML/GTKWave
            outputs draw (signal windows around the worst places, a thinned step trace).
        keep_violations: the worst violations kept per rule (the counts are exact).
        block_edges: edges gathered before a window is checked (memory follows it).
        require: rules that must be decided (``"dir_setup,dir_hold"``, ``["all"]``: every rule
            the drive gives a figure for), as ``--require``.
    """

    invert: Iterable[str]
    step_type: int | None
    forward_level: int
    user_table: tuple[int, ...] | None
    pulse_level: int | None
    active_edge: ActiveEdge | None
    resolution: str | Fraction | None
    limit: Iterable[str]
    margin: str | None
    ini: PathOrText | None
    hal: PathOrText | Sequence[PathOrText] | None
    channel: int
    latency: str | Fraction | None
    pictures: bool
    keep_violations: int
    block_edges: int
    require: str | Iterable[str]


def _time(value: str | Fraction | None, name: str) -> Fraction | None:
    """A time keyword in exact seconds: text needs its unit (docs/reference.md)."""
    if isinstance(value, str):
        return parse_option(value, name, "time")
    return None if value is None else Fraction(value)


def _latency_ns(value: str | Fraction | None) -> Fraction | None:
    seconds = _time(value, "latency")
    return None if seconds is None else seconds * 10**9


#: keyword → its field's value of its value (the field: :data:`OPTIONS`); ``ini``, ``hal`` and
#: ``channel`` together are one LinuxCNC configuration (``stepgen``).
_CONVERT: dict[str, Callable[[Any], Any]] = {
    "invert": tuple,
    "step_type": lambda v: {} if v is None else {None: v},
    "forward_level": lambda v: {None: v},
    "user_table": lambda v: None if v is None else tuple(v),
    "pulse_level": lambda v: v,
    "active_edge": lambda v: v,
    "resolution": lambda v: _time(v, "resolution"),
    "limit": tuple,
    "margin": lambda v: v,
    "latency": _latency_ns,
    "pictures": bool,
    "keep_violations": int,
    "block_edges": int,
    "require": require_list,
}
_STEPGEN = ("ini", "hal", "channel")
_FIELD = {o.keyword: o.field for o in OPTIONS if o.keyword}


def options_from_keywords(
    drive: Mapping[str | None, Drive] | None = None,
    axes: tuple[AxisMap, ...] | None = None,
    keywords: CheckKeywords | Mapping[str, Any] | None = None,
    *,
    base: CheckOptions | None = None,
) -> CheckOptions:
    """The options object of the Python entry points' keywords: ``base`` (default: the
    defaults) with what is given replaced; times as text with their unit or exact seconds,
    LinuxCNC files read.

    Raises:
        UsageError: an unknown keyword, a bad value (:class:`CheckOptions` checks them).
    """
    given = dict(keywords or {})
    unknown = sorted(set(given) - set(_CONVERT) - set(_STEPGEN))
    if unknown:
        known = ", ".join(sorted([*_CONVERT, *_STEPGEN]))
        raise UsageError(f"unknown check option(s) {', '.join(unknown)} (known: {known})")
    fields: dict[str, Any] = {}
    if drive is not None:
        fields["drive"] = dict(drive)
    if axes is not None:
        fields["axes"] = tuple(axes)
    if given.get("ini") is not None or given.get("hal") is not None:
        from wavecheck.linuxcnc.stepgen_config import read_config

        hal = given.get("hal")
        hals = [hal] if isinstance(hal, (str, os.PathLike)) else list(hal or [])
        fields["stepgen"] = read_config(given.get("ini"), hals, given.get("channel", 0))
    for key, value in given.items():
        if key in _CONVERT:
            fields[_FIELD[key]] = _CONVERT[key](value)
    if base is None:
        return CheckOptions(**fields)
    return replace(base, **fields)
