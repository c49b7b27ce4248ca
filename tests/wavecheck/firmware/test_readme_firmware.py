"""The firmware commands of the docs (docs/firmware.md), run as written from the repository's root on the real
configurations it ships in ``captures/firmware/`` (issue 26: they named files that did not ship).
Each file there is byte for byte the one in the shared set the README of that folder names."""

from __future__ import annotations

import shlex
from pathlib import Path

import pytest

from tests.conftest import SHARED
from tests.doc_pages import marked_all
from wavecheck.cli import main

REPO = Path(__file__).resolve().parents[3]
SHIPPED = REPO / "captures" / "firmware"
BLOCKS = marked_all(r"firmware-(\w+)")
EXPECT = {
    "grbl": "grbl",
    "klipper": "klipper",
    "marlin": "marlin",
    "rrf": "reprapfirmware",
    "smoothie": "smoothieware",
    "fluidnc": "fluidnc",
    "hm2": "hm2",
    "linuxcnc": "linuxcnc",
}


def test_every_firmware_has_a_block() -> None:
    assert {name for name, _ in BLOCKS} == {*EXPECT, "measure"}


@pytest.mark.parametrize("name,block", BLOCKS, ids=[n for n, _ in BLOCKS])
def test_readme_firmware_command(
    name: str, block: str, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.chdir(REPO)
    argv = shlex.split(block.replace("\\\n", " "))
    assert argv[0] == "wavecheck"
    for arg in argv:
        if arg.startswith("captures/"):
            assert (REPO / arg).is_file(), f"the docs name {arg}, which does not ship"
    code = main(argv[1:])
    out = capsys.readouterr().out
    assert code in (0, 1, 3)
    if name == "measure":
        assert "paired: capture axis y ↔ firmware axis Y (same name)" in out
        return
    assert out.startswith(f"{EXPECT[name]} configuration") and "\nverdict: " in out


SHARED = SHARED


@pytest.mark.skipif(not SHARED.is_dir(), reason="shared firmware files not present")
def test_shipped_files_are_unchanged_copies() -> None:
    """Each shipped file is byte for byte a file of the shared real sets."""
    pool = {p.read_bytes() for d in ("firmware", "firmware-corpus")
            for p in (SHARED / d).rglob("*") if p.is_file() and p.stat().st_size < 1 << 20}  # fmt: skip
    shipped = [p for p in SHIPPED.rglob("*") if p.is_file() and p.name != "README.md"]
    assert len(shipped) >= 12
    for p in shipped:
        assert p.read_bytes() in pool, f"{p} is not an unchanged copy"
