"""A bounded run of the fuzz driver per reader, and real subprocesses with a timeout (no hang)."""

from __future__ import annotations

import os
import resource
import subprocess
import sys
from pathlib import Path

import pytest

from tests.bounds import HANG_GUARD_S
from tests.reliability.corpus import Case, one_line_error, sr_cases, vcd_cases
from tests.reliability.fuzz import FORKED, READERS, run_random

REPO = Path(__file__).resolve().parents[2]


@pytest.mark.parametrize(
    "reader",
    [
        "sr",
        "vcd",
        "rules",
    ],
)
def test_bounded_fuzz(tmp_path: Path, reader: str) -> None:
    # each case bounded in memory (tracemalloc); seconds only guard against a hang (tests/bounds.py)
    tally = run_random(reader, 300, seed=1, out=tmp_path, max_seconds=HANG_GUARD_S)
    assert tally.cases > 300 and tally.peak_bytes > 0
    assert not tally.failures, tally.report(tmp_path)


@pytest.mark.parametrize("reader", sorted(FORKED))
def test_bounded_fuzz_in_a_child(tmp_path: Path, reader: str) -> None:
    """Issue 27: GHW, FST, Saleae CSV and binary, latency files and histograms, follow's
    command files: 24 truncations of each seed and 40 mutants (``make fuzz`` runs thousands),
    each case in a forked child under RLIMIT_AS (a panic, an abort, a hang past the guard of
    tests/bounds.py or a traceback is a failure)."""
    if not READERS[reader][2]:
        pytest.skip("the tool that makes its seeds (ghdl, gtkwave) is not installed")
    tally = run_random(reader, 40, seed=27, out=tmp_path, cuts=24, max_seconds=HANG_GUARD_S)
    assert tally.results >= 1 and tally.errors >= 1  # its seeds read, broken inputs refused
    assert not tally.failures, tally.report(tmp_path)


_NASTY = {"nul-tail", "huge-declared-width", "wide-vector-value", "time-backwards",
          "size-lie-inflates-more", "declared-size-2GiB", "corrupt-chunk-4", "png",
          "chunk-number-1e11", "overlapping-entries-1000", "no-whitespace-body",
          "time-19-digits", "time-2^63"}  # fmt: skip
#: Address space for one subprocess run (the interpreter with numpy needs ~150 MiB).
_MEMORY = 1 << 30


def _limit_memory() -> None:
    resource.setrlimit(resource.RLIMIT_AS, (_MEMORY, _MEMORY))


@pytest.mark.parametrize(
    "case",
    [c for c in [*sr_cases(), *vcd_cases()] if c.name in _NASTY],
    ids=lambda c: f"{c.name}{c.suffix}",
)
def test_subprocess_bounded(tmp_path: Path, case: Case) -> None:
    """The real command in its own process: finishes within 60 s and 1 GiB of address space; a
    broken file gives exit 2, one line naming it and no report file; a readable odd one gives a
    verdict."""
    path = tmp_path / f"in{case.suffix}"
    path.write_bytes(case.data)
    out = tmp_path / "out"
    out.mkdir()
    proc = subprocess.run(
        [sys.executable, "-m", "wavecheck", "check", str(path), "--drive", "gecko-g202",
         "--map", "step=STEP,dir=DIR", "-o", str(out / "r.json")],
        capture_output=True, text=True, timeout=60, cwd=REPO, check=False,
        preexec_fn=_limit_memory, env={**os.environ, "OPENBLAS_NUM_THREADS": "1"},
    )  # fmt: skip
    if case.expect != "error" and proc.returncode in (0, 1, 3):
        assert (out / "r.json").exists() and "Traceback" not in proc.stderr
        return
    assert proc.returncode == 2, proc.stderr[-400:]
    assert one_line_error(proc.stderr, str(path)) is None, proc.stderr
    assert proc.stdout == ""
    assert list(out.iterdir()) == []
