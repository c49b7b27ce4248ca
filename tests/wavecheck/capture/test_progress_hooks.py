"""Readers report how far they are through wavecheck.progress (the CLI draws the bar)."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.conftest import write_vcd
from wavecheck.capture.sr import read_sr
from wavecheck.capture.vcd import read_vcd
from wavecheck.progress import _ACTIVE


@pytest.fixture
def reports() -> list[tuple[int, int | None]]:
    seen: list[tuple[int, int | None]] = []
    token = _ACTIVE.set(lambda done, total=None: seen.append((done, total)))
    yield seen
    _ACTIVE.reset(token)


def test_vcd_reader_reports_bytes_up_to_the_file_size(
    tmp_path: Path, reports: list[tuple[int, int | None]]
) -> None:
    edges = list(range(10, 20_000, 10))
    path = write_vcd(tmp_path / "a.vcd", {"step": (0, edges), "dir": (0, [5, 9_995])})
    reports.clear()  # the writer's own progress (value changes) is not under test
    read_vcd(path, chunk_bytes=1024)
    size = path.stat().st_size
    assert len(reports) > 10
    assert all(total == size for _, total in reports)
    done = [d for d, _ in reports]
    assert done == sorted(done) and done[-1] <= size


def test_sr_reader_reports_samples_bytes_to_the_total(
    smoothie_sr: Path, reports: list[tuple[int, int | None]]
) -> None:
    read_sr(smoothie_sr, chunk_bytes=1 << 16)
    assert reports, "no progress reported"
    total = reports[-1][1]
    assert total is not None and reports[-1][0] == total
    assert [d for d, _ in reports] == sorted(d for d, _ in reports)
