"""Shared test fixtures: the real captures in ../shared/captures and small VCD builders."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest
from hypothesis import settings

from wavecheck.capture.vcd.writer import VcdWire
from wavecheck.capture.vcd.writer import write_vcd as write_vcd_file

# No per-example deadline: a loaded 2-core CI machine must not turn a slow example into a failure.
# In CI (CI=true) the examples are derandomised, so the gate is repeatable; local runs explore.
settings.register_profile("wavecheck", deadline=None, derandomize=os.environ.get("CI") == "true")
settings.load_profile("wavecheck")

REPO = Path(__file__).resolve().parent.parent
SHARED_CAPTURES = REPO.parent / "shared" / "captures"


def shared_capture(relpath: str) -> Path:
    """Path of a real capture under ../shared/captures; skip locally, fail in CI, when missing."""
    path = SHARED_CAPTURES / relpath
    if not path.exists():
        if os.environ.get("CI") == "true":
            pytest.fail(f"shared capture missing in CI: {path}")
        pytest.skip(f"shared capture not present: {path}")
    return path


@pytest.fixture
def grbl_sr() -> Path:
    return shared_capture("sigrok-dumps/stepper_motor/grbl_cnc/grbl_cnc_1.sr")


@pytest.fixture
def smoothie_sr() -> Path:
    return shared_capture("sigrok-dumps/stepper_motor/smoothieware/smoothieware_snippet.sr")


@pytest.fixture
def smoothie_no_rate_sr() -> Path:
    return shared_capture(
        "sigrok-dumps/stepper_motor/smoothieware/smoothieware_snippet_no_samplerate.sr"
    )


def write_vcd(
    path: Path,
    signals: dict[str, tuple[int, list[int]]],
    timescale: str = "1 ns",
    end: int | None = None,
) -> Path:
    """Write a small simulator-style VCD: ``signals`` maps name → (initial level, edge times).

    Each edge toggles the level. ``end`` adds a final timestamp (default: last edge + 1).
    Written by the project's one VCD writer (:func:`wavecheck.capture.vcd.writer.write_vcd`).
    """
    wires = [
        VcdWire(name, init, np.asarray(edges, dtype=np.int64))
        for name, (init, edges) in signals.items()
    ]
    last = max((max(edges) for _, edges in signals.values() if edges), default=0)
    write_vcd_file(
        path, wires, timescale=timescale, end=end if end is not None else last + 1, scope="top"
    )
    return path
