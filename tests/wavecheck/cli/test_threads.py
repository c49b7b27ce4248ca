"""The commands start numpy with one OpenBLAS thread (a thread per core cost about 0.1 s of CPU
at every start, for linear algebra no command does), unless the environment says otherwise."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from tests.conftest import REPO

PROBE = (
    "import os, sys; from wavecheck.cli import main; "
    "rc = main(['drives']); print(os.environ.get('OPENBLAS_NUM_THREADS'), file=sys.stderr)"
)


@pytest.mark.parametrize(("given", "seen"), [(None, "1"), ("2", "2")])
def test_one_blas_thread_unless_told(given: str | None, seen: str) -> None:
    env = {k: v for k, v in os.environ.items() if k != "OPENBLAS_NUM_THREADS"}
    if given is not None:
        env["OPENBLAS_NUM_THREADS"] = given
    run = subprocess.run(
        [sys.executable, "-c", PROBE], capture_output=True, text=True, env=env, cwd=REPO,
        timeout=120, check=True,
    )  # fmt: skip
    assert run.stderr.strip().splitlines()[-1] == seen
