"""The pages whose blocks the tests run: the README (the front page) and every page of ``docs/``.

A block is found by the marker before it (``<!-- readme-test: NAME -->``, the name a test reads
it by), on whichever page it lives, so a section can move between pages without its test."""

from __future__ import annotations

import re
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent


def pages() -> list[Path]:
    """README.md, then docs/*.md in name order."""
    return [REPO / "README.md", *sorted((REPO / "docs").glob("*.md"))]


def text_of(page: Path) -> str:
    return page.read_text(encoding="utf-8")


def marked(name: str, kind: str = "readme-test") -> str:
    """The one block marked ``<!-- KIND: NAME -->`` on any page, without its fences."""
    found = [
        (page, m.group(1))
        for page in pages()
        for m in re.finditer(
            rf"<!-- {re.escape(kind)}: {re.escape(name)} -->\n```\w*\n(.*?)```", text_of(page), re.S
        )
    ]
    assert found, f"no page has a block marked {kind}: {name} (README.md, docs/*.md)"
    assert len(found) == 1, (
        f"{kind}: {name} marks {len(found)} blocks: {[str(p) for p, _ in found]}"
    )
    return found[0][1]


def marked_all(pattern: str, language: str = "sh") -> list[tuple[str, str]]:
    """Every block whose ``readme-test`` name matches ``pattern`` (one group: the name's part),
    on any page: (that part, block text)."""
    return [
        (m.group(1), m.group(2))
        for page in pages()
        for m in re.finditer(
            rf"<!-- readme-test: {pattern} -->\n```{language}\n(.*?)```", text_of(page), re.S
        )
    ]
