"""``make demo`` runs on a fresh clone with nothing beside it (issue 37: its section 5, the real
grbl capture, was skipped without a word when ``../shared`` was missing)."""

from __future__ import annotations

import re
from pathlib import Path

from tests.conftest import shared_capture

REPO = Path(__file__).resolve().parent.parent


def _demo_recipe() -> str:
    makefile = (REPO / "Makefile").read_text(encoding="utf-8")
    m = re.search(r"^demo:.*?\n((?:\t.*\n|\n)*)", makefile, re.M)
    assert m, "the Makefile has no demo target"
    return m.group(1)


def test_every_file_the_demo_reads_ships() -> None:
    makefile = (REPO / "Makefile").read_text(encoding="utf-8")
    variables = dict(re.findall(r"^(\w+)\s*:=\s*(\S+)", makefile, re.M))
    recipe = re.sub(r"\$\((\w+)\)", lambda m: variables.get(m.group(1), m.group(0)), _demo_recipe())
    paths = set(re.findall(r"(?<![\w/.-])([\w./-]+\.(?:sr|vcd))\b", recipe))
    named = {p for p in paths if not p.startswith("out/")}  # out/: what the demo writes
    assert len(named) >= 4, named
    for rel in named:
        assert not rel.startswith(".."), f"the demo reads {rel} from outside the clone"
        assert (REPO / rel).is_file(), f"the demo reads {rel}, which does not ship"


def test_the_demo_skips_nothing_silently() -> None:
    """No section of the recipe is run only when a file happens to be there."""
    assert not re.search(r"if \[ -[ef] ", _demo_recipe())


def test_the_shipped_grbl_capture_is_sigrok_dumps_own() -> None:
    shared = shared_capture("sigrok-dumps/stepper_motor/grbl_cnc/grbl_cnc_1.sr")
    assert (REPO / "captures/real/grbl_cnc_1.sr").read_bytes() == shared.read_bytes()
