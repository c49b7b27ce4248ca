"""A bounded run of the firmware fuzzer (``fuzz_firmware.py``) per format, in its own process
with its address space limited (RLIMIT_AS) and a timeout, as ``tests/reliability`` runs the
capture readers' fuzzers: every case is read or refused with one line naming the file, within
its time bound; nothing may crash, hang or grow without bound."""

from __future__ import annotations

import os
import resource
import subprocess
import sys
from pathlib import Path

import pytest

from tests.bounds import HANG_GUARD_S
from tests.wavecheck.firmware.fuzz_firmware import FORMATS

REPO = Path(__file__).resolve().parents[3]
#: Address space for the whole run (the interpreter with numpy needs ~150 MiB).
_MEMORY = 1 << 30


def _limit_memory() -> None:
    resource.setrlimit(resource.RLIMIT_AS, (_MEMORY, _MEMORY))


@pytest.mark.parametrize("name", sorted(FORMATS))
def test_bounded_fuzz(name: str, tmp_path: Path) -> None:
    proc = subprocess.run(
        [sys.executable, "-m", "tests.wavecheck.firmware.fuzz_firmware", "--reader", name,
         "-n", "200", "--seed", "1", "--max-seconds", str(HANG_GUARD_S), "--out", str(tmp_path)],
        capture_output=True, text=True, timeout=None, cwd=REPO, check=False,
        preexec_fn=_limit_memory, env={**os.environ, "OPENBLAS_NUM_THREADS": "1"},
    )  # fmt: skip
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    assert f"{name}: " in proc.stdout and " 0 failures" in proc.stdout
