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
