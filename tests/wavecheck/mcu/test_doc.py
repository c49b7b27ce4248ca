"""docs/firmware-simulation.md runs as written: each ``sh`` block, in order, in a fresh folder
with the installed ``wavecheck`` on PATH, and each gives the verdict the page says."""

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


def test_every_block_runs_and_gives_the_verdict_the_page_says(grbl, runner, tmp_path):
    blocks = re.findall(r"```sh\n(.*?)```", DOC.read_text(encoding="utf-8"), re.S)
    assert len(blocks) == 3
    # the page runs from the checkout's root, where ../shared/firmware-src is the source
    (tmp_path / "repo").mkdir()
    shutil.copytree(REPO / "docs" / "grbl", tmp_path / "repo" / "docs" / "grbl")
    (tmp_path / "shared").symlink_to(GRBL_SRC.parents[1])
    env = {**os.environ, "PATH": f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}"}
    codes = []
    for block in blocks:
        done = subprocess.run(
            ["bash", "-c", block],
            cwd=tmp_path / "repo",
            env=env,
            capture_output=True,
            text=True,
        )
        assert "error" not in done.stderr.lower(), done.stderr
        codes.append((done.returncode, done.stdout))
    assert codes[0][0] == 1 and re.search(r"dir_setup\s+650 ns\s+5\s+5 .* FAIL", codes[0][1])
    assert codes[1][0] == 0 and "verdict: PASS" in codes[1][1]
    assert codes[2][0] == 0 and re.search(r"dir_setup .* 10\.06 us .* pass", codes[2][1])
    assert re.search(r"step_high .* 6\.188 us", codes[2][1])  # the page's 6.19 us
    assert SIMAVR_SRC.is_dir()
