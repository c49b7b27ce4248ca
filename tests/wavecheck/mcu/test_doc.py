"""docs/firmware-simulation.md runs as written: each ``sh`` block, in order, in a fresh folder
with the installed ``wavecheck`` on PATH, and each gives the verdict the page says (grbl's
section, then Klipper's)."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from tests.wavecheck.mcu.helpers import GRBL_SRC, REPO, SIMAVR_SRC

#: grbl simulated end to end (make test-all and CI run it; make test leaves it out)
pytestmark = pytest.mark.slow

DOC = REPO / "docs" / "firmware-simulation.md"
KLIPPER = "## Klipper"


def run_blocks(section: str, folder: str, tmp_path: Path) -> list[tuple[int, str, str]]:
    """Each sh block of one section of the page, in a copy of the checkout's docs/FOLDER, from
    its root, where ../shared/firmware-src holds the sources: (exit code, stdout, stderr)."""
    blocks = re.findall(r"```sh\n(.*?)```", section, re.S)
    (tmp_path / "repo").mkdir()
    shutil.copytree(REPO / "docs" / folder, tmp_path / "repo" / "docs" / folder)
    (tmp_path / "shared").symlink_to(GRBL_SRC.parents[1])
    env = {**os.environ, "PATH": f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}"}
    out = []
    for block in blocks:
        done = subprocess.run(
            ["bash", "-c", block],
            cwd=tmp_path / "repo",
            env=env,
            capture_output=True,
            text=True,
        )
        assert "error" not in done.stderr.lower(), done.stderr
        out.append((done.returncode, done.stdout, done.stderr))
    return out


def test_every_grbl_block_runs_and_gives_the_verdict_the_page_says(grbl, runner, tmp_path):
    grbl_part = DOC.read_text(encoding="utf-8").split(KLIPPER)[0]
    codes = run_blocks(grbl_part, "grbl", tmp_path)
    assert len(codes) == 3
    assert codes[0][0] == 1 and re.search(r"dir_setup\s+650 ns\s+5\s+5 .* FAIL", codes[0][1])
    assert codes[1][0] == 0 and "verdict: PASS" in codes[1][1]
    assert codes[2][0] == 0 and re.search(r"dir_setup .* 10\.06 us .* pass", codes[2][1])
    assert re.search(r"step_high .* 6\.188 us", codes[2][1])  # the page's 6.19 us
    assert SIMAVR_SRC.is_dir()


def test_every_klipper_block_runs_and_gives_the_verdict_the_page_says(
    klipper_build, klippy, runner, tmp_path
):
    page = DOC.read_text(encoding="utf-8")
    part = page.split(KLIPPER)[1]
    codes = run_blocks(part, "klipper", tmp_path)
    assert len(codes) == 2
    (code, out, err), (code2, out2, err2) = codes
    assert code == 1 and "final position +2" in out, (code, out[-600:], err[-600:])
    assert re.search(r"step_high\s+4\.5 us\s+38400\s+33075 .* 2\.625 us .* FAIL", out)
    assert code2 == 0 and "verdict: PASS" in out2 and "final position +0" in out2
    slots = re.search(r"the MCU has (\d+) move-queue slots", err)
    assert slots and f"leaves this build {slots.group(1)}" in " ".join(page.split())
    for line in out.splitlines()[4:9]:  # the page quotes the steps line and the rule table
        if line.startswith(("steps:", "step_high", "dir_setup")):
            assert line in page
