"""Hostile files cost bounded time and memory (issue 12): each shape runs the real command in
its own process under a wall-clock timeout and an address-space limit (``RLIMIT_AS``).

The shapes: a ``.sr`` whose chunk numbers are far apart (``logic-1-1`` and
``logic-1-100000000000``: a reader listing the missing numbers allocated 14 GB), a ``.sr`` whose
1,000 directory entries share one deflate stream (inflated 1,000 times: minutes), a VCD with
200,000 ``$var`` lines (line numbers recounted from the start: quadratic, 80,000 took 42 s), one
with a million (over 60 s and 1 GB before issue 27: now refused at once, beyond
``MAX_VARS``), and a VCD body of 2 GB without whitespace (a sparse file: read whole, 8.2 GB).
"""

from __future__ import annotations

import os
import resource
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import pytest

from tests.bounds import HANG_GUARD_S
from tests.reliability.corpus import (
    one_line_error,
    sr_far_chunk,
    sr_overlapping_entries,
    vcd_many_vars,
    vcd_no_whitespace_body,
    vcd_text,
)

REPO = Path(__file__).resolve().parents[2]
#: Address space allowed to one run: the interpreter with numpy needs ~150 MiB.
MEMORY_LIMIT = 1 << 30


def run_bounded(
    argv: list[str], *, memory: int = MEMORY_LIMIT, stdin: Path | None = None
) -> subprocess.CompletedProcess[str]:
    """``python -m wavecheck *argv`` in a child limited to ``memory`` bytes of address space
    (the bound); a child still running after the hang guard (tests/bounds.py) fails the test."""

    def limit() -> None:
        resource.setrlimit(resource.RLIMIT_AS, (memory, memory))

    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1"}
    try:
        with open(stdin or os.devnull, "rb") as inp:
            proc = subprocess.run(
                [sys.executable, "-m", "wavecheck", *argv],
                stdin=inp,
                capture_output=True,
                text=True,
                timeout=HANG_GUARD_S,
                cwd=REPO,
                env=env,
                preexec_fn=limit,
                check=False,
            )
    except subprocess.TimeoutExpired:
        pytest.fail(f"wavecheck {' '.join(argv)} still running after {HANG_GUARD_S:g} s: a hang")
    return proc


def _far_chunk(path: Path) -> None:
    path.write_bytes(sr_far_chunk())


def _overlap(path: Path) -> None:
    path.write_bytes(sr_overlapping_entries())


def _many_vars(path: Path) -> None:
    path.write_bytes(vcd_many_vars(200_000))


def _million_vars(path: Path) -> None:
    path.write_bytes(vcd_many_vars(1_000_000))


def _no_whitespace(path: Path) -> None:
    head, size = vcd_no_whitespace_body()
    with open(path, "wb") as f:
        f.write(head)
        f.truncate(size)  # sparse: 2 GB of NUL bytes that take no disk


def _time_19_digits(path: Path) -> None:
    path.write_text(vcd_text().replace("#3000", "#9000000000000000000"))


# (name, suffix, builder, expected: "error" or "ok", text the result must contain); the
# 200,000 $var file is read (~9 s on a quiet machine; slow: tests/capture/vcd/test_reader.py
# holds the header parse linear by work counted), the others refused before the work
SHAPES = [
    ("sr-chunk-number-1e11", ".sr", _far_chunk, "error", "logic-1-2: is missing"),
    ("sr-1000-entries-one-stream", ".sr", _overlap, "error", "overlap"),
    ("vcd-200000-vars", ".vcd", _many_vars, "ok", "w199999"),
    ("vcd-1000000-vars", ".vcd", _million_vars, "error", "1,000,002 variables"),
    ("vcd-2GB-without-whitespace", ".vcd", _no_whitespace, "error", "byte "),
    ("vcd-19-digit-time", ".vcd", _time_19_digits, "ok", "9000000000000000000 ticks"),
]
#: Shapes a valid file of which is read whole: minutes' worth of the suite's time.
SLOW_SHAPES = {"vcd-200000-vars"}


@pytest.mark.parametrize(
    ("name", "suffix", "build", "expect", "says"),
    [
        pytest.param(*s, id=s[0], marks=[pytest.mark.slow] if s[0] in SLOW_SHAPES else [])
        for s in SHAPES
    ],
)
def test_hostile_shape_is_bounded(
    tmp_path: Path,
    name: str,
    suffix: str,
    build: Callable[[Path], None],
    expect: str,
    says: str,
) -> None:
    """``wavecheck info`` ends within 1 GiB of address space: a refusal is exit 2 with one line
    naming the file and the place; a valid file gives its channels."""
    path = tmp_path / f"{name}{suffix}"
    build(path)
    proc = run_bounded(["info", str(path)])
    assert "Traceback" not in proc.stderr and "MemoryError" not in proc.stderr, proc.stderr[-600:]
    if expect == "error":
        assert proc.returncode == 2, proc.stderr[-400:]
        assert one_line_error(proc.stderr, str(path)) is None, proc.stderr
        assert says in proc.stderr
    else:
        assert proc.returncode == 0, proc.stderr[-400:]
        assert says in proc.stdout


def test_hostile_sr_check_is_bounded(tmp_path: Path) -> None:
    """``check -o`` on the overlapping-entries bomb: refused within 1 GiB, no report left behind."""
    path = tmp_path / "bomb.sr"
    _overlap(path)
    out = tmp_path / "out"
    out.mkdir()
    proc = run_bounded(
        ["check", str(path), "--drive", "gecko-g202", "--map", "step=STEP,dir=DIR",
         "-o", str(out / "r.json")],
    )  # fmt: skip
    assert proc.returncode == 2, proc.stderr[-400:]
    assert one_line_error(proc.stderr, str(path)) is None, proc.stderr
    assert list(out.iterdir()) == []
