"""Shared test fixtures: the real captures in ../shared/captures and small VCD builders."""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from hypothesis import settings

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
    """
    ids = {name: chr(33 + i) for i, name in enumerate(signals)}
    lines = [f"$timescale {timescale} $end", "$scope module top $end"]
    lines += [f"$var wire 1 {ids[n]} {n} $end" for n in signals]
    lines += ["$upscope $end", "$enddefinitions $end", "#0", "$dumpvars"]
    lines += [f"{init}{ids[n]}" for n, (init, _) in signals.items()]
    lines.append("$end")
    events: dict[int, list[str]] = {}
    for n, (init, edges) in signals.items():
        level = init
        for t in edges:
            level ^= 1
            events.setdefault(t, []).append(f"{level}{ids[n]}")
    last = 0
    for t in sorted(events):
        if t != 0:
            lines.append(f"#{t}")
        lines += events[t]
        last = t
    lines.append(f"#{end if end is not None else last + 1}")
    path.write_text("\n".join(lines) + "\n")
    return path
