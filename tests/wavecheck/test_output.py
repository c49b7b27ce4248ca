"""Outputs are written whole or not at all, with the mode a plain open() would give."""

import os
import stat
from pathlib import Path

import pytest

from wavecheck.errors import UsageError
from wavecheck.output import atomic_path, atomic_write


def test_atomic_write_creates_file_with_umask_mode(tmp_path: Path) -> None:
    target = tmp_path / "report.json"
    old = os.umask(0o022)
    try:
        atomic_write(target, "{}")
    finally:
        os.umask(old)
    assert target.read_text() == "{}"
    assert stat.S_IMODE(target.stat().st_mode) == 0o644


def test_failure_leaves_nothing(tmp_path: Path) -> None:
    target = tmp_path / "out.vcd"
    with pytest.raises(RuntimeError), atomic_path(target) as tmp:
        tmp.write_text("half a file")
        raise RuntimeError("simulated failure mid-write")
    assert list(tmp_path.iterdir()) == []


def test_failure_keeps_previous_output(tmp_path: Path) -> None:
    target = tmp_path / "out.txt"
    target.write_text("old")
    with pytest.raises(RuntimeError), atomic_path(target) as tmp:
        tmp.write_text("new, unfinished")
        raise RuntimeError("boom")
    assert target.read_text() == "old"


def test_missing_folder_is_a_usage_error(tmp_path: Path) -> None:
    with pytest.raises(UsageError, match="does not exist"):
        atomic_write(tmp_path / "nope" / "x.txt", "x")
