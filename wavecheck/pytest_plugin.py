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

What an item expects: a rule listed in ``expect_rules`` must have that verdict. Otherwise, with
``expect = "pass"`` every rule must pass; with ``expect = "fail"`` (or indeterminate) a rule may
pass or have the expected verdict — the ``verdict`` item checks the capture as a whole. A rule
with no interval in the capture (``unchecked``) is skipped. A failure shows the worst
violation.

Options: ``--wavecheck-report-dir DIR`` writes an HTML report (with plots) of every capture that
has a failing item; ``--wavecheck-max-violations N`` lists N violations in a failure (default 3).
Works with pytest-xdist (each worker checks the captures of the items it runs, once).

The ``wavecheck_check`` fixture is :func:`wavecheck.check` with relative capture paths taken
from pytest's rootdir, plus ``.expect(report, "pass")``, which fails with the same readable text.
"""

from __future__ import annotations

import os
import tomllib
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import pytest

if TYPE_CHECKING:
    from wavecheck.checks.result import RuleResult
    from wavecheck.report.model import Report

__all__ = [
    "CaptureSpec",
    "WavecheckChecker",
    "describe_rule",
    "load_specs",
    "pytest_addoption",
    "pytest_collect_file",
    "wavecheck_check",
]

VERDICTS = ("pass", "fail", "indeterminate")
_KEYS = {
    "name",
    "path",
    "drive",
    "map",
    "invert",
    "type",
    "resolution",
    "samplerate",
    "input_format",
    "dir_forward",
    "expect",
    "expect_rules",
    "ini",
    "hal",
    "channel",
    "latency",
}


class WavecheckConfigError(Exception):
    """A ``wavecheck.toml`` entry cannot be used (reported as a collection error)."""


class WavecheckFailure(AssertionError):
    """An item's verdict is not the expected one (its text is the failure report)."""


@dataclass(frozen=True)
class CaptureSpec:
    """One ``[[capture]]`` entry, paths resolved against the config file's folder."""

    name: str
    path: Path
    drive: str
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

    def expected(self, rule: str) -> tuple[str, ...]:
        """The verdicts a rule item accepts."""
        if rule in self.expect_rules:
            return (self.expect_rules[rule],)
        if self.expect == "pass":
            return ("pass",)
        return ("pass", self.expect)


def _spec(entry: Any, where: str, folder: Path) -> CaptureSpec:
    if not isinstance(entry, dict):
        raise WavecheckConfigError(f"{where}: a [[capture]] entry must be a table")
    unknown = sorted(set(entry) - _KEYS)
    if unknown:
        raise WavecheckConfigError(
            f"{where}: unknown key(s) {', '.join(unknown)} (known: {', '.join(sorted(_KEYS))})"
        )
    for key in ("path", "drive"):
        if not isinstance(entry.get(key), str):
            raise WavecheckConfigError(f"{where}: {key!r} is required (a string)")
    raw_map = entry.get("map", {})
    if isinstance(raw_map, str):
        from wavecheck.interface import parse_map

        mapping = parse_map([raw_map])
    elif isinstance(raw_map, dict):
        mapping = {str(k): str(v) for k, v in raw_map.items()}
    else:
        raise WavecheckConfigError(f"{where}: 'map' must be a table or 'role=CH,...' text")
    expect = entry.get("expect", "pass")
    rules = entry.get("expect_rules", {})
    if expect not in VERDICTS or not isinstance(rules, dict):
        raise WavecheckConfigError(f"{where}: 'expect' must be one of {', '.join(VERDICTS)}")
    for rule, verdict in rules.items():
        if verdict not in VERDICTS:
            raise WavecheckConfigError(
                f"{where}: expect_rules.{rule} = {verdict!r} (use {', '.join(VERDICTS)})"
            )
    invert = entry.get("invert", [])
    if isinstance(invert, str):
        invert = [invert]
    drive = entry["drive"]
    drive_path = folder / drive
    if drive.endswith(".toml") and drive_path.exists():
        drive = str(drive_path)
    path = Path(entry["path"])
    hal = entry.get("hal", [])
    hal = [hal] if isinstance(hal, str) else hal
    ini = entry.get("ini")
    return CaptureSpec(
        name=str(entry.get("name") or path.stem),
        path=path if path.is_absolute() else folder / path,
        drive=drive,
        map=mapping,
        invert=tuple(invert),
        type=entry.get("type"),
        resolution=entry.get("resolution"),
        samplerate=entry.get("samplerate"),
        input_format=entry.get("input_format"),
        dir_forward=str(entry.get("dir_forward", "low")),
        expect=expect,
        expect_rules={str(k): str(v) for k, v in rules.items()},
        ini=None if ini is None else folder / str(ini),
        hal=tuple(folder / str(h) for h in hal),
        channel=int(entry.get("channel", 0)),
        latency=None if entry.get("latency") is None else str(entry["latency"]),
    )


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


def _run(spec: CaptureSpec) -> Report:
    from wavecheck.api import check

    return check(
        spec.path,
        spec.drive,
        map=spec.map,
        invert=spec.invert,
        step_type=spec.type,
        resolution=spec.resolution,
        samplerate=spec.samplerate,
        input_format=spec.input_format,
        forward_level=1 if spec.dir_forward == "high" else 0,
        ini=spec.ini,
        hal=spec.hal or None,
        channel=spec.channel,
        latency=spec.latency,
    )


def _report(config_path: Path, spec: CaptureSpec) -> Report:
    """The capture's report, checked once per process (an error is kept and re-raised)."""
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

        lines.append(f"  sampling faster than {format_frequency(r.decide_samplerate_hz)} would decide it")
    lines.append(
        f"  capture {report.capture.path} vs drive {report.drive.id} "
        f"(step type {report.step_type.number}, {report.steps.count} steps)"
    )
    return "\n".join(lines)


def _describe_report(report: Report, max_violations: int) -> str:
    from wavecheck.report.text import rate_lines

    lines = [f"verdict {report.verdict.upper()} ({report.total_violations} violation(s))"]
    lines += [describe_rule(report, r, max_violations) for r in report.rules if r.verdict != "pass"]
    lines += rate_lines(report)
    return "\n".join(lines)


# -- collection ---------------------------------------------------------------------------------
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
    """One capture: a ``verdict`` item and one item per rule the drive states."""

    def __init__(self, *, spec: CaptureSpec, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self.spec = spec

    def collect(self) -> Iterator[pytest.Item]:
        yield RuleItem.from_parent(self, name="verdict", rule=None)
        for rule in _rules_of(self.spec):
            yield RuleItem.from_parent(self, name=rule, rule=rule)

    def repr_failure(self, excinfo: pytest.ExceptionInfo[BaseException]) -> Any:  # type: ignore[override]
        from wavecheck.errors import WavecheckError

        if isinstance(excinfo.value, WavecheckError):
            return f"{self.spec.name}: {excinfo.value}"
        return super().repr_failure(excinfo)


def _rules_of(spec: CaptureSpec) -> list[str]:
    """The rules a check of ``spec`` will evaluate, known without reading the capture."""
    from wavecheck.checks.compile import planned_rules
    from wavecheck.drives.library import load_drive
    from wavecheck.engine import default_step_type
    from wavecheck.linuxcnc.steptypes import step_type

    drive = load_drive(spec.drive)
    st = step_type(default_step_type(drive) if spec.type is None else spec.type)
    return [r.id for r in planned_rules(drive, st)[0]]


class RuleItem(pytest.Item):
    """One rule of one capture (or, with ``rule=None``, the capture's overall verdict)."""

    def __init__(self, *, rule: str | None, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self.rule = rule
        parent = self.parent
        assert isinstance(parent, CaptureCollector)
        self.spec = parent.spec
        self.config_path = parent.path

    def runtest(self) -> None:
        report = _report(self.config_path, self.spec)
        if self.rule is None:
            self.user_properties += _rate_properties(report)
        max_v = int(self.config.getoption("wavecheck_max_violations"))
        try:
            self._judge(report, max_v)
        except WavecheckFailure:
            self._write_html(report)
            raise

    def _judge(self, report: Report, max_v: int) -> None:
        if self.rule is None:
            if report.verdict != self.spec.expect:
                raise WavecheckFailure(
                    f"{self.spec.name}: expected {self.spec.expect.upper()}, got "
                    f"{_describe_report(report, max_v)}"
                )
            return
        r = report.rule(self.rule)
        if r is None:
            raise WavecheckFailure(f"{self.spec.name}: rule {self.rule} was not evaluated")
        if r.verdict == "unchecked":
            pytest.skip(f"no {self.rule} interval in {self.spec.path.name}")
        expected = self.spec.expected(self.rule)
        if r.verdict not in expected:
            want = " or ".join(v.upper() for v in expected)
            raise WavecheckFailure(
                f"{self.spec.name}: expected {want}, got {describe_rule(report, r, max_v)}"
            )

    def _write_html(self, report: Report) -> None:
        folder = self.config.getoption("wavecheck_report_dir")
        if not folder:
            return
        from wavecheck.report.html import write_html

        os.makedirs(folder, exist_ok=True)
        target = Path(folder) / f"{self.spec.name}.html"
        if not target.exists():
            write_html([report], target, title=f"wavecheck: {self.spec.name}")

    def repr_failure(self, excinfo: pytest.ExceptionInfo[BaseException]) -> Any:  # type: ignore[override]
        if isinstance(excinfo.value, WavecheckFailure):
            return str(excinfo.value)
        return super().repr_failure(excinfo)

    def reportinfo(self) -> tuple[Path, int | None, str]:
        return self.path, None, f"{self.spec.name}::{self.name}"


def _rate_properties(report: Report) -> list[tuple[str, object]]:
    named = report.rates.named().items()
    return [(f"max_step_rate_hz.{k}", float(v)) for k, v in named if v is not None]


# -- fixture ------------------------------------------------------------------------------------
class WavecheckChecker:
    """:func:`wavecheck.check` for tests, relative capture paths taken from ``root``."""

    def __init__(self, root: Path, max_violations: int = 3) -> None:
        self.root = root
        self.max_violations = max_violations

    def __call__(self, capture: str | os.PathLike[str], drive: str, **kwargs: Any) -> Report:
        """Check ``capture`` against ``drive`` (keyword arguments as :func:`wavecheck.check`)."""
        from wavecheck.api import check

        path = Path(capture)
        if not path.is_absolute():
            path = self.root / path
        return check(path, drive, **kwargs)

    def expect(self, report: Report, verdict: str = "pass") -> None:
        """Fail the test, showing the rules that are not pass, unless the verdict is ``verdict``."""
        __tracebackhide__ = True
        if report.verdict != verdict:
            pytest.fail(
                f"expected {verdict.upper()}, got {_describe_report(report, self.max_violations)}",
                pytrace=False,
            )


@pytest.fixture
def wavecheck_check(request: pytest.FixtureRequest) -> WavecheckChecker:
    """A :class:`WavecheckChecker`: ``report = wavecheck_check("run.vcd", "gecko-g202")``."""
    return WavecheckChecker(
        Path(request.config.rootpath), int(request.config.getoption("wavecheck_max_violations"))
    )
