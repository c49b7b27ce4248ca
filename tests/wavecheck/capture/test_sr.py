"""Native .sr reader: real captures, chunk boundaries, metadata and corruption."""

from __future__ import annotations

import zipfile
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tests.wavecheck.capture.srutil import count_edges_by_members, edges_by_unpacking, write_sr
from wavecheck.capture.sr import read_sr
from wavecheck.errors import CaptureError


def test_grbl_channels_and_edges_match_independent_unpacking(grbl_sr: Path) -> None:
    cap = read_sr(grbl_sr)
    assert [c.name for c in cap.channels] == ["EN", "STEP (Y axis)", "TX", "RX"]
    assert cap.samplerate_hz == 2_000_000 and cap.resolution_ticks == 1
    initial, counts, samples = count_edges_by_members(grbl_sr)
    assert cap.end == samples
    assert [len(c.edges) for c in cap.channels] == counts[:4]
    assert [c.initial for c in cap.channels] == initial[:4]
    assert all(np.all(np.diff(c.edges) > 0) for c in cap.channels)


def test_smoothie(smoothie_sr: Path) -> None:
    cap = read_sr(smoothie_sr)
    assert cap.samplerate_hz == 12_000_000 and len(cap.channels) == 8
    assert len(cap.channel("3").edges) > 0


def test_no_samplerate_refused_unless_given(smoothie_no_rate_sr: Path, smoothie_sr: Path) -> None:
    with pytest.raises(CaptureError, match="no samplerate.*--samplerate"):
        read_sr(smoothie_no_rate_sr)
    cap = read_sr(smoothie_no_rate_sr, samplerate=Fraction(12_000_000))
    ref = read_sr(smoothie_sr)
    assert [c.edges.tolist() for c in cap.channels] == [c.edges.tolist() for c in ref.channels]


@pytest.mark.parametrize(
    ("text", "rate"),
    [
        ("12.5 MHz", Fraction(12_500_000)),
        ("1.234567 MHz", Fraction(1_234_567)),
        ("250 Hz", 250),
        ("1 GHz", 10**9),
        ("200 kHz", 200_000),
    ],
)
def test_samplerate_exact(tmp_path: Path, text: str, rate: Fraction) -> None:
    cap = read_sr(write_sr(tmp_path / "a.sr", bytes([0, 1, 0]), samplerate=text))
    assert cap.samplerate_hz == rate and cap.timebase.tick_s == 1 / Fraction(rate)


def _raw(rng: np.random.Generator, n: int, unitsize: int, p: float) -> bytes:
    flips = rng.random((n, unitsize * 8)) < p
    bits = np.cumsum(flips, axis=0) % 2
    return np.packbits(bits.astype(np.uint8), axis=1, bitorder="little").tobytes()


@pytest.mark.parametrize("unitsize", [1, 2, 3])
@pytest.mark.parametrize("chunk", [1, 2, 3, 7, 64, 1 << 20])
@pytest.mark.parametrize("member", [5, 7, 1 << 20])
def test_chunk_boundaries(tmp_path: Path, unitsize: int, chunk: int, member: int) -> None:
    rng = np.random.default_rng(unitsize * 1000 + chunk)
    raw = _raw(rng, 50, unitsize, 0.3)
    member -= member % unitsize
    path = write_sr(tmp_path / "a.sr", raw, total=unitsize * 8, unitsize=unitsize, chunk=member)
    cap = read_sr(path, chunk_bytes=chunk * unitsize)
    assert cap.end == 50
    for ch in cap.channels:
        init, edges = edges_by_unpacking(raw, unitsize, ch.index)
        assert (ch.initial, ch.edges.tolist()) == (init, edges)


@settings(max_examples=60, deadline=None)
@given(
    data=st.binary(min_size=1, max_size=80),
    chunk=st.integers(1, 9),
    member=st.integers(1, 12),
)
def test_random_waveforms(
    tmp_path_factory: pytest.TempPathFactory, data: bytes, chunk: int, member: int
) -> None:
    path = write_sr(tmp_path_factory.mktemp("h") / "r.sr", data, chunk=member)
    cap = read_sr(path, chunk_bytes=chunk)
    for ch in cap.channels:
        assert (ch.initial, ch.edges.tolist()) == edges_by_unpacking(data, 1, ch.index)


def test_disabled_probes_and_names(tmp_path: Path) -> None:
    path = write_sr(
        tmp_path / "a.sr", bytes([0, 0b1000, 0, 0b1000]), probes={0: "STEP", 3: "DIR X"}
    )
    cap = read_sr(path)
    assert [(c.name, c.index) for c in cap.channels] == [("STEP", 0), ("DIR X", 3)]
    assert cap.channel("DIR X").edges.tolist() == [1, 2, 3]
    assert any("disabled" in n for n in cap.notes)


def test_single_capturefile_member(tmp_path: Path) -> None:
    path = write_sr(tmp_path / "a.sr", b"", members={"logic-1": bytes([1, 0, 1])})
    assert read_sr(path).channel("D0").edges.tolist() == [1, 2]


def test_chunks_in_numeric_order(tmp_path: Path) -> None:
    members = {f"logic-1-{i}": bytes([i % 2]) for i in (1, 2, 10, 3, 4, 5, 6, 7, 8, 9, 11)}
    cap = read_sr(write_sr(tmp_path / "a.sr", b"", members=members))
    assert cap.channel("D0").edges.tolist() == list(range(1, 11))


def _corrupt_crc(path: Path) -> Path:
    data = bytearray(path.read_bytes())
    with zipfile.ZipFile(path) as z:
        info = z.getinfo("logic-1-2")
    # flip a byte of the stored data of logic-1-2 (stored, so the CRC check catches it)
    off = info.header_offset + 30 + len(info.filename) + 10
    data[off] ^= 0xFF
    bad = path.with_name("crc.sr")
    bad.write_bytes(bytes(data))
    return bad


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"samplerate": "0 Hz"}, "samplerate='0 Hz' must be positive"),
        ({"samplerate": "fast"}, "not a frequency"),
        ({"unitsize": 0}, "no 'unitsize'"),
        ({"total": 9}, "does not fit in unitsize=1"),
        ({"probes": {9: "X"}}, "outside total probes"),
        ({"version": b"3"}, "unsupported .sr version"),
        ({"members": {"logic-1-1": b"\0", "logic-1-3": b"\0"}}, "member logic-1-2: is missing"),
        ({"members": {"other": b"\0"}}, "no logic data"),
        (
            {"members": {"logic-1-1": b"\0\0\0"}, "unitsize": 2, "total": 16},
            "member logic-1-1: is 3 bytes, not a whole number",
        ),
        ({"extra_meta": "[device 1\n"}, "metadata: cannot be parsed"),
    ],
)
def test_bad_metadata(tmp_path: Path, kwargs: dict[str, object], match: str) -> None:
    path = write_sr(tmp_path / "a.sr", bytes(8), **kwargs)  # type: ignore[arg-type]
    with pytest.raises(CaptureError, match=match) as info:
        read_sr(path)
    assert str(path) in str(info.value) and "\n" not in str(info.value)


def test_crc_error_names_member(tmp_path: Path) -> None:
    raw = bytes(range(256)) * 4
    path = write_sr(
        tmp_path / "a.sr",
        raw + raw,
        probes={0: "A"},
        chunk=len(raw),
        compression=zipfile.ZIP_STORED,
    )
    with pytest.raises(CaptureError, match="member logic-1-2: is corrupt.*CRC"):
        read_sr(_corrupt_crc(path))


def test_bomb_limits(tmp_path: Path) -> None:
    path = write_sr(tmp_path / "a.sr", bytes(4096), chunk=1024)
    with pytest.raises(CaptureError, match="member logic-1-1: would unpack to 1024 bytes"):
        read_sr(path, max_member_bytes=1000)
    with pytest.raises(CaptureError, match="would unpack to 4096 bytes, more than"):
        read_sr(path, max_total_bytes=4000)


@pytest.mark.parametrize("cut", [10, 200, -10])
def test_truncated_and_garbage(tmp_path: Path, grbl_sr: Path, cut: int) -> None:
    data = grbl_sr.read_bytes()
    bad = tmp_path / "cut.sr"
    bad.write_bytes(data[:cut] if cut > 0 else data[:cut])
    with pytest.raises(CaptureError, match="cut.sr: .*(truncated|damaged|not a sigrok)"):
        read_sr(bad)


def test_not_a_zip_and_missing(tmp_path: Path) -> None:
    (tmp_path / "g.sr").write_bytes(b"garbage" * 10)
    with pytest.raises(CaptureError, match="not a sigrok .sr file"):
        read_sr(tmp_path / "g.sr")
    with pytest.raises(CaptureError, match="no such file"):
        read_sr(tmp_path / "missing.sr")


# --- issue 12: chunk names as libsigrok reads them; zip entries that overlap -----------------


@pytest.mark.parametrize("odd", [["logic-1-02"], ["logic-1-0"], ["logic-1-02", "logic-1-0"]])
def test_chunk_names_follow_libsigrok(tmp_path: Path, odd: list[str]) -> None:
    """libsigrok opens ``"%s-%d"`` for 1, 2, … by exact name: ``logic-1-02`` and ``logic-1-0``
    are never read, so their (busy) data must not change the capture; a note names them."""
    chunks = {"logic-1-1": bytes([0, 0, 1, 1]), "logic-1-2": bytes([0, 0, 0, 1])}
    plain = read_sr(write_sr(tmp_path / "plain.sr", b"", members=chunks))
    busy = bytes([0, 1] * 50)
    path = write_sr(tmp_path / "odd.sr", b"", members={**chunks, **dict.fromkeys(odd, busy)})
    cap = read_sr(path)
    assert cap.end == plain.end == 8
    assert cap.channel("D0").edges.tolist() == plain.channel("D0").edges.tolist() == [2, 4, 7]
    assert any("never reads" in n and all(o in n for o in odd) for n in cap.notes), cap.notes


def test_chunk_numbers_far_apart_cost_nothing(tmp_path: Path) -> None:
    """``logic-1-1`` and ``logic-1-100000000000``: a gap reported at once (the old reader built a
    set of every missing number: 14 GB); numbers past any int are a gap too."""
    for far in ("100000000000", "9" * 5000):
        members = {"logic-1-1": b"\0", f"logic-1-{far}": b"\1"}
        path = write_sr(tmp_path / "far.sr", b"", members=members)
        with pytest.raises(CaptureError, match="member logic-1-2: is missing") as exc:
            read_sr(path)
        assert "\n" not in str(exc.value)


def _repoint(path: Path, member: str, to: str) -> Path:
    """Make ``member``'s central directory entry point at ``to``'s local header (overlap)."""
    import struct

    with zipfile.ZipFile(path) as z:
        target = z.getinfo(to)
    data = bytearray(path.read_bytes())
    pos = 0
    while (pos := data.find(b"PK\x01\x02", pos)) >= 0:
        (nlen,) = struct.unpack_from("<H", data, pos + 28)
        if data[pos + 46 : pos + 46 + nlen] == member.encode():
            struct.pack_into("<I", data, pos + 42, target.header_offset)
            for off, value in (
                (16, target.CRC),
                (20, target.compress_size),
                (24, target.file_size),
            ):
                struct.pack_into("<I", data, pos + off, value)
        pos += 4
    out = path.with_name("overlap.sr")
    out.write_bytes(bytes(data))
    return out


def test_overlapping_zip_entries_refused(tmp_path: Path) -> None:
    """Two directory entries on the same data (how a 1 MB file inflates to 1 TB) are refused
    as a zip bomb with one line, before anything is inflated."""
    raw = bytes(range(4)) * 64
    path = write_sr(tmp_path / "a.sr", raw, chunk=64)
    assert read_sr(path).end == 256
    with pytest.raises(CaptureError, match="overlap.*zip bomb") as exc:
        read_sr(_repoint(path, "logic-1-3", "logic-1-2"))
    assert "\n" not in str(exc.value) and "overlap.sr" in str(exc.value)


def test_overlapping_entries_bomb_is_refused_quickly(tmp_path: Path) -> None:
    """1,000 entries on one 64 MiB stream: refused with nothing inflated (the peak of memory
    stays far below one stream's 64 MiB; tests/bounds.py)."""
    from tests.bounds import peak_bytes
    from tests.reliability.corpus import sr_overlapping_entries

    path = tmp_path / "bomb.sr"
    path.write_bytes(sr_overlapping_entries())

    def refused() -> None:
        with pytest.raises(CaptureError, match="overlap"):
            read_sr(path)

    _, peak = peak_bytes(refused)
    assert peak < 8 << 20, peak


def test_exact_edges_section_gives_resolution_zero(tmp_path: Path) -> None:
    """A .sr of simulated edges (stepgen) says ``[wavecheck] edges=exact``: resolution 0 with a
    note naming the source; the same file without the section is sampled (one period)."""
    from wavecheck.capture.srzip import write_sr_edges

    edges = [np.array([2, 7], dtype=np.int64), np.array([5], dtype=np.int64)]
    exact = tmp_path / "exact.sr"
    write_sr_edges(exact, ["STEP", "DIR"], edges, [0, 0], 10, samplerate=40_000,
                   exact_source="a test\nsimulation")  # fmt: skip
    plain = tmp_path / "plain.sr"
    write_sr_edges(plain, ["STEP", "DIR"], edges, [0, 0], 10, samplerate=40_000)
    cap = read_sr(exact)
    assert cap.resolution_ticks == 0 and cap.resolution_ns == 0
    assert any("exact" in n and "a test simulation" in n for n in cap.notes), cap.notes
    assert cap.channel("STEP").edges.tolist() == [2, 7]
    assert read_sr(plain).resolution_ticks == 1
    assert read_sr(exact, resolution_s=Fraction(50, 10**6)).resolution_ticks == 2
