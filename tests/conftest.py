"""Shared test fixtures: the real captures in ../shared/captures and small VCD builders."""

from __future__ import annotations

import os
import re
from collections import Counter
from pathlib import Path
from typing import Any

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
SHARED = REPO.parent / "shared"
SHARED_CAPTURES = SHARED / "captures"


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


#: Tests left out of ``make test`` (``-m "not slow"``), by node id or its start, and why: the
#: slow real corpora, sweeps and block-size matrices (seconds summed over an --durations run of
#: the whole suite, -n 2 on a loaded 2-core machine). ``make test-all`` and .ci/run run them; the
#: tests marked ``slow`` in their own files (the lattice sweep, the wheel install, cocotb, the
#: pages' commands from a clone, PulseView) are left out the same way.
SLOW = {
    "tests/wavecheck/engine/test_block_readers.py::test_sr_blocks":
        "the real grbl .sr read at three block sizes (365 s)",
    "tests/wavecheck/capture/test_block_sources.py::test_a_block_source_gives_the_whole_reads_capture[vcd through sigrok-cli":
        "sigrok-cli's conversion at three block sizes (244 s)",
    "tests/wavecheck/engine/test_windows.py::test_windows_stay_bounded_when_every_interval_fails[1]":
        "one edge per block over every failing interval (226 s)",
    "tests/architecture/test_layering.py::test_every_module_imports_alone_in_a_fresh_interpreter":
        "an interpreter per module (200 s)",
    "tests/wavecheck/engine/test_block_matrix.py::test_one_block_or_many":
        "116 options x block sizes against one block (177 s)",
    "tests/reliability/test_fuzz_run.py::test_bounded_fuzz_in_a_child":
        "a forked child per fuzz case (99 s)",
    "tests/wavecheck/engine/test_trace.py::test_real_captures[1]":
        "the real captures one edge per block (87 s)",
    "tests/wavecheck/lattice/test_analysis.py::test_every_model_every_rate_period_exact_lateness_within_a_sample":
        "every latency model x rate x period (33 s)",
    "tests/wavecheck/report/test_figure_files.py::test_the_file_name_says_the_format":
        "every figure format rendered (78 s)",
    "tests/wavecheck/engine/test_windows.py::test_cli_streams_plot_gtkw_and_html":
        "every picture of a long capture, streamed (59 s)",
    "tests/reliability/test_fuzz_run.py::test_bounded_fuzz[":
        "300 mutants of each in-process reader (46 s)",
    "tests/wavecheck/sigrok/test_sigrok_cli.py::test_golden_captures":
        "sigrok-cli's run of the decoder on every golden trace (42 s)",
    "tests/wavecheck/firmware/test_fuzz_firmware.py::test_bounded_fuzz":
        "200 mutants of each firmware format (37 s)",
    "tests/wavecheck/engine/test_trace.py::test_cli_streamed_png_has_the_panel":
        "a long capture's motion panel, streamed (35 s)",
    "tests/reliability/test_malformed_sr.py::test_fuzz_metadata_values":
        "fuzzed .sr metadata (26 s)",
    "tests/wavecheck/firmware/test_fixes_work.py::test_every_printed_fix_works":
        "every printed fix applied to every corpus file and re-run (3-8 min)",
}  # fmt: skip


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """Mark the tests of :data:`SLOW` slow."""
    for item in items:
        if any(item.nodeid.startswith(start) for start in SLOW):
            item.add_marker(pytest.mark.slow)


#: Path-like words in a skip reason (a file that is missing), left out when reasons are grouped.
_PATHISH = re.compile(r"\S*/\S*")


def _why(report: pytest.TestReport) -> str:
    """A skip's reason, without the paths that would make every missing file a reason of its own."""
    longrepr = report.longrepr
    text = longrepr[2] if isinstance(longrepr, tuple) else str(longrepr)
    text = text.removeprefix("Skipped: ")
    text = _PATHISH.sub("…", text).strip()
    return text if len(text) <= 100 else text[:99] + "…"


#: How many tests the xdist workers deselected (each collects the whole run: the largest count).
_WORKERS_DESELECTED = pytest.StashKey[int]()


def pytest_deselected(items: list[pytest.Item]) -> None:
    """In an xdist worker, count what ``-m`` left out for the controller's last line."""
    if items and hasattr(items[0].config, "workeroutput"):
        output = items[0].config.workeroutput  # type: ignore[attr-defined]
        output["deselected"] = output.get("deselected", 0) + len(items)


@pytest.hookimpl(optionalhook=True)
def pytest_testnodedown(node: Any, error: Any) -> None:
    """In the xdist controller: keep the workers' count of deselected tests."""
    count = getattr(node, "workeroutput", {}).get("deselected", 0)
    stash = node.config.stash
    stash[_WORKERS_DESELECTED] = max(stash.get(_WORKERS_DESELECTED, 0), count)


def pytest_unconfigure(config: pytest.Config) -> None:
    """The run's last line: what did not run, and why (issue 37)."""
    terminalreporter = config.pluginmanager.get_plugin("terminalreporter")
    if terminalreporter is None or hasattr(config, "workerinput"):  # an xdist worker says nothing
        return
    stats = terminalreporter.stats
    skipped = [r for r in stats.get("skipped", []) if getattr(r, "longrepr", None) is not None]
    deselected = len(stats.get("deselected", [])) or config.stash.get(_WORKERS_DESELECTED, 0)
    parts = []
    if deselected:
        expr = config.getoption("markexpr") or ""
        how = f'-m "{expr}": make test-all (.ci/run) runs them' if expr else "deselected"
        parts.append(f"{deselected} deselected ({how})")
    if skipped:
        reasons = Counter(_why(r) for r in skipped).most_common()
        shown = "; ".join(f"{n} {why}" for why, n in reasons[:4])
        more = (
            f"; {sum(n for _, n in reasons[4:])} for {len(reasons) - 4} other reasons"
            if len(reasons) > 4
            else ""
        )
        parts.append(f"{len(skipped)} skipped: {shown}{more}")
    terminalreporter.write_line("not run: " + (" | ".join(parts) if parts else "nothing"))
