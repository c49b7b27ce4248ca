"""Every path handed to another program is a path, never an option (issue 27).

``fst2vcd -fother.fst`` is ``fst2vcd -f other.fst``: before the fix, ``wavecheck check --
-fother.fst`` reported the content of ``other.fst`` under the name ``-fother.fst``. Each
subprocess that takes a capture's path is run here on a file whose name starts with ``-``,
next to the file that name would mean as options, and must read the file named.
"""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import pytest

from tests.conftest import write_vcd
from wavecheck.capture.common import path_argument
from wavecheck.capture.open import open_capture
from wavecheck.capture.sigrokcli import convert, read_with_sigrok


@pytest.mark.parametrize(
    ("given", "passed"),
    [("-fother.fst", "./-fother.fst"), ("a/-b.sr", "a/-b.sr"), ("/t/-x", "/t/-x"), ("x", "x")],
)
def test_path_argument(given: str, passed: str) -> None:
    assert path_argument(given) == passed


def _edges(path: Path, **kw: str) -> list[tuple[str, int]]:
    cap = open_capture(path, **kw)  # type: ignore[arg-type]
    return [(c.name.rsplit(".", 1)[-1], len(c.edges)) for c in cap.channels]


@pytest.mark.skipif(
    not (shutil.which("vcd2fst") and shutil.which("fst2vcd")), reason="needs gtkwave"
)
def test_fst2vcd_reads_the_file_named(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    one = write_vcd(tmp_path / "one.vcd", {"step": (0, [10, 20, 30, 40])}, end=50)
    two = write_vcd(tmp_path / "two.vcd", {"step": (0, [10, 20]), "dir": (0, [5])}, end=50)
    for vcd, fst in ((one, "-fother.fst"), (two, "other.fst")):
        subprocess.run(["vcd2fst", str(vcd), str(tmp_path / fst)], check=True, capture_output=True)
    monkeypatch.chdir(tmp_path)
    assert _edges(Path("-fother.fst")) == [("step", 4)]
    assert _edges(Path("other.fst")) == [("step", 2), ("dir", 1)]


@pytest.mark.skipif(shutil.which("sigrok-cli") is None, reason="needs sigrok-cli")
def test_sigrok_cli_reads_the_file_named(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """sigrok-cli's ``-i`` and ``-o`` values: a CSV named ``-ochanged.csv`` (sigrok-cli's
    ``-o changed.csv`` as options) converted to a ``.sr`` named ``-i.sr``."""
    monkeypatch.chdir(tmp_path)
    Path("-ochanged.csv").write_text("a,b\n0,1\n1,1\n0,0\n1,0\n")
    cap = read_with_sigrok("-ochanged.csv", "csv:header=yes", samplerate=1000000)  # type: ignore[arg-type]
    assert [len(c.edges) for c in cap.channels] == [3, 1]
    convert("-ochanged.csv", "-i.sr", input_format="csv:header=yes:samplerate=1000000")
    assert Path("-i.sr").stat().st_size > 0 and not Path("changed.csv").exists()
    assert [len(c.edges) for c in open_capture("-i.sr").channels] == [3, 1]


@pytest.mark.skipif(
    not (shutil.which("vcd2fst") and shutil.which("fst2vcd")), reason="needs gtkwave"
)
def test_a_cut_short_fst_does_not_hang_fst2vcd(tmp_path: Path) -> None:
    """GTKWave 3.3's fst2vcd loops forever, writing nothing, on an FST cut short by one byte
    (issue 27's fuzz run). The native reader refuses it at once (one line naming the byte,
    exit 2); fst2vcd, still used for FastLZ-packed files, is stopped after
    FST2VCD_STALL_SECONDS."""
    import sys

    from tests.bounds import HANG_GUARD_S
    from tests.reliability.seeds import fst_seeds
    from wavecheck.capture.wellen import FST2VCD_STALL_SECONDS, FstBlocks
    from wavecheck.errors import CaptureError

    seed = fst_seeds()[0]
    cut = tmp_path / "cut.fst"
    cut.write_bytes(seed[:-1])
    proc = subprocess.run(
        [sys.executable, "-m", "wavecheck", "info", str(cut)],
        capture_output=True, text=True, timeout=HANG_GUARD_S, cwd=tmp_path,
    )  # fmt: skip
    assert proc.returncode == 2 and proc.stderr.count("\n") == 1, proc.stderr
    assert f"{cut}: byte " in proc.stderr and "cut off" in proc.stderr
    # the timeout guards against a hang; the stall watchdog's own message says that it fired
    stalled = f"fst2vcd gave nothing for {FST2VCD_STALL_SECONDS:g} s"
    with pytest.raises(CaptureError, match=stalled):
        list(FstBlocks(cut, str(shutil.which("fst2vcd"))).blocks())
