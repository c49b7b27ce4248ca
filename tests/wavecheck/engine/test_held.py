"""Memory follows the window, not the capture (issue 23): what an axis holds between windows is
bounded however long a line stays unchanged. An ENABLE that rose once, or a DIR that never
changes again, once held every edge after it (a 16 G-sample capture with ENABLE mapped: 550 MB)."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.conftest import write_vcd
from wavecheck.capture.open import open_source
from wavecheck.drives.library import load_drive
from wavecheck.engine.options import CheckOptions
from wavecheck.engine.run import start
from wavecheck.steps.mapping import AxisMap

BLOCK = 64  # edges a window


def _capture(tmp: Path, lines: dict[str, tuple[int, list[int]]]) -> Path:
    """20,000 steps of 2 µs every 10 µs after 1 ms, with ``lines`` beside them."""
    step = [t for k in range(20_000) for t in (1_000_000 + 10_000 * k, 1_002_000 + 10_000 * k)]
    return write_vcd(tmp / "c.vcd", {"step": (0, step), **lines})


@pytest.mark.parametrize(
    "lines",
    [
        {"dir": (0, [500_000]), "en": (0, [100_000])},  # each changed once, before the steps
        {"dir": (0, []), "en": (1, [])},  # never changed
        {"dir": (0, [500_000, 150_000_000]), "en": (0, [100_000, 120_000_000, 120_500_000])},
    ],
    ids=["changed-once", "never-changed", "changed-mid-run"],
)
def test_an_axis_holds_a_bounded_context(tmp_path: Path, lines: dict) -> None:
    path = _capture(tmp_path, lines)
    mapping = {"step": "step", "dir": "dir", "enable": "en"}
    options = CheckOptions(
        drive={None: load_drive("gecko-g202")}, axes=(AxisMap(None, mapping),), block_edges=BLOCK,
        pulse_level=1,
    )  # fmt: skip
    machine, blocks = start(open_source(path, chunk_bytes=512), options)
    axis = machine.axes[0]
    most = 0
    windows = 0
    for block in blocks:
        machine.feed(block)
        most = max(most, axis.held)
        windows += 1
    report = machine.finish(open_source(path).skeleton)
    assert windows > 100  # many windows: the context was carried over many times
    assert report.axes[0].steps.count == 20_000
    assert most <= 4 * BLOCK  # held back: a few edges of context, not the capture
