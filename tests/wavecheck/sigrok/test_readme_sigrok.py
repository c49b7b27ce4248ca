"""The README's PulseView and sigrok-cli block, run as written (but its last line, PulseView itself:
``test_pulseview.py``), with the user decoder directory in a temporary ``XDG_DATA_HOME``."""

from __future__ import annotations

import os
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from tests.test_readme import _block
from tests.wavecheck.sigrok.conftest import need

pytestmark = pytest.mark.sigrok

REPO = Path(__file__).resolve().parents[3]


def test_readme_sigrok_block(tmp_path: Path) -> None:
    need("sigrok-cli")
    shutil.copytree(REPO / "captures" / "golden", tmp_path / "captures" / "golden")
    env = dict(os.environ, XDG_DATA_HOME=str(tmp_path / "data"))
    env.pop("SIGROKDECODE_DIR", None)
    bindir = Path(sys.executable).parent
    lines = _block("sigrok").replace("\\\n", " ").strip().splitlines()
    assert lines[-1] == "pulseview -s g202.pvs -i g202.sr"
    outputs = []
    for line in lines[:-1]:
        argv = shlex.split(line)
        if argv[0] in ("wavecheck", "stepgen"):
            argv[0] = str(bindir / argv[0])
        run = subprocess.run(argv, cwd=tmp_path, env=env, capture_output=True, text=True)
        assert run.returncode in (0, 1), f"{line}: {run.stderr}"
        outputs.append(run)
    install, _, decoded, check = outputs
    assert "ok: sigrok-cli ran the decoder" in install.stdout
    assert "SIGROKDECODE_DIR" not in install.stdout  # the user directory is searched
    assert (tmp_path / "data/libsigrokdecode/decoders/wavecheck/pd.py").is_file()
    assert decoded.stdout.splitlines() == [
        "485011-485020 wavecheck-1: dir_hold: measured 9 us, limit 20 us, margin -11 us"
    ]
    assert check.returncode == 1
    assert "pulseview -s g202.pvs -i g202.sr" in check.stderr
    assert "not installed" not in check.stderr
    assert "decoder0\\id=wavecheck" in (tmp_path / "g202.pvs").read_text()
