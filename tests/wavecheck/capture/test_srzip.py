"""The one .sr writer: member layout, metadata, edges → samples, read back by the reader."""

from __future__ import annotations

import io
import zipfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tests.wavecheck.capture.srutil import edges_by_unpacking
from wavecheck.capture.sr import read_sr
from wavecheck.capture.srzip import (
    rate_text,
    samples_from_edges,
    sr_metadata,
    write_sr,
    write_sr_edges,
)


def test_metadata_text() -> None:
    assert sr_metadata(["STEP", "DIR"], samplerate=12_000_000) == (
        "[global]\nsigrok version=0.5.2\n\n[device 1]\ncapturefile=logic-1\ntotal probes=2\n"
        "samplerate=12 MHz\ntotal analog=0\nprobe1=STEP\nprobe2=DIR\nunitsize=1\n"
    )
    text = sr_metadata({0: "A", 9: "J"}, samplerate=None, total_probes=12, total_analog=None)
    assert "samplerate" not in text and "total analog" not in text
    assert "probe1=A\nprobe10=J\nunitsize=2\n" in text


@pytest.mark.parametrize(
    ("hz", "text"),
    [
        (10**9, "1 GHz"),
        (20_000_000, "20 MHz"),
        (125_000, "125 kHz"),
        (1_500, "1500 Hz"),
        (3, "3 Hz"),
    ],
)
def test_rate_text(hz: int, text: str) -> None:
    assert rate_text(hz) == text


def test_members_are_cut_in_chunks(tmp_path: Path) -> None:
    raw = bytes(range(256)) * 10  # 2560 bytes
    path = tmp_path / "a.sr"
    assert (
        write_sr(path, raw, metadata=sr_metadata(["a"], samplerate=1000), chunk_bytes=1000) == 2560
    )
    with zipfile.ZipFile(path) as z:
        infos = z.infolist()
        assert [i.filename for i in infos] == [
            "version", "metadata", "logic-1-1", "logic-1-2", "logic-1-3"
        ]  # fmt: skip
        assert z.read("version") == b"2" and infos[0].compress_type == zipfile.ZIP_STORED
        assert [len(z.read(f"logic-1-{k}")) for k in (1, 2, 3)] == [1000, 1000, 560]
        assert b"".join(z.read(f"logic-1-{k}") for k in (1, 2, 3)) == raw
        assert all(i.compress_type == zipfile.ZIP_DEFLATED for i in infos[1:])


def test_pieces_file_object_and_reproducible_bytes(tmp_path: Path) -> None:
    meta = sr_metadata(["a", "b"], samplerate=1_000_000)
    pieces = [bytes([0, 1, 3]), bytes([2, 2])]
    buf = io.BytesIO()
    write_sr(buf, iter(pieces), metadata=meta)
    with zipfile.ZipFile(io.BytesIO(buf.getvalue())) as z:
        assert z.read("logic-1-1") == pieces[0] and z.read("logic-1-2") == pieces[1]
    write_sr(tmp_path / "b.sr", iter(pieces), metadata=meta)
    assert (tmp_path / "b.sr").read_bytes() == buf.getvalue()  # no timestamps in the zip
    cap = read_sr(tmp_path / "b.sr")
    assert cap.channel("a").edges.tolist() == [1, 3] and cap.channel("b").edges.tolist() == [2]


@settings(max_examples=40)
@given(
    nch=st.integers(1, 20),
    n=st.integers(1, 300),
    data=st.data(),
)
def test_samples_from_edges_matches_unpacking(nch: int, n: int, data: st.DataObject) -> None:
    initial = data.draw(st.lists(st.integers(0, 1), min_size=nch, max_size=nch))
    edges = [sorted(data.draw(st.lists(st.integers(0, n - 1), max_size=8))) for _ in range(nch)]
    raw = samples_from_edges([np.array(e, dtype=np.int64) for e in edges], initial, n).tobytes()
    unit = (nch + 7) // 8
    assert len(raw) == n * unit
    for bit, (init, e) in enumerate(zip(initial, edges, strict=True)):
        # an odd number of toggles at a sample changes the level there; at 0, the first sample
        odd = sorted(t for t in set(e) if e.count(t) % 2)
        first = init ^ (1 if 0 in odd else 0)
        assert edges_by_unpacking(raw, unit, bit) == (first, [t for t in odd if t > 0])


def test_edges_round_trip_through_the_reader(tmp_path: Path) -> None:
    path = tmp_path / "e.sr"
    edges = [np.array([3, 10, 11], dtype=np.int64), np.array([7], dtype=np.int64)]
    write_sr_edges(path, ["STEP", "DIR"], edges, [0, 1], 20, samplerate=2_000_000, chunk_bytes=6)
    cap = read_sr(path)
    assert cap.samplerate_hz == 2_000_000 and cap.end == 20
    assert (cap.channel("STEP").initial, cap.channel("STEP").edges.tolist()) == (0, [3, 10, 11])
    assert (cap.channel("DIR").initial, cap.channel("DIR").edges.tolist()) == (1, [7])
    with zipfile.ZipFile(path) as z:
        assert len([n for n in z.namelist() if n.startswith("logic-1-")]) == 4  # 20 bytes / 6


@pytest.mark.parametrize(
    ("edges", "n", "match"),
    [([np.array([5])], 5, "must lie in 0 … 4"), ([np.array([-1])], 5, "must lie")],
)
def test_edges_outside_the_samples_are_refused(edges: list[np.ndarray], n: int, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        samples_from_edges(edges, [0], n)


def test_wide_samples(tmp_path: Path) -> None:
    """17 channels: 3 bytes a sample, channel 16 in the third byte."""
    edges = [np.zeros(0, dtype=np.int64)] * 16 + [np.array([2], dtype=np.int64)]
    raw = samples_from_edges(edges, [1] + [0] * 16, 4)
    assert raw.tolist() == [1, 0, 0, 1, 0, 0, 1, 0, 1, 1, 0, 1]
