"""Every command block of the README and of docs/ runs as written, from a fresh clone (issue 26;
issue 37 moved most sections from the README to docs/, one page per audience).

The tracked files of the checkout are copied to an empty folder (what ``git clone`` gives) and
each ``sh`` block's commands run there with bash from the clone's root, page by page (README
first), as a reader following the page would run them, with the installed ``wavecheck`` and ``stepgen`` on ``PATH``. A command
runs as written when it ends with a verdict's exit code (0 pass, 1 fail, 3 indeterminate, 4 a
required rule not decided) and says no error: exit 2 (unusable input or usage), a traceback or
a ``wavecheck: error:`` line is a page that does not work. What each block must *give* is asserted by
its own test (``readme-test`` markers); this one holds every block to running at all, and every
other block (Python, TOML) to having such a test.

Skipped, each with its reason (:data:`SKIPPED`): only what needs hardware, a window, or sets up
the machine. Every file a block names ships (the grbl capture in ``captures/real/``). The pages also build as a site: ``mkdocs build --strict``
(:func:`test_the_docs_build_as_a_site`).
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

from tests.doc_pages import pages

REPO = Path(__file__).resolve().parent.parent
BIN = Path(sys.executable).parent

#: Commands not run, by their first words, and why.
SKIPPED = {
    ". .venv/bin/activate": "puts .venv/bin on PATH; the installed commands are on it already",
    "make demo": "sets the machine up (a virtual environment, apt-get) before its check",
    "make test": "this suite itself (ruff, mypy, pytest)",
    "make bench": "minutes of benchmarks against other tools (bench/README.md)",
    "make story": "a make target: sets up .venv in the clone first (pip, from the network)",
    "make golden-check": "a make target: sets up .venv in the clone first (pip, from the network)",
    "make fuzz": "a longer fuzz run (minutes); the suite runs a bounded one",
    "wavecheck watch --driver fx2lafw": "needs an FX2 logic analyzer on USB",
    "wavecheck simulate": "builds grbl and simavr from ../shared/firmware-src, which a clone "
    "has not (tests/wavecheck/mcu/test_doc.py runs docs/firmware-simulation.md beside it)",
    "sed 's|^// #define STEP_PULSE_DELAY": "edits grbl's config.h from ../shared/firmware-src "
    "(tests/wavecheck/mcu/test_doc.py)",
    "pulseview": "opens PulseView's window (tests/wavecheck/sigrok/test_pulseview.py runs it "
    "under Xvfb)",
}
#: What LinuxCNC's latency-test leaves in ~/.latency (one number, ns), for `--latency ~/.latency`.
DOT_LATENCY_NS = "11000\n"
#: Exit codes that are verdicts (docs/reference.md, "Exit codes").
VERDICTS = (0, 1, 3, 4)
#: The one-line error of either tool (README: "one line naming the file and the place in it").
ERROR = re.compile(r"^(?:wavecheck|stepgen)(?: \w+)?: error:", re.M)


@dataclass(frozen=True)
class Block:
    """A fenced block of a page: its language, the marker before it, its page and first line."""

    page: str
    language: str
    marker: str
    line: int
    text: str

    @property
    def commands(self) -> list[str]:
        """Its commands: continued lines joined, comments and blank lines left out."""
        joined = self.text.replace("\\\n", " ")
        return [c.strip() for c in joined.splitlines() if c.strip() and not c.startswith("#")]


def blocks() -> list[Block]:
    """Every fenced block of the README and docs/*.md, page by page."""
    found = []
    for page in pages():
        text = page.read_text(encoding="utf-8")
        for m in re.finditer(r"(?:<!-- ([\w-]+: ?[\w./-]+) -->\n)?```(\w*)\n(.*?)```", text, re.S):
            line = text[: m.start(2)].count("\n") + 1
            found.append(Block(page.name, m.group(2), m.group(1) or "", line, m.group(3)))
    return found


def _synopsis() -> Block:
    return next(b for b in blocks() if b.text.startswith("wavecheck info CAPTURE"))


def _skipped(command: str) -> str | None:
    return next((why for start, why in SKIPPED.items() if command.startswith(start)), None)


@pytest.fixture(scope="module")
def clone(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The tracked files of the checkout in an empty folder, and a home of its own."""
    if shutil.which("git") is None:
        pytest.skip("needs git to list the tracked files")
    listed = subprocess.run(["git", "ls-files", "-z"], cwd=REPO, capture_output=True, check=False)
    if listed.returncode != 0:
        pytest.skip("not a git checkout (an installed wheel): no page's commands to run")
    root = tmp_path_factory.mktemp("clone")
    for name in listed.stdout.decode().split("\0"):
        if name and (REPO / name).is_file():
            (root / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(REPO / name, root / name)
    home = root.parent / "home"
    home.mkdir()
    (home / ".latency").write_text(DOT_LATENCY_NS)
    return root


def _run(command: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    env = {
        **os.environ,
        "PATH": f"{BIN}{os.pathsep}{os.environ.get('PATH', '')}",
        "HOME": str(cwd.parent / "home"),
        "XDG_DATA_HOME": str(cwd.parent / "home" / ".local" / "share"),
        "MPLBACKEND": "Agg",
    }
    return subprocess.run(
        ["bash", "-o", "pipefail", "-c", command],
        cwd=cwd, env=env, capture_output=True, text=True, timeout=600, check=False,
    )  # fmt: skip


SHELL = [b for b in blocks() if b.language == "sh"]


@pytest.mark.slow
@pytest.mark.parametrize(
    "block", [b for b in SHELL if not b.text.startswith("wavecheck info CAPTURE")],
    ids=lambda b: f"{b.page}:{b.line}-{b.marker.split(':')[-1].strip() or 'unmarked'}",
)  # fmt: skip
def test_every_command_runs_as_written(block: Block, clone: Path) -> None:
    ran = 0
    for command in block.commands:
        if _skipped(command):
            continue
        done = _run(command, clone)
        said = done.stdout + done.stderr
        assert done.returncode in VERDICTS, (command, done.returncode, said[-2000:])
        assert "Traceback" not in said and not ERROR.search(said), (command, said[-2000:])
        ran += 1
    if not ran:
        pytest.skip("; ".join(sorted({str(_skipped(c)) for c in block.commands})))


def test_the_synopsis_names_only_options_that_exist() -> None:
    """The usage block is a synopsis, not commands: each option it lists is one of that
    command's options (``--help``)."""
    checked = 0
    for entry in re.split(r"\n(?=(?:wavecheck|stepgen) )", _synopsis().text.strip()):
        tool, sub = entry.split()[:2]
        options = set(re.findall(r"(?<![\w-])(--[a-z][\w-]*)", entry.split("#")[0]))
        out = subprocess.run(
            [str(BIN / tool), sub, "--help"], capture_output=True, text=True, check=True
        ).stdout
        for option in options:
            assert re.search(rf"(?<![\w-]){option}(?![\w-])", out), (tool, sub, option)
            checked += 1
        assert tool in ("wavecheck", "stepgen"), entry
    assert checked > 40  # the synopsis lists 52 options


def test_every_other_block_has_its_own_test() -> None:
    """A Python or TOML block is run by the test its marker names (readme-test: NAME is read
    by a test with that name; cocotb-example: PATH is that file)."""
    tests = "\n".join(p.read_text(encoding="utf-8") for p in (REPO / "tests").rglob("*.py"))
    for b in blocks():
        if b.language == "sh":
            continue
        kind, _, name = b.marker.partition(":")
        name = name.strip()
        assert kind in ("readme-test", "cocotb-example"), (b.page, b.line, b.text[:60])
        if kind == "cocotb-example":
            assert (REPO / name).is_file(), name
        else:
            assert f'"{name}"' in tests or f"readme-test: {name}" in tests, name


def test_the_skip_list_only_skips_what_the_pages_have() -> None:
    commands = [c for b in SHELL for c in b.commands]
    for start in SKIPPED:
        assert any(c.startswith(start) for c in commands), start


def test_the_docs_build_as_a_site(tmp_path: Path) -> None:
    """``mkdocs build --strict`` (mkdocs.yml): every page in the navigation, every link between
    pages and every anchor found; a warning fails the build."""
    mkdocs = BIN / "mkdocs"
    if not mkdocs.exists():
        pytest.skip("mkdocs is not installed (the test extra has it)")
    built = subprocess.run(
        [str(mkdocs), "build", "--strict", "-q", "-f", str(REPO / "mkdocs.yml"), "-d", str(tmp_path)],
        capture_output=True, text=True, timeout=300, check=False,
    )  # fmt: skip
    assert built.returncode == 0, built.stderr
    listed = {p.name for p in (REPO / "docs").glob("*.md")}
    nav = set(re.findall(r"^  - [^:]+: (\S+\.md)$", (REPO / "mkdocs.yml").read_text(), re.M))
    assert nav == listed, listed ^ nav  # every page reachable from the site's navigation
    assert (tmp_path / "index.html").is_file()


def test_the_front_page_stays_short() -> None:
    """Issue 37: the README is a front page (at most about 250 lines); the rest is in docs/."""
    text = (REPO / "README.md").read_text(encoding="utf-8")
    assert len(text.splitlines()) <= 250
    linked = re.findall(r"\]\((docs/[^)#]+)", text)
    assert len(linked) > 12 and all((REPO / rel).is_file() for rel in linked), linked
