"""The commands of ``wavecheck`` do not import each other (issue 37): what several commands share
lives in ``wavecheck/cli/_*.py``, so a command can change without reaching into another."""

from __future__ import annotations

import ast
from pathlib import Path

from wavecheck.cli import COMMANDS

ROOT = Path(__file__).resolve().parents[2]
MODULES = {c.module for c in COMMANDS.values()}


def _imports(path: Path) -> set[str]:
    names: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            names.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names.add(node.module)
            names.update(f"{node.module}.{a.name}" for a in node.names)
    return names


def test_no_wavecheck_module_imports_a_command() -> None:
    """Only the command table names the commands' modules (cli/__init__, imported when run)."""
    reached = {}
    for path in sorted((ROOT / "wavecheck").rglob("*.py")):
        rel = path.relative_to(ROOT).with_suffix("").as_posix().replace("/", ".")
        found = (_imports(path) & MODULES) - {rel}
        if found:
            reached[rel] = sorted(found)
    assert len(MODULES) >= 10
    assert not reached, reached


def _format_branches(path: Path) -> list[int]:
    """Lines of ``path`` that compare ``args.format`` with something (a branch on ``--format``;
    a capture's own ``cap.format`` is no option)."""
    lines = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Compare):
            sides = [node.left, *node.comparators]
            if any(
                isinstance(s, ast.Attribute)
                and s.attr == "format"
                and isinstance(s.value, ast.Name)
                and s.value.id == "args"
                for s in sides
            ):
                lines.append(node.lineno)
    return lines


def test_no_command_branches_on_its_format() -> None:
    """Every ``--format`` is one renderer per format in a registry (cli/_formats.py): check's
    FORMATS, every other command's Formats; no command tests ``args.format`` itself."""
    bad = {
        str(p.relative_to(ROOT)): lines
        for p in sorted((ROOT / "wavecheck" / "cli").glob("*.py"))
        if (lines := _format_branches(p))
    }
    assert not bad, bad


def test_the_format_test_sees_a_branch(tmp_path: Path) -> None:
    probe = tmp_path / "probe.py"
    probe.write_text("def f(args):\n    return 1 if args.format == 'json' else 2\n")
    assert _format_branches(probe) == [2]


def test_no_library_module_imports_the_command_line() -> None:
    """The command lines (wavecheck/cli, stepgen/cli) sit on the library, never under it:
    ``stepgen plan --latency-from`` reads a capture's latency through wavecheck.step_latency,
    not through ``wavecheck latency``'s module."""
    reached = {}
    for top in ("wavecheck", "stepgen"):
        for path in sorted((ROOT / top).rglob("*.py")):
            rel = path.relative_to(ROOT).as_posix()
            if rel.startswith(("wavecheck/cli/", "stepgen/cli/")) or path.stem == "__main__":
                continue
            found = {n for n in _imports(path) if n.startswith(("wavecheck.cli", "stepgen.cli"))}
            if found:
                reached[rel] = sorted(found)
    assert not reached, reached
