"""The README's "three ways" examples, run exactly as written (blocks marked readme-test)."""

from __future__ import annotations

import json
import shlex
import shutil
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from tests.doc_pages import marked
from wavecheck.cli import main

REPO = Path(__file__).resolve().parent.parent
GOLDEN = "captures/golden/g202-p20-worst-dirhold.vcd"

pytest_plugins = ["pytester"]


def _block(name: str) -> str:
    """The block marked ``readme-test: NAME`` on the README or a page of docs/."""
    return marked(name)


@pytest.fixture
def workdir(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """A folder holding the golden traces the README names, as the current directory."""
    src = REPO / "captures" / "golden"
    if not (REPO / GOLDEN).exists():
        pytest.fail(f"{GOLDEN} is missing (the README names it)")
    shutil.copytree(src, tmp_path / "captures" / "golden")
    monkeypatch.chdir(tmp_path)
    return tmp_path


def test_cli_block(workdir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    commands = _block("cli").replace("\\\n", " ").strip().splitlines()
    codes = []
    for line in commands:
        argv = shlex.split(line)
        assert argv[0] == "wavecheck"
        if "*" in line:  # what the shell would expand
            argv = [a for arg in argv for a in (sorted(map(str, workdir.glob(arg))) or [arg])]
            argv = [
                str(Path(a).relative_to(workdir)) if a.startswith(str(workdir)) else a for a in argv
            ]
        codes.append(main(argv[1:]))
    out = capsys.readouterr().out
    assert codes == [1, 1] and "dir_hold     20 us   1        1" in out  # both: a rule failed
    for name in ("g202.png", "g202.html", "g202.gtkw"):
        assert (workdir / name).stat().st_size > 0
    root = ET.parse(workdir / "junit.xml").getroot()
    assert len(root.findall("testsuite")) == len(
        list((workdir / "captures/golden").glob("g202-*.vcd"))
    )
    assert root.get("errors") == "0"


def test_axes_block(workdir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Two axes, x failing dir_hold (the 20 us story trace) and y passing (the 16 us plan)."""
    shutil.copytree(REPO / "captures" / "examples", workdir / "captures" / "examples")
    codes = [
        main(shlex.split(line)[1:])
        for line in _block("axes").replace("\\\n", " ").strip().splitlines()
    ]
    out = capsys.readouterr().out
    assert codes == [1, 1] and "== axis x ==" in out and "== axis y ==" in out
    data = json.loads((workdir / "machine.json").read_text())
    assert {a["name"]: a["verdict"] for a in data["axes"]} == {"x": "fail", "y": "pass"}


def test_require_block(capsys: pytest.CaptureFixture[str], monkeypatch) -> None:
    """The Verdicts section's --require example: exit 4 and the line saying why (issue 26)."""
    monkeypatch.chdir(REPO)
    (line,) = _block("require").strip().splitlines()
    assert main(shlex.split(line)[1:]) == 4
    first, second = capsys.readouterr().out.splitlines()[:2]
    assert first == (  # issue 34: the first line carries the exit code's outcome
        "verdict: NOT DECIDED (exit 4: required dir_setup, dir_hold not checked: no DIR "
        "channel); the rules checked: PASS (dir_setup, dir_hold not checked: no DIR channel; "
        "enable_setup not checked: drive drv8825 states no figure)"
    )
    assert second == "required but not decided: dir_setup, dir_hold not checked: no DIR channel"


def test_rule_file_block(workdir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The README's own rule file, as written (issue 26: the documented top-level form was
    refused), used by --drive; the other figures stay the G202's."""
    (workdir / "my-g202.toml").write_text(_block("rule-file"))
    code = main(["check", GOLDEN, "--drive", "./my-g202.toml", "--format", "json"])
    rules = {r["id"]: r for r in json.loads(capsys.readouterr().out)["rules"]}
    assert code == 1  # the G202 trace still fails dir_hold
    assert rules["step_high"]["limit_ns"] == 2500 and rules["step_high"]["limit_status"] == "user"
    assert (
        rules["dir_hold"]["limit_ns"] == 20000 and rules["dir_hold"]["limit_status"] == "datasheet"
    )


def test_a_figure_at_the_top_of_a_rule_file_says_where_it_goes(workdir: Path, capsys) -> None:
    (workdir / "top.toml").write_text('extends = "gecko-g202"\nstep_high = "2.5us"\n')
    assert main(["check", GOLDEN, "--drive", "./top.toml"]) == 2
    err = capsys.readouterr().err
    assert (
        'step_high: unknown key (a figure goes under [limits]: [limits] step_high = "2.5us")' in err
    )


def test_python_block(workdir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    exec(compile(_block("python"), "README.md", "exec"), {})
    assert capsys.readouterr().out == "fail 9000 20000\n"


def test_python_options_block(workdir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """An options object handed whole, a keyword replacing its margin (issue 37)."""
    exec(compile(_block("python-options"), "docs/python.md", "exec"), {})
    assert capsys.readouterr().out == "21000\n"


def test_pytest_blocks(pytester: pytest.Pytester) -> None:
    shutil.copytree(REPO / "captures" / "golden", pytester.path / "captures" / "golden")
    (pytester.path / "wavecheck.toml").write_text(_block("toml"))
    pytester.makepyfile(test_readme_fixture=_block("fixture"))
    result = pytester.runpytest("-v", "-p", "no:cacheprovider")
    out = result.stdout.str()
    assert "wavecheck.toml::g202-p20::dir_hold PASSED" in out
    assert "test_g202_at_20us_breaks_dir_hold PASSED" in out
    result.assert_outcomes(passed=7)  # verdict + 5 rules + the fixture test


def test_pytest_axes_block(pytester: pytest.Pytester) -> None:
    """The two-axis wavecheck.toml: x fails dir_hold as expected, y passes (issue 13)."""
    shutil.copytree(REPO / "captures" / "examples", pytester.path / "captures" / "examples")
    (pytester.path / "wavecheck.toml").write_text(_block("toml-axes"))
    result = pytester.runpytest("-v", "-p", "no:cacheprovider")
    out = result.stdout.str()
    for item in (
        "machine::verdict",
        "machine::x::dir_hold",
        "machine::y::dir_hold",
        "machine::y::verdict",
    ):
        assert f"wavecheck.toml::{item} PASSED" in out, item
    result.assert_outcomes(passed=13)  # the capture + 2 axes × (verdict + 5 rules)


def test_latency_block(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """The latency section's commands run as written (issue 17)."""
    from stepgen.cli import main as stepgen_main

    monkeypatch.chdir(tmp_path)
    for line in _block("latency").strip().splitlines():
        argv = shlex.split(line)
        tool = main if argv[0] == "wavecheck" else stepgen_main
        assert tool(argv[1:]) == 0, line


@pytest.mark.parametrize(
    ("name", "code"),
    [("latency-example", 0), ("tour-check", 1)],  # docs/linuxcnc.md; the README's tour (a FAIL)
)
def test_transcript_block(
    name: str, code: int, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """A shown command and an excerpt of what it prints: each line shown is a line the command
    prints, as written, and the command ends with the exit code the text implies (issue 25)."""
    lines = _block(name).strip().splitlines()
    assert lines[0].startswith("$ wavecheck ")
    monkeypatch.chdir(REPO)
    assert main([*shlex.split(lines[0][2:])[1:], "-q"]) == code
    out = capsys.readouterr().out.splitlines()
    for line in lines[1:]:
        assert line in out, line
