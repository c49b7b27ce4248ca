"""The one VCD writer: exact text, round trip through both readers, refusals, progress."""

from __future__ import annotations

from collections import Counter
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from wavecheck.capture.vcd import read_vcd, read_vcd_reference
from wavecheck.capture.vcd.writer import VcdVector, VcdWire, write_vcd
from wavecheck.progress import _ACTIVE


def _a(*xs: int) -> np.ndarray:
    return np.array(xs, dtype=np.int64)


def test_exact_text(tmp_path: Path) -> None:
    path = tmp_path / "a.vcd"
    n = write_vcd(
        path,
        [VcdWire("step", 0, _a(0, 5, 5, 9)), VcdWire("dir", 1, _a(5))],
        vectors=[VcdVector("counts", _a(5, 9), _a(3, 4), size=8)],
        timescale="10 ns",
        end=12,
        scope="top",
        comment="made by a test",
        version="v1",
    )
    assert n == 7
    assert path.read_text() == (
        "$comment made by a test $end\n"
        "$timescale 10 ns $end\n"
        "$version v1 $end\n"
        "$scope module top $end\n"
        "$var wire 1 ! step $end\n"
        '$var wire 1 " dir $end\n'
        "$var integer 8 # counts $end\n"
        "$upscope $end\n"
        "$enddefinitions $end\n"
        "#0\n"
        "$dumpvars\n"
        "1!\n"  # the edge at 0 replaces the initial level
        '1"\n'
        "b0 #\n"
        "$end\n"
        "#5\n"
        "0!\n"
        "1!\n"
        '0"\n'
        "b11 #\n"
        "#9\n"
        "0!\n"
        "b100 #\n"
        "#12\n"
    )


def _expected(initial: int, edges: list[int]) -> tuple[int, list[int]]:
    """Initial level and edges a reader must see: an odd number of toggles at a time changes
    the level (the last change at a time wins); toggles at 0 change the initial level."""
    counts = Counter(edges)
    level = initial ^ (counts.pop(0, 0) & 1)
    return level, sorted(t for t, c in counts.items() if c % 2)


wire = st.tuples(st.integers(0, 1), st.lists(st.integers(0, 60), max_size=12).map(sorted))


@settings(max_examples=60)
@given(wires=st.lists(wire, min_size=1, max_size=4), tail=st.integers(0, 5))
def test_round_trip_through_both_readers(
    tmp_path_factory: pytest.TempPathFactory, wires: list[tuple[int, list[int]]], tail: int
) -> None:
    path = tmp_path_factory.mktemp("w") / "r.vcd"
    end = max((e[-1] for _, e in wires if e), default=0) + tail
    write_vcd(
        path,
        [VcdWire(f"s{i}", init, np.array(e, dtype=np.int64)) for i, (init, e) in enumerate(wires)],
        timescale="1 us",
        end=end,
        scope="x",
    )
    for cap in (read_vcd(path, chunk_bytes=7), read_vcd_reference(path)):
        assert cap.end == end
        for i, (init, e) in enumerate(wires):
            ch = cap.channel(f"s{i}")
            assert (ch.initial, ch.edges.tolist()) == _expected(init, e)


@pytest.mark.parametrize(
    ("wires", "end", "match"),
    [
        ([VcdWire("a", 0, _a(5, 3))], 10, "go backwards"),
        ([VcdWire("a", 0, _a(5, 30))], 10, "outside 0 … end 10"),
        ([VcdWire("a", 0, _a(-1, 3))], 10, "outside"),
    ],
)
def test_refusals_write_nothing(tmp_path: Path, wires: list[VcdWire], end: int, match: str) -> None:
    path = tmp_path / "bad.vcd"
    with pytest.raises(ValueError, match=match):
        write_vcd(path, wires, timescale="1 ns", end=end, scope="t")
    assert not path.exists()


def test_vector_value_too_wide_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "bad.vcd"
    with pytest.raises(ValueError):
        write_vcd(
            path, [], vectors=[VcdVector("c", _a(1), _a(300), size=8)], timescale="1 ns", end=2,
            scope="t",
        )  # fmt: skip
    assert not path.exists()


def test_progress_counts_value_changes(tmp_path: Path) -> None:
    seen: list[tuple[int, int | None]] = []
    token = _ACTIVE.set(lambda done, total=None: seen.append((done, total)))
    try:
        edges = np.arange(1, 200_001, dtype=np.int64)
        n = write_vcd(tmp_path / "p.vcd", [VcdWire("a", 0, edges)], timescale="1 ns",
                      end=200_001, scope="t")  # fmt: skip
    finally:
        _ACTIVE.reset(token)
    assert n == 200_000
    assert seen[-1] == (n, n) and len(seen) == 4
    assert [d for d, _ in seen] == sorted(d for d, _ in seen)
