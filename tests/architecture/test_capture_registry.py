"""The capture formats are one table (issue 37): ``capture/open.py`` names no format, and the
modules of ``capture/`` import each other without a circle."""

from __future__ import annotations

import ast
from pathlib import Path

from tests.architecture.test_layering import ROOT, _deps
from wavecheck.capture.formats import FORMATS, SIGROK


def _circle(graph: dict[str, set[str]]) -> list[str] | None:
    seen: dict[str, int] = {}
    path: list[str] = []

    def visit(u: str) -> list[str] | None:
        seen[u] = 1
        path.append(u)
        for v in sorted(graph.get(u, ())):
            if seen.get(v) == 1:
                return [*path[path.index(v) :], v]
            if v not in seen and (found := visit(v)):
                return found
        path.pop()
        seen[u] = 2
        return None

    for u in sorted(graph):
        if u not in seen and (found := visit(u)):
            return found
    return None


def test_no_circle_inside_capture() -> None:
    graph = {
        m: {n for n in names if n.startswith("wavecheck.capture")}
        for m, names in _deps().items()
        if m.startswith("wavecheck.capture")
    }
    assert len(graph) > 10
    circle = _circle(graph)
    assert circle is None, "circle: " + " → ".join(circle or [])


def test_the_circle_test_sees_a_circle() -> None:
    assert _circle({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == ["a", "b", "c", "a"]


def test_open_names_no_format() -> None:
    """Every format's name, magic and extensions live in its record, not in open.py."""
    tree = ast.parse((ROOT / "wavecheck" / "capture" / "open.py").read_text(encoding="utf-8"))
    words = {n for f in (*FORMATS, SIGROK) for n in (f.name, *f.aliases, *f.extensions)}
    magics = {m for f in FORMATS for m in f.magic}
    hits = [
        f"line {node.lineno}: {node.value!r}"
        for node in ast.walk(tree)
        if isinstance(node, ast.Constant) and (node.value in words or node.value in magics)
    ]
    assert not hits, "format knowledge in capture/open.py: " + ", ".join(hits)


def test_no_reader_borrows_from_the_vcd_header() -> None:
    """Shared helpers (resolution_of, path_argument) come from capture/common.py."""
    borrowed = []
    for path in sorted((ROOT / "wavecheck" / "capture").rglob("*.py")):
        if path.parent.name == "vcd":
            continue
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.ImportFrom) and node.module in (
                "wavecheck.capture.vcd.header",
                "wavecheck.capture.open",
            ):
                names = {a.name for a in node.names}
                if names & {"resolution_of", "stated_samplerate", "path_argument"}:
                    borrowed.append(f"{Path(path).name}: {sorted(names)}")
    assert not borrowed, borrowed
