"""pytest plugin: waveform regression tests from a ``wavecheck.toml``, and a checker fixture.

Installed with the package (entry point ``pytest11``); it only acts on files named
``wavecheck.toml`` (and on ``pyproject.toml`` files that have a ``[tool.wavecheck]`` table), so
other test runs are untouched. Each listed capture becomes a collector and each of its rules a
test item::

    wavecheck.toml::g202-run::verdict      # the capture's overall verdict
    wavecheck.toml::g202-run::step_high    # one item per rule the drive states
    wavecheck.toml::g202-run::dir_hold

The file (paths relative to it)::

    [[capture]]
    name = "g202-run"                  # default: the file's stem
    path = "captures/run.vcd"
    drive = "gecko-g202"               # a rules/ id or a TOML rule file
    map = { step = "STEP", dir = "DIR" }   # or "step=STEP,dir=3"
    invert = ["step"]
    type = 0                           # LinuxCNC step type (default: the drive's)
    resolution = "500ns"               # optional; also samplerate, input_format, dir_forward
    ini = "machine.ini"                # optional LinuxCNC files for the config and latency_safe
    hal = ["machine.hal"]              #   step rates (channel = N), with latency = "11us"
    expect = "pass"                    # pass | fail | indeterminate (default pass)
    expect_rules = { dir_hold = "fail" }
    require = ["dir_setup", "dir_hold"]  # or "all": these must be decided (not skipped)

Several axes of one capture (read once; ``wavecheck check --map x.step=…``)::

    [[capture]]
    name = "machine"
    path = "captures/machine.vcd"
    drive = "gecko-g202"               # default of every axis (as are invert, type, dir_forward,
    map = { enable = "EN" }            #   expect and expect_rules); map: roles shared (enable)
    axes.x = { step = "x_step", dir = "x_dir", expect = "fail", expect_rules = { dir_hold = "fail" } }
    axes.y = { step = "y_step", dir = "y_dir", drive = "leadshine-dm542", invert = ["step"] }

An axis table holds its roles (``step``, ``dir``, ``up``, ``down``, ``phase-A`` …; or
``map = "step=5,dir=6"``) and its own ``drive``, ``type``, ``invert``, ``dir_forward``,
``expect``, ``expect_rules`` (merged over the entry's). Items: ``machine::verdict`` (the whole
capture: the entry's ``expect``, else the worst of the axes'), and per axis
``machine::x::verdict`` and ``machine::x::dir_hold`` …

What an item expects: a rule listed in ``expect_rules`` must have that verdict. Otherwise, with
``expect = "pass"`` every rule must pass; with ``expect = "fail"`` (or indeterminate) a rule may
pass or have the expected verdict — the ``verdict`` item checks the capture as a whole. A rule
with no interval in the capture (``unchecked``) is skipped, unless ``require`` names it (or is
``"all"``: every rule the drive gives a figure for): a required rule that is unchecked or
indeterminate fails its item and the ``verdict`` item, saying why (``wavecheck check
--require``). A failure shows the worst violation.

Options: ``--wavecheck-report-dir DIR`` writes an HTML report (with plots) of every capture that
has a failing item; ``--wavecheck-max-violations N`` lists N violations in a failure (default 3).
Works with pytest-xdist (each worker checks the captures of the items it runs, once).

The ``wavecheck_check`` fixture is :func:`wavecheck.check` with relative capture paths taken
from pytest's rootdir, plus ``.expect(report, "pass")``, which fails with the same readable text.
``wavecheck_dump("sim_build")`` is the newest simulator dump a simulation of the same test run
wrote there (a cocotb test run with ``waves=True``); a ``path`` may be a glob for the same
purpose (``path = "sim_build/*.fst"``: the newest match, when the item runs).
"""

from __future__ import annotations

import os
import tomllib
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import pytest

from wavecheck.options import OPTIONS

if TYPE_CHECKING:
    from wavecheck.engine import MachineReport, Report, RuleResult

    Checked = Report | MachineReport

__all__ = [
    "AxisCollector",
    "AxisSpec",
    "CaptureSpec",
    "WavecheckChecker",
    "describe_rule",
    "load_specs",
    "pytest_addoption",
    "pytest_collect_file",
    "wavecheck_check",
    "wavecheck_dump",
]

VERDICTS = ("pass", "fail", "indeterminate")
#: Keys of a ``[[capture]]`` entry: its own, and the check options' (:data:`wavecheck.options.OPTIONS`).
_KEYS = {"name", "path", "expect", "expect_rules", "axes"} | {o.toml for o in OPTIONS if o.toml}
#: Keys of an axis table besides its roles.
_AXIS_KEYS = {"map", "drive", "type", "invert", "dir_forward", "expect", "expect_rules", "require"}


class WavecheckConfigError(Exception):
    """A ``wavecheck.toml`` entry cannot be used (reported as a collection error)."""


class WavecheckFailure(AssertionError):
    """An item's verdict is not the expected one (its text is the failure report)."""


def _expected(rule: str, expect: str, expect_rules: dict[str, str]) -> tuple[str, ...]:
    """The verdicts a rule item accepts."""
    if rule in expect_rules:
        return (expect_rules[rule],)
    if expect == "pass":
        return ("pass",)
    return ("pass", expect)


@dataclass(frozen=True)
class AxisSpec:
    """One axis of a ``[[capture]]`` entry with ``axes``: the entry's defaults applied."""

    name: str
    drive: str
    map: dict[str, str]
    invert: tuple[str, ...] = ()
    type: int | None = None
    dir_forward: str = "low"
    expect: str = "pass"
    expect_rules: dict[str, str] = field(default_factory=dict)
    require: tuple[str, ...] = ()

    def expected(self, rule: str) -> tuple[str, ...]:
        """The verdicts a rule item of this axis accepts."""
        return _expected(rule, self.expect, self.expect_rules)


@dataclass(frozen=True)
class CaptureSpec:
    """One ``[[capture]]`` entry, paths resolved against the config file's folder.

    With ``axes`` the capture is checked as a machine (one report per axis); ``drive`` is then
    only the axes' default (None when each axis names its own) and ``expect`` the whole
    capture's verdict.
    """

    name: str
    path: Path
    drive: str | None
    map: dict[str, str] = field(default_factory=dict)
    invert: tuple[str, ...] = ()
    type: int | None = None
    resolution: str | None = None
    samplerate: str | None = None
    input_format: str | None = None
    dir_forward: str = "low"
    expect: str = "pass"
    expect_rules: dict[str, str] = field(default_factory=dict)
    ini: Path | None = None
    hal: tuple[Path, ...] = ()
    channel: int = 0
    latency: str | None = None
    axes: tuple[AxisSpec, ...] = ()
    user_step_type: tuple[int, ...] | None = None
    pulse_level: str | None = None
    active_edge: str | None = None
    limit: tuple[str, ...] = ()
    margin: str | None = None
    require: tuple[str, ...] = ()

    def expected(self, rule: str) -> tuple[str, ...]:
        """The verdicts a rule item accepts."""
        return _expected(rule, self.expect, self.expect_rules)


def _map_of(raw: Any, where: str) -> dict[str, str]:
    """A ``map`` value: a table or ``"role=CH,..."`` text."""
    if isinstance(raw, str):
        from wavecheck.steps.interface import parse_map

        return parse_map([raw])
    if isinstance(raw, dict):
        return {str(k): str(v) for k, v in raw.items()}
    raise WavecheckConfigError(f"{where}: 'map' must be a table or 'role=CH,...' text")


def _expectations(entry: dict[str, Any], where: str) -> tuple[str | None, dict[str, str]]:
    """``expect`` (None when not given) and ``expect_rules`` of a table, checked."""
    expect = entry.get("expect")
    rules = entry.get("expect_rules", {})
    if (expect is not None and expect not in VERDICTS) or not isinstance(rules, dict):
        raise WavecheckConfigError(f"{where}: 'expect' must be one of {', '.join(VERDICTS)}")
    for rule, verdict in rules.items():
        if verdict not in VERDICTS:
            raise WavecheckConfigError(
                f"{where}: expect_rules.{rule} = {verdict!r} (use {', '.join(VERDICTS)})"
            )
    return expect, {str(k): str(v) for k, v in rules.items()}


def _strings(value: Any) -> tuple[str, ...]:
    return (value,) if isinstance(value, str) else tuple(str(v) for v in value)


def _require(entry: dict[str, Any], where: str, default: tuple[str, ...] = ()) -> tuple[str, ...]:
    """``require`` of a table (``"all"``, ``"dir_setup,dir_hold"`` or a list), checked."""
    from wavecheck.errors import UsageError
    from wavecheck.rules import RULE_IDS
    from wavecheck.verdict import check_require, require_list

    if "require" not in entry:
        return default
    raw = entry["require"]
    if not isinstance(raw, (str, list)):
        raise WavecheckConfigError(f"{where}: 'require' must be \"all\" or a list of rule ids")
    require = require_list(raw)
    try:
        check_require(require, RULE_IDS)
    except UsageError as err:
        raise WavecheckConfigError(f"{where}: {err}") from None
    return require


def _drive_ref(drive: str, folder: Path) -> str:
    """A rule file beside the config is found from there; an id stays as it is."""
    drive_path = folder / drive
    if drive.endswith(".toml") and drive_path.exists():
        return str(drive_path)
    return drive


def _axes(
    entry: dict[str, Any], where: str, folder: Path, defaults: AxisSpec, shared: dict[str, str]
) -> tuple[AxisSpec, ...]:
    """The ``axes`` table of an entry, ``defaults`` (the entry's own values) filling the gaps."""
    from wavecheck.errors import WavecheckError
    from wavecheck.steps.interface import role_name
    from wavecheck.steps.mapping import axes_from_tables

    raw = entry["axes"]
    if not isinstance(raw, dict) or not raw or not all(isinstance(v, dict) for v in raw.values()):
        raise WavecheckConfigError(
            f"{where}: 'axes' must be a table of axis tables "
            '(axes.x = { step = "5", dir = "6" })'
        )
    tables: dict[str, dict[str, str]] = {}
    for name, table in raw.items():
        at = f"{where}: axes.{name}"
        if name == "verdict":
            raise WavecheckConfigError(
                f"{at}: 'verdict' names the capture's own item; rename the axis"
            )
        roles = _map_of(table.get("map", {}), at)
        for key, value in table.items():
            if key in _AXIS_KEYS:
                continue
            try:
                role_name(key)
            except WavecheckError:
                known = ", ".join(sorted(_AXIS_KEYS))
                raise WavecheckConfigError(
                    f"{at}: unknown key {key} (an axis takes its roles, e.g. step, dir, enable, "
                    f"and {known})"
                ) from None
            if key in roles:
                raise WavecheckConfigError(f"{at}: {key} is given twice (as a key and in map)")
            roles[key] = str(value)
        tables[str(name)] = roles
    try:
        maps = {a.name: a.roles for a in axes_from_tables(tables, shared, f"{where}: axes")}
    except WavecheckError as err:
        raise WavecheckConfigError(str(err)) from None
    out = []
    for name, table in raw.items():
        at = f"{where}: axes.{name}"
        expect, rules = _expectations(table, at)
        drive = table.get("drive", defaults.drive)
        if not isinstance(drive, str) or not drive:
            raise WavecheckConfigError(f"{at}: no drive (give drive here or for the capture)")
        out.append(
            AxisSpec(
                name=str(name),
                drive=_drive_ref(drive, folder),
                map=dict(maps[str(name)]),
                invert=_strings(table["invert"]) if "invert" in table else defaults.invert,
                type=table.get("type", defaults.type),
                dir_forward=str(table.get("dir_forward", defaults.dir_forward)),
                expect=expect or defaults.expect,
                expect_rules={**defaults.expect_rules, **rules},
                require=_require(table, at, defaults.require),
            )
        )
    return tuple(out)


def _spec(entry: Any, where: str, folder: Path) -> CaptureSpec:
    if not isinstance(entry, dict):
        raise WavecheckConfigError(f"{where}: a [[capture]] entry must be a table")
    unknown = sorted(set(entry) - _KEYS)
    if unknown:
        raise WavecheckConfigError(
            f"{where}: unknown key(s) {', '.join(unknown)} (known: {', '.join(sorted(_KEYS))})"
        )
    several = "axes" in entry
    for key in ("path",) if several else ("path", "drive"):
        if not isinstance(entry.get(key), str):
            raise WavecheckConfigError(f"{where}: {key!r} is required (a string)")
    if several and not isinstance(entry.get("drive", ""), str):
        raise WavecheckConfigError(f"{where}: 'drive' must be a string")
    mapping = _map_of(entry.get("map", {}), where)
    expect, rules = _expectations(entry, where)
    invert = _strings(entry.get("invert", []))
    drive = entry.get("drive")
    dir_forward = str(entry.get("dir_forward", "low"))
    require = _require(entry, where)
    axes: tuple[AxisSpec, ...] = ()
    if several:
        from wavecheck.verdict import overall_verdict

        defaults = AxisSpec(
            "",
            drive or "",
            {},
            invert,
            entry.get("type"),
            dir_forward,
            expect or "pass",
            rules,
            require,
        )
        axes = _axes(entry, where, folder, defaults, mapping)
        if expect is None:  # the whole capture: the worst of its axes
            expect = overall_verdict(a.expect for a in axes)
    path = Path(entry["path"])
    hal = entry.get("hal", [])
    hal = [hal] if isinstance(hal, str) else hal
    ini = entry.get("ini")
    return CaptureSpec(
        name=str(entry.get("name") or path.stem),
        path=path if path.is_absolute() else folder / path,
        drive=None if drive is None else _drive_ref(drive, folder),
        map=mapping,
        invert=invert,
        type=entry.get("type"),
        resolution=entry.get("resolution"),
        samplerate=entry.get("samplerate"),
        input_format=entry.get("input_format"),
        dir_forward=dir_forward,
        expect=expect or "pass",
        expect_rules=rules,
        ini=None if ini is None else folder / str(ini),
        hal=tuple(folder / str(h) for h in hal),
        channel=int(entry.get("channel", 0)),
        latency=None if entry.get("latency") is None else str(entry["latency"]),
        axes=axes,
        user_step_type=_table_of(entry.get("user_step_type"), where),
        pulse_level=_choice(entry, "pulse_level", ("high", "low"), where),
        active_edge=_choice(entry, "active_edge", ("rising", "falling", "both"), where),
        limit=_limits(entry.get("limit", []), where),
        margin=None if entry.get("margin") is None else str(entry["margin"]),
        require=require,
    )


def _table_of(raw: Any, where: str) -> tuple[int, ...] | None:
    """``user_step_type``: a list of state values or ``"1,3,2,0"`` text (None when absent)."""
    if raw is None:
        return None
    items = raw.split(",") if isinstance(raw, str) else raw
    try:
        return tuple(int(str(v).strip(), 0) for v in items)
    except (TypeError, ValueError):
        raise WavecheckConfigError(
            f"{where}: 'user_step_type' must be a list of state values (e.g. [1, 3, 2, 0])"
        ) from None


def _choice(entry: Any, key: str, allowed: tuple[str, ...], where: str) -> str | None:
    raw = entry.get(key)
    if raw is None:
        return None
    if raw not in allowed:
        raise WavecheckConfigError(f"{where}: {key!r} must be one of {', '.join(allowed)}")
    return str(raw)


def _limits(raw: Any, where: str) -> tuple[str, ...]:
    """``limit``: a table ``{ step_high = "5us" }`` or a list of ``"RULE=T"`` texts."""
    if isinstance(raw, dict):
        return tuple(f"{k}={v}" for k, v in raw.items())
    if isinstance(raw, list) and all(isinstance(v, str) for v in raw):
        return tuple(raw)
    raise WavecheckConfigError(f"{where}: 'limit' must be a table {{ rule = \"T\" }} or a list")


def load_specs(path: Path) -> list[CaptureSpec]:
    """The captures listed in a ``wavecheck.toml`` (``[[capture]]``) or a ``pyproject.toml``
    (``[[tool.wavecheck.capture]]``).

    Raises:
        WavecheckConfigError: malformed TOML, a missing key, an unknown key or verdict, a
            repeated name.
    """
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except (OSError, tomllib.TOMLDecodeError) as err:
        raise WavecheckConfigError(f"{path}: {err}") from None
    if path.name == "pyproject.toml":
        data = data.get("tool", {}).get("wavecheck", {})
    entries = data.get("capture", [])
    if not isinstance(entries, list):
        raise WavecheckConfigError(f"{path}: 'capture' must be an array of tables ([[capture]])")
    specs = [_spec(e, f"{path}: capture {i + 1}", path.parent) for i, e in enumerate(entries)]
    seen: set[str] = set()
    for s in specs:
        if s.name in seen:
            raise WavecheckConfigError(f"{path}: two captures are named {s.name!r} (give 'name')")
        seen.add(s.name)
    return specs


# -- running and describing ----------------------------------------------------------------------
_REPORTS: dict[tuple[str, str], Any] = {}


def newest_match(path: Path) -> Path:
    """``path`` itself, or for a glob (``sim_build/*.fst``) the newest file it matches.

    Raises:
        WavecheckFailure: a glob matches nothing (the simulation that writes it has not run).
    """
    if not any(c in str(path) for c in "*?["):
        return path
    hits = [
        p for p in Path(path.anchor or ".").glob(str(path.relative_to(path.anchor))) if p.is_file()
    ]
    if not hits:
        raise WavecheckFailure(f"no file matches {path} (has the simulation that writes it run?)")
    return max(hits, key=lambda p: p.stat().st_mtime_ns)


def _run(spec: CaptureSpec) -> Checked:
    from dataclasses import replace

    from wavecheck.api import Axis, check, check_axes

    spec = replace(spec, path=newest_match(spec.path))
    if spec.axes:  # every axis from one reading of the capture
        return check_axes(
            spec.path,
            {
                a.name: Axis(
                    a.map,
                    drive=a.drive,
                    invert=a.invert,
                    step_type=a.type,
                    forward_level=1 if a.dir_forward == "high" else 0,
                )
                for a in spec.axes
            },
            **_common(spec),
        )
    assert spec.drive is not None  # load_specs requires it without axes
    return check(
        spec.path,
        spec.drive,
        map=spec.map,
        invert=spec.invert,
        step_type=spec.type,
        forward_level=1 if spec.dir_forward == "high" else 0,
        **_common(spec),
    )


def _common(spec: CaptureSpec) -> dict[str, Any]:
    """The check arguments every axis of ``spec`` shares."""
    return {
        "resolution": spec.resolution,
        "samplerate": spec.samplerate,
        "input_format": spec.input_format,
        "ini": spec.ini,
        "hal": spec.hal or None,
        "channel": spec.channel,
        "latency": spec.latency,
        "user_table": spec.user_step_type,
        "pulse_level": None if spec.pulse_level is None else int(spec.pulse_level == "high"),
        "active_edge": spec.active_edge,
        "limit": spec.limit,
        "margin": spec.margin,
    }


def _report(config_path: Path, spec: CaptureSpec) -> Checked:
    """The capture's report (one per axis with ``axes``), checked once per process (an error is
    kept and re-raised)."""
    from wavecheck.errors import WavecheckError

    key = (str(config_path), spec.name)
    if key not in _REPORTS:
        try:
            _REPORTS[key] = _run(spec)
        except WavecheckError as err:
            _REPORTS[key] = err
    value = _REPORTS[key]
    if isinstance(value, Exception):
        raise WavecheckFailure(f"{spec.name}: cannot check {spec.path}: {value}")
    return value  # type: ignore[no-any-return]


def _ns(v: Any) -> str:
    from wavecheck.units import format_ns

    return format_ns(v, signed=True)


def describe_rule(report: Report, r: RuleResult, max_violations: int = 3) -> str:
    """A readable account of one rule: verdict, counts, limit, margin and the worst violations."""
    limit = "-" if r.limit_ns is None else _ns(r.limit_ns).lstrip("+")
    lines = [
        f"{r.rule}: {r.verdict.upper()} — {r.violations} violation(s), {r.indeterminate} "
        f"indeterminate in {r.checked} interval(s); limit {limit}, min margin {_ns(r.min_margin_ns)}"
    ]
    for v in r.worst_violations(max_violations):
        if v.margin_ns is None:
            lines.append(f"  at {float(v.time_s):.9f} s: {v.detail}")
        else:
            lines.append(
                f"  at {float(v.time_s):.9f} s: measured {_ns(v.measured_ns).lstrip('+')}, "
                f"limit {_ns(v.limit_ns).lstrip('+')}, margin {_ns(v.margin_ns)}"
            )
    if r.violations > max_violations:
        lines.append(f"  … and {r.violations - max_violations} more")
    if r.verdict == "indeterminate" and r.decide_samplerate_hz is not None:
        from wavecheck.units import format_frequency

        lines.append(
            f"  sampling faster than {format_frequency(r.decide_samplerate_hz)} would decide it"
        )
    axis = "" if report.axis is None else f" axis {report.axis}"
    lines.append(
        f"  capture {report.capture.path}{axis} vs drive {report.drive.id} "
        f"(step type {report.step_type.number}, {report.steps.count} steps)"
    )
    return "\n".join(lines)


def _describe_report(report: Report, max_violations: int) -> str:
    from wavecheck.report.text import rate_lines

    lines = [f"verdict {report.verdict.upper()} ({report.total_violations} violation(s))"]
    lines += [describe_rule(report, r, max_violations) for r in report.rules if r.verdict != "pass"]
    lines += rate_lines(report)
    return "\n".join(lines)


def _describe(checked: Checked, max_violations: int) -> str:
    """A report's account, or a machine's: its verdict, then each axis that does not pass."""
    from wavecheck.engine import MachineReport

    if not isinstance(checked, MachineReport):
        return _describe_report(checked, max_violations)
    lines = [f"verdict {checked.verdict.upper()} ({checked.total_violations} violation(s))"]
    for r in checked.axes:
        if r.verdict != "pass":
            lines.append(f"axis {r.axis}: {_describe_report(r, max_violations)}")
    return "\n".join(lines)


# -- collection ---------------------------------------------------------------------------------
def pytest_sessionstart(session: pytest.Session) -> None:
    """Each session reads its captures afresh (a long-lived process may run several)."""
    _REPORTS.clear()


def pytest_addoption(parser: pytest.Parser) -> None:
    """Add the ``--wavecheck-*`` options."""
    group = parser.getgroup("wavecheck", "waveform checks from wavecheck.toml")
    group.addoption(
        "--wavecheck-report-dir",
        metavar="DIR",
        default=None,
        help="write an HTML report (with plots) of each capture with a failing item to DIR",
    )
    group.addoption(
        "--wavecheck-max-violations",
        type=int,
        default=3,
        metavar="N",
        help="violations listed in a failure (default 3)",
    )


def pytest_collect_file(file_path: Path, parent: pytest.Collector) -> pytest.Collector | None:
    """Collect ``wavecheck.toml``, and ``pyproject.toml`` files with a ``[tool.wavecheck]``."""
    if file_path.name == "wavecheck.toml":
        return WavecheckFile.from_parent(parent, path=file_path)
    if file_path.name == "pyproject.toml":
        try:
            text = file_path.read_text(encoding="utf-8")
        except OSError:
            return None
        if "[tool.wavecheck" in text:
            return WavecheckFile.from_parent(parent, path=file_path)
    return None


class WavecheckFile(pytest.File):
    """A config file: one :class:`CaptureCollector` per capture."""

    def collect(self) -> Iterator[pytest.Collector]:
        for spec in load_specs(self.path):
            yield CaptureCollector.from_parent(self, name=spec.name, spec=spec)

    def repr_failure(self, excinfo: pytest.ExceptionInfo[BaseException]) -> Any:  # type: ignore[override]
        if isinstance(excinfo.value, WavecheckConfigError):
            return str(excinfo.value)
        return super().repr_failure(excinfo)


class CaptureCollector(pytest.Collector):
    """One capture: a ``verdict`` item and one item per rule the drive states; with ``axes`` an
    :class:`AxisCollector` per axis after the capture's ``verdict``."""

    def __init__(self, *, spec: CaptureSpec, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self.spec = spec

    def collect(self) -> Iterator[pytest.Item | pytest.Collector]:
        yield RuleItem.from_parent(self, name="verdict", rule=None, spec=self.spec, axis=None)
        if self.spec.axes:
            for axis in self.spec.axes:
                yield AxisCollector.from_parent(self, name=axis.name, spec=self.spec, axis=axis)
            return
        assert self.spec.drive is not None  # load_specs requires it without axes
        for rule in _rules_of(self.spec.drive, self.spec.type):
            yield RuleItem.from_parent(self, name=rule, rule=rule, spec=self.spec, axis=None)

    def repr_failure(self, excinfo: pytest.ExceptionInfo[BaseException]) -> Any:  # type: ignore[override]
        from wavecheck.errors import WavecheckError

        if isinstance(excinfo.value, WavecheckError):
            return f"{self.spec.name}: {excinfo.value}"
        return super().repr_failure(excinfo)


class AxisCollector(CaptureCollector):
    """One axis of a capture: its ``verdict`` item and one item per rule its drive states."""

    def __init__(self, *, axis: AxisSpec, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self.axis = axis

    def collect(self) -> Iterator[pytest.Item | pytest.Collector]:
        yield RuleItem.from_parent(self, name="verdict", rule=None, spec=self.spec, axis=self.axis)
        for rule in _rules_of(self.axis.drive, self.axis.type):
            yield RuleItem.from_parent(self, name=rule, rule=rule, spec=self.spec, axis=self.axis)


def _rules_of(drive_ref: str, type_number: int | None) -> list[str]:
    """The rules a check against ``drive_ref`` will evaluate, known without reading the capture."""
    from wavecheck.drives.library import load_drive
    from wavecheck.engine.planning import default_step_type, planned_rules
    from wavecheck.steptypes import step_type

    drive = load_drive(drive_ref)
    st = step_type(default_step_type(drive) if type_number is None else type_number)
    return [r.id for r in planned_rules(drive, st)[0]]


class RuleItem(pytest.Item):
    """One rule of one capture or axis (or, with ``rule=None``, its overall verdict)."""

    def __init__(
        self, *, rule: str | None, spec: CaptureSpec, axis: AxisSpec | None, **kwargs: Any
    ) -> None:
        super().__init__(**kwargs)
        self.rule = rule
        self.spec = spec
        self.axis = axis
        self.config_path = self.path

    @property
    def _where(self) -> str:
        return self.spec.name if self.axis is None else f"{self.spec.name}::{self.axis.name}"

    def runtest(self) -> None:
        from wavecheck.engine import MachineReport

        checked = _report(self.config_path, self.spec)
        report: Checked = checked
        if self.axis is not None and isinstance(checked, MachineReport):
            report = checked.axis(self.axis.name)
        if self.rule is None and not isinstance(report, MachineReport):
            self.user_properties += _rate_properties(report)
        max_v = int(self.config.getoption("wavecheck_max_violations"))
        try:
            self._judge(report, max_v)
        except WavecheckFailure:
            self._write_html(checked)
            raise

    def _unmet(self, report: Checked) -> str:
        """The required rules (``require``) ``report`` did not decide, as one line ("": none)."""
        from wavecheck.engine import MachineReport
        from wavecheck.report.claims import requirement_line

        if isinstance(report, MachineReport):  # the capture's verdict: each axis's own require
            lines = [
                (a.name, requirement_line(report.axis(a.name), a.require)) for a in self.spec.axes
            ]
            return "; ".join(f"axis {name}: {line}" for name, line in lines if line)
        spec = self.spec if self.axis is None else self.axis
        return requirement_line(report, spec.require)

    def _judge(self, report: Checked, max_v: int) -> None:
        expect = self.spec.expect if self.axis is None else self.axis.expect
        if self.rule is None:
            if report.verdict != expect:
                raise WavecheckFailure(
                    f"{self._where}: expected {expect.upper()}, got {_describe(report, max_v)}"
                )
            missing = self._unmet(report)
            if missing:
                raise WavecheckFailure(f"{self._where}: {missing}")
            return
        from wavecheck.engine import MachineReport
        from wavecheck.report.claims import unmet

        assert not isinstance(report, MachineReport)  # rule items belong to one report
        r = report.rule(self.rule)
        if r is None:
            raise WavecheckFailure(f"{self._where}: rule {self.rule} was not evaluated")
        spec = self.spec if self.axis is None else self.axis
        for u in unmet(report, spec.require):
            if u.rule == self.rule:
                raise WavecheckFailure(
                    f"{self._where}: {self.rule} is required but {u.said}: {u.why}"
                )
        if r.verdict == "unchecked":
            from wavecheck.report.claims import rule_statuses

            why = next(s.why for s in rule_statuses(report) if s.rule == self.rule)
            pytest.skip(f"{self.rule} not checked in {self.spec.path.name}: {why}")
        expected = (self.spec if self.axis is None else self.axis).expected(self.rule)
        if r.verdict not in expected:
            want = " or ".join(v.upper() for v in expected)
            raise WavecheckFailure(
                f"{self._where}: expected {want}, got {describe_rule(report, r, max_v)}"
            )

    def _write_html(self, checked: Checked) -> None:
        folder = self.config.getoption("wavecheck_report_dir")
        if not folder:
            return
        from wavecheck.engine import MachineReport
        from wavecheck.report.html import write_html

        os.makedirs(folder, exist_ok=True)
        target = Path(folder) / f"{self.spec.name}.html"
        reports = checked.axes if isinstance(checked, MachineReport) else [checked]
        if not target.exists():
            write_html(reports, target, title=f"wavecheck: {self.spec.name}")

    def repr_failure(self, excinfo: pytest.ExceptionInfo[BaseException]) -> Any:  # type: ignore[override]
        if isinstance(excinfo.value, WavecheckFailure):
            return str(excinfo.value)
        return super().repr_failure(excinfo)

    def reportinfo(self) -> tuple[Path, int | None, str]:
        return self.path, None, f"{self._where}::{self.name}"


def _rate_properties(report: Report) -> list[tuple[str, object]]:
    named = report.rates.named().items()
    return [(f"max_step_rate_hz.{k}", float(v)) for k, v in named if v is not None]


# -- fixture ------------------------------------------------------------------------------------
class WavecheckChecker:
    """:func:`wavecheck.check` for tests, relative capture paths taken from ``root``."""

    def __init__(self, root: Path, max_violations: int = 3) -> None:
        self.root = root
        self.max_violations = max_violations

    def _path(self, capture: str | os.PathLike[str]) -> Path:
        path = Path(capture)
        return path if path.is_absolute() else self.root / path

    def __call__(self, capture: str | os.PathLike[str], drive: str, **kwargs: Any) -> Report:
        """Check ``capture`` against ``drive`` (keyword arguments as :func:`wavecheck.check`)."""
        from wavecheck.api import check

        return check(self._path(capture), drive, **kwargs)

    def axes(
        self, capture: str | os.PathLike[str], axes: Any, drive: str | None = None, **kwargs: Any
    ) -> MachineReport:
        """Check every axis of ``capture`` (arguments as :func:`wavecheck.check_axes`)."""
        from wavecheck.api import check_axes

        return check_axes(self._path(capture), axes, drive, **kwargs)

    def expect(self, report: Checked, verdict: str = "pass") -> None:
        """Fail the test, showing the rules (of each axis) that are not pass, unless the verdict
        is ``verdict``."""
        __tracebackhide__ = True
        if report.verdict != verdict:
            pytest.fail(
                f"expected {verdict.upper()}, got {_describe(report, self.max_violations)}",
                pytrace=False,
            )


def _dump(root: Path) -> Callable[[str | os.PathLike[str]], Path]:
    def find(where: str | os.PathLike[str] = "sim_build") -> Path:
        """The newest simulator dump (``.fst``, ``.vcd``, ``.ghw``) in the folder ``where``, or
        the newest match of a glob (``"sim_build/*.fst"``), relative to pytest's rootdir; fails
        the test readably when there is none."""
        __tracebackhide__ = True
        path = Path(where) if Path(where).is_absolute() else root / where
        if path.is_dir():
            found = [p for p in path.iterdir() if p.suffix in (".fst", ".vcd", ".ghw")]
            if not found:
                pytest.fail(f"no simulator dump (.fst, .vcd, .ghw) in {path}: run the "
                            "simulation with waves=True (cocotb's runner) first", pytrace=False)  # fmt: skip
            return max(found, key=lambda p: p.stat().st_mtime_ns)
        try:
            return newest_match(path)
        except WavecheckFailure as err:
            pytest.fail(str(err), pytrace=False)

    return find


@pytest.fixture
def wavecheck_dump(request: pytest.FixtureRequest) -> Callable[[str | os.PathLike[str]], Path]:
    """``wavecheck_dump("sim_build")`` → the dump a simulation of this test run wrote there (the
    newest ``.fst``/``.vcd``/``.ghw``; cocotb's runner with ``waves=True`` writes
    ``<build_dir>/<toplevel>.fst``), to check with ``wavecheck_check``. A ``wavecheck.toml``
    ``path`` may be such a glob too (``"sim_build/*.fst"``): the newest match when the item runs."""
    return _dump(Path(request.config.rootpath))


@pytest.fixture
def wavecheck_check(request: pytest.FixtureRequest) -> WavecheckChecker:
    """A :class:`WavecheckChecker`: ``report = wavecheck_check("run.vcd", "gecko-g202")``."""
    return WavecheckChecker(
        Path(request.config.rootpath), int(request.config.getoption("wavecheck_max_violations"))
    )
