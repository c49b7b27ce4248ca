"""The capture and crosscheck modules share only public names: none imports another module's
``_private`` name (what both VCD readers need lives, public, in ``capture/vcd/header.py``)."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

import wavecheck

ROOT = Path(wavecheck.__file__).resolve().parent
MODULES = sorted([*ROOT.glob("capture/**/*.py"), *ROOT.glob("crosscheck/**/*.py")])


@pytest.mark.parametrize("path", MODULES, ids=lambda p: str(p.relative_to(ROOT)))
def test_no_private_name_is_imported_from_another_module(path: Path) -> None:
    bad = [
        f"line {node.lineno}: from {node.module} import {alias.name}"
        for node in ast.walk(ast.parse(path.read_text(), str(path)))
        if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("wavecheck")
        for alias in node.names
        if alias.name.startswith("_") and not alias.name.startswith("__")
    ]
    assert not bad, bad


def test_the_walk_sees_the_vcd_package() -> None:
    names = {p.relative_to(ROOT).as_posix() for p in MODULES}
    assert {"capture/vcd/header.py", "capture/vcd/reader.py", "capture/vcd/reference.py"} <= names
