"""The pytest plugin with several axes in one [[capture]] entry (issue 13): items per axis, the
capture read once, the entry's keys as the axes' defaults, every single-axis entry unchanged."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from wavecheck.pytest_plugin import WavecheckConfigError, load_specs

pytest_plugins = ["pytester"]

REPO = Path(__file__).resolve().parents[2]
TWO_AXIS = REPO / "captures" / "examples" / "two-axis.vcd"
G202_RULES = ["step_high", "step_low", "step_period", "dir_setup", "dir_hold"]

# tools/examples.py: axis x is the 20 us story trace (dir_hold 9 us < 20 us), y the 16 us plan
CONFIG = """\
[[capture]]
name = "machine"
path = "two-axis.vcd"
drive = "gecko-g202"
axes.x = { step = "x_step", dir = "x_dir", expect = "fail", expect_rules = { dir_hold = "fail" } }
axes.y = { map = "step=y_step,dir=y_dir" }

[[capture]]
name = "hoped"
path = "two-axis.vcd"
drive = "gecko-g202"
axes = { x = { step = "x_step", dir = "x_dir" }, y = { step = "y_step", dir = "y_dir" } }

[[capture]]
name = "single"
path = "two-axis.vcd"
drive = "gecko-g202"
map = { step = "y_step", dir = "y_dir" }
"""

# counts the captures opened in the pytest process (one per [[capture]] entry, however many items)
COUNTING_CONFTEST = """
import wavecheck.capture.open as opener

OPENED = []
_real = opener.open_source


def _counting(path, *args, **kwargs):
    OPENED.append(str(path))
    return _real(path, *args, **kwargs)


opener.open_source = _counting


def pytest_terminal_summary(terminalreporter):
    terminalreporter.write_line(f"captures opened: {len(OPENED)}")
"""


@pytest.fixture
def project(pytester: pytest.Pytester) -> pytest.Pytester:
    shutil.copy(TWO_AXIS, pytester.path / "two-axis.vcd")
    (pytester.path / "wavecheck.toml").write_text(CONFIG)
    pytester.makeconftest(COUNTING_CONFTEST)
    return pytester


def _lines(out: str) -> dict[str, str]:
    return {ln.split(" ")[0]: ln for ln in out.splitlines() if ln.startswith("wavecheck.toml::")}


def test_items_per_axis_and_outcomes(project: pytest.Pytester) -> None:
    result = project.runpytest("-v", "-p", "no:cacheprovider", "-p", "no:randomly")
    out = result.stdout.str()
    lines = _lines(out)
    for name in ("machine", "hoped"):
        assert f"wavecheck.toml::{name}::verdict" in lines
        for axis in ("x", "y"):
            for rule in ["verdict", *G202_RULES]:
                assert f"wavecheck.toml::{name}::{axis}::{rule}" in lines, (name, axis, rule)
    assert "wavecheck.toml::single::dir_hold" in lines  # the single-axis form, unchanged
    # machine: x is expected to fail dir_hold and does; y passes; the capture fails (worst)
    for item in (
        "machine::verdict",
        "machine::x::verdict",
        "machine::x::dir_hold",
        "machine::y::verdict",
        "machine::y::dir_hold",
    ):
        assert "PASSED" in lines[f"wavecheck.toml::{item}"], item
    # hoped: every axis expected to pass; x does not
    for item in ("hoped::verdict", "hoped::x::verdict", "hoped::x::dir_hold"):
        assert "FAILED" in lines[f"wavecheck.toml::{item}"], item
    assert "PASSED" in lines["wavecheck.toml::hoped::y::verdict"]
    assert "PASSED" in lines["wavecheck.toml::single::verdict"]
    # 2 × (1 + 2 × 6) axes items + single's 6 = 32; three of hoped's fail
    result.assert_outcomes(passed=29, failed=3)
    # the failure names the axis and shows its worst violation, not a traceback
    assert "hoped::x: expected PASS, got dir_hold: FAIL — 1 violation(s)" in out
    assert "at 0.485011000 s: measured 9 us, limit 20 us, margin -11 us" in out
    assert "two-axis.vcd axis x vs drive gecko-g202" in out
    assert "hoped: expected PASS, got verdict FAIL (1 violation(s))\naxis x: verdict FAIL" in out
    assert "Traceback" not in out
    assert "captures opened: 3" in out  # once per entry, not once per axis or item


def test_one_axis_item_alone(project: pytest.Pytester) -> None:
    result = project.runpytest("-p", "no:cacheprovider", "wavecheck.toml::hoped::y::dir_hold")
    result.assert_outcomes(passed=1)
    result = project.runpytest("-p", "no:cacheprovider", "wavecheck.toml::hoped::x")
    result.assert_outcomes(passed=4, failed=2)


def test_report_dir_has_every_axis(project: pytest.Pytester) -> None:
    result = project.runpytest(
        "-p",
        "no:cacheprovider",
        "--wavecheck-report-dir",
        "reports",
        "wavecheck.toml::hoped::x::dir_hold",
    )
    result.assert_outcomes(failed=1)
    html = (project.path / "reports" / "hoped.html").read_text()
    assert "axis x" in html and "axis y" in html


def test_fixture_checks_axes(pytester: pytest.Pytester) -> None:
    shutil.copy(TWO_AXIS, pytester.path / "two-axis.vcd")
    pytester.makepyfile(
        test_axes="""
        AXES = {"x": {"step": "x_step", "dir": "x_dir"}, "y": {"step": "y_step", "dir": "y_dir"}}

        def test_y_passes(wavecheck_check):
            machine = wavecheck_check.axes("two-axis.vcd", AXES, "gecko-g202")
            assert machine.axis("y").verdict == "pass"
            wavecheck_check.expect(machine, "fail")

        def test_machine_fails_readably(wavecheck_check):
            wavecheck_check.expect(wavecheck_check.axes("two-axis.vcd", AXES, "gecko-g202"))
        """
    )
    result = pytester.runpytest("-p", "no:cacheprovider")
    result.assert_outcomes(passed=1, failed=1)
    assert (
        "expected PASS, got verdict FAIL (1 violation(s))\naxis x: verdict FAIL"
        in result.stdout.str()
    )


def test_smoothieware_each_axis_its_drive(pytester: pytest.Pytester, smoothie_sr: Path) -> None:
    """The real Smoothieware capture (X on 5/6, Y on 3/4): the G202's 4.5 us high time fails on
    x (3.7 us pulses), the DM542 passes y; rules with no interval are skipped."""
    (pytester.path / "wavecheck.toml").write_text(
        f"""\
[[capture]]
name = "smoothie"
path = "{smoothie_sr}"
axes.x = {{ step = "5", dir = "6", drive = "gecko-g202", expect = "fail", expect_rules = {{ step_high = "fail" }} }}
axes.y = {{ step = "3", dir = "4", drive = "leadshine-dm542" }}
"""
    )
    result = pytester.runpytest("-v", "-p", "no:cacheprovider", "-p", "no:randomly")
    lines = _lines(result.stdout.str())
    assert "PASSED" in lines["wavecheck.toml::smoothie::verdict"]  # expected: the worst, fail
    assert "PASSED" in lines["wavecheck.toml::smoothie::x::step_high"]
    assert "SKIPPED" in lines["wavecheck.toml::smoothie::x::dir_hold"]
    assert "PASSED" in lines["wavecheck.toml::smoothie::y::verdict"]
    assert "wavecheck.toml::smoothie::y::enable_setup" in lines  # the DM542 states it
    assert result.ret == 0


def _write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "wavecheck.toml"
    path.write_text(text)
    return path


def test_entry_keys_are_the_axes_defaults(tmp_path: Path) -> None:
    spec = load_specs(
        _write(
            tmp_path,
            """\
[[capture]]
path = "m.vcd"
drive = "gecko-g202"
map = { enable = "EN" }
invert = ["step"]
type = 0
dir_forward = "high"
expect_rules = { step_high = "indeterminate" }
axes.x = { step = "XS", dir = "XD", expect = "fail", expect_rules = { dir_hold = "fail" } }
axes.y = { STEP = "YS", drive = "leadshine-dm542", invert = [], dir_forward = "low", type = 1 }
""",
        )
    )[0]
    x, y = spec.axes
    assert (x.name, x.drive, x.invert, x.type, x.dir_forward) == (
        "x",
        "gecko-g202",
        ("step",),
        0,
        "high",
    )
    assert x.map == {"step": "XS", "dir": "XD", "enable": "EN"}  # enable shared
    assert x.expect_rules == {"step_high": "indeterminate", "dir_hold": "fail"}  # merged
    assert x.expected("dir_hold") == ("fail",) and x.expected("step_low") == ("pass", "fail")
    assert (y.drive, y.invert, y.type, y.dir_forward, y.expect) == (
        "leadshine-dm542",
        (),
        1,
        "low",
        "pass",
    )
    assert y.map == {"step": "YS", "enable": "EN"}
    assert spec.expect == "fail"  # the capture: the worst of its axes


@pytest.mark.parametrize(
    ("entry", "message"),
    [
        ('map = { step = "S" }\naxes.x = { dir = "D" }', "every role but enable names its axis"),
        (
            'axes.x = { step = "S" }\naxes.y = { step = "S" }',
            "channel 'S' is mapped as x.step and y.step",
        ),
        ('axes.x = { step = "S", speed = 3 }', "axes.x: unknown key speed"),
        ('axes.x = { step = "S", map = "step=T" }', "step is given twice"),
        ('axes."x y" = { step = "S" }', "axis name 'x y'"),
        ('axes.verdict = { step = "S" }', "'verdict' names the capture's own item"),
        ('axes.x = { step = "S", expect = "maybe" }', "'expect' must be one of"),
        ("axes = 3", "'axes' must be a table of axis tables"),
    ],
)
def test_bad_axes_are_collection_errors(tmp_path: Path, entry: str, message: str) -> None:
    with pytest.raises(WavecheckConfigError, match="capture 1") as err:
        load_specs(
            _write(tmp_path, f'[[capture]]\npath = "m.vcd"\ndrive = "gecko-g202"\n{entry}\n')
        )
    assert message in str(err.value)


def test_an_axis_needs_a_drive(tmp_path: Path) -> None:
    text = '[[capture]]\npath = "m.vcd"\naxes.x = { step = "S", drive = "gecko-g202" }\naxes.y = { step = "T" }\n'
    with pytest.raises(WavecheckConfigError, match="axes.y: no drive"):
        load_specs(_write(tmp_path, text))
    with pytest.raises(
        WavecheckConfigError, match="'drive' is required"
    ):  # without axes: as before
        load_specs(_write(tmp_path, '[[capture]]\npath = "m.vcd"\n'))
