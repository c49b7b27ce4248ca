"""captures/examples/ is what tools/examples.py writes (so the README's examples stay honest)."""

from __future__ import annotations

from tools.examples import main


def test_examples_are_as_written() -> None:
    assert main(["--check"]) == 0
