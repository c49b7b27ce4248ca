"""The one VCD writer: exact text, round trip through both readers, refusals, progress."""

from __future__ import annotations

import io
import subprocess
import sys
from collections import Counter
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from wavecheck.capture.vcd import read_vcd, read_vcd_reference, writer
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


# The numpy path (``_write_fast``) against pyvcd (``_write_pyvcd``, the reference): the same
# bytes for the same changes.


def _both_paths(
    wires: list[VcdWire],
    vectors: list[VcdVector],
    timescale: str,
    end: int,
    comment: str = "",
    version: str = "",
    scope: str = "stepgen",
) -> tuple[bytes, bytes]:
    outs = []
    for fast in (False, True):
        fh = io.TextIOWrapper(io.BytesIO(), encoding="utf-8", newline="\n")
        if fast:
            writer._write_fast(fh, wires, vectors, timescale, end, scope, comment, version)
        else:
            t, v, x = writer._changes(wires, vectors)
            writer._write_pyvcd(
                fh, wires, vectors, t, v, x, timescale, end, scope, comment, version
            )
        fh.flush()
        outs.append(fh.buffer.getvalue())  # type: ignore[attr-defined]
    return outs[0], outs[1]


_TIMES = (
    st.integers(0, 40) | st.integers(0, 10**12) | st.sampled_from([10**8 - 1, 10**8, 10**16, 2**62])
)


@st.composite
def _signals(draw: st.DrawFn) -> tuple[list[VcdWire], list[VcdVector], str, int, int]:
    """Random edge sets (several edges at one time, edges at 0, times of any length) and
    vectors like stepgen's ``counts`` (repeats, negatives, the extremes of their size)."""
    wires = [
        VcdWire(f"w{i}", draw(st.integers(0, 1)), np.sort(np.array(draw(st.lists(_TIMES, max_size=30)), dtype=np.int64)))
        for i in range(draw(st.integers(0, 4)))
    ]  # fmt: skip
    vectors = []
    for i in range(draw(st.integers(0 if wires else 1, 2))):
        size = draw(st.sampled_from([2, 3, 8, 32, 62]))
        lo, hi = -(1 << (size - 1)), (1 << size) - 1
        values = st.integers(lo, hi) | st.sampled_from([0, 1, lo, hi])
        times = np.sort(np.array(draw(st.lists(_TIMES, max_size=30)), dtype=np.int64))
        vals = np.array([draw(values) for _ in times], dtype=np.int64)
        kind = draw(st.sampled_from(sorted(writer._VECTOR_TYPES)))
        vectors.append(
            VcdVector(f"v{i}", times, vals, size=size, var_type=kind, initial=draw(values))
        )
    last = max([0] + [int(w.edges[-1]) for w in wires if len(w.edges)]
               + [int(vec.times[-1]) for vec in vectors if len(vec.times)])  # fmt: skip
    end = last + draw(st.sampled_from([0, 0, 1, 10**9]))
    return (
        wires,
        vectors,
        draw(st.sampled_from(["1 ns", "10 us", "100 ps", "1 s", "1ns", "ms", "010 fs", "1000 ns"])),
        end,
        draw(st.integers(1, 7)),
    )


@settings(max_examples=300, deadline=None)
@given(case=_signals())
def test_fast_path_writes_the_bytes_pyvcd_writes(
    case: tuple[list[VcdWire], list[VcdVector], str, int, int],
) -> None:
    wires, vectors, timescale, end, block = case
    assert writer._fast_covers(wires, vectors)
    with pytest.MonkeyPatch.context() as m:
        m.setattr(writer, "_FAST_BLOCK", block)  # block boundaries inside one timestamp too
        ref, fast = _both_paths(wires, vectors, timescale, end, comment="c")
    assert fast == ref


@settings(max_examples=60, deadline=None)
@given(
    case=_signals(),
    comment=st.sampled_from(["", "one line", "two\nlines", "tab\there"]),
    version=st.sampled_from(["", "v 1.0", "a\nb"]),
    scope=st.sampled_from(["stepgen", "top module", "a.b", ""]),
)
def test_header_is_the_one_pyvcd_writes(
    case: tuple[list[VcdWire], list[VcdVector], str, int, int],
    comment: str,
    version: str,
    scope: str,
) -> None:
    """The header the writer makes itself (pyvcd is not imported for it) and the ones it leaves
    to pyvcd (a nested or empty scope, a timescale it does not know) are pyvcd's bytes."""
    wires, vectors, timescale, end, _ = case
    ref, fast = _both_paths(wires, vectors, timescale, end, comment, version, scope)
    assert fast == ref


@pytest.mark.parametrize("number", [1, 2, 94, 95, 96, 94 * 95, 94 * 95 + 1, 10**6])
def test_id_codes_are_pyvcds(number: int) -> None:
    from vcd.writer import _encode_identifier

    assert writer._ident(number) == _encode_identifier(number)


def test_a_plain_vcd_is_written_without_pyvcd(tmp_path: Path) -> None:
    """pyvcd (~6 ms to import) is loaded only for a header outside the plain cases."""
    code = (
        "import sys, numpy as np\n"
        "from wavecheck.capture.vcd.writer import VcdVector, VcdWire, write_vcd\n"
        "w = [VcdWire('step', 0, np.arange(1, 9)), VcdWire('dir', 1, np.arange(0, 9, 4))]\n"
        "v = [VcdVector('counts', np.arange(0, 9, 2), np.arange(-2, 3), size=32)]\n"
        f"write_vcd({str(tmp_path / 'a.vcd')!r}, w, vectors=v, timescale='1 ns', end=9,"
        " scope='stepgen', comment='c')\n"
        "print('vcd' in sys.modules)\n"
    )
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert run.stdout.split() == ["False"]


def test_fast_path_on_a_stepgen_like_trace() -> None:
    """Thousands of changes, 11-digit timestamps, a 32-bit counter going up and down."""
    rng = np.random.default_rng(7)
    step = np.cumsum(rng.integers(1, 50_000, 4000)).astype(np.int64) + 10**10
    dirs = np.sort(rng.choice(step, 40, replace=False)) - 3
    counts_t = np.sort(np.concatenate([step, step[::7]]))
    counts = np.cumsum(rng.choice([-1, 1], len(counts_t))).astype(np.int64)
    wires = [VcdWire("step", 0, step), VcdWire("dir", 0, dirs)]
    vectors = [VcdVector("counts", counts_t, counts, size=32)]
    ref, fast = _both_paths(wires, vectors, "1 ns", int(step[-1]) + 1)
    assert fast == ref and len(ref) > 50_000


@pytest.mark.parametrize(
    ("wires", "vectors"),
    [
        ([VcdWire("a", 2, _a(1))], []),  # a level that is not 0/1
        ([], [VcdVector("c", _a(1), _a(1), size=64)]),  # wider than 62 bits
        ([], [VcdVector("c", _a(1), _a(1), size=1)]),  # pyvcd writes it as a scalar
        ([], [VcdVector("c", _a(1), _a(300), size=8)]),  # does not fit: pyvcd raises
        ([], [VcdVector("r", _a(1), _a(1), size=64, var_type="real")]),
        ([VcdWire(f"w{i}", 0, _a(1)) for i in range(300)], []),  # many variables
        ([], []),
    ],
)
def test_fast_path_leaves_the_rest_to_pyvcd(wires: list[VcdWire], vectors: list[VcdVector]) -> None:
    assert not writer._fast_covers(wires, vectors)
