"""The .sr reader's fast paths give the same edges as the simple path (unpackbits over all samples).

The fast paths are: members inflated straight from the file (zlib-ng or zlib, stored or
deflated), and changed samples found 8 bytes at a time. Edges are put exactly on, and one sample
either side of, word boundaries (every 8 samples), read boundaries (``chunk_bytes``) and member
boundaries, so a carry or an off-by-one at any of them shows up.
"""

from __future__ import annotations

import zipfile
import zlib
from pathlib import Path

import numpy as np
import pytest

from tests.wavecheck.capture.srutil import edges_by_unpacking, write_sr
from wavecheck.capture import sr
from wavecheck.capture.sr import _nonzero_bytes, read_sr


def _toggles_at(n: int, positions: list[int], unitsize: int, bit: int) -> bytes:
    """``n`` samples where ``bit`` toggles at each of ``positions`` (other bits: a slow square)."""
    level = np.zeros(n, dtype=np.uint8)
    for p in sorted(set(p for p in positions if 0 < p < n)):
        level[p:] ^= 1
    u8 = np.zeros((n, unitsize), dtype=np.uint8)
    u8[:, bit // 8] |= level << (bit % 8)
    u8[:, 0] |= ((np.arange(n) // 1000) & 1).astype(np.uint8) << 7  # another bit in byte 0
    return u8.tobytes()


@pytest.mark.parametrize("unitsize,bit", [(1, 0), (1, 5), (2, 9)])
@pytest.mark.parametrize("chunk", [8, 9, 64, 4099])
@pytest.mark.parametrize("inflater", ["default", "zlib"])
def test_edges_on_and_next_to_every_boundary(
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    unitsize: int,
    bit: int,
    chunk: int,
    inflater: str,
) -> None:
    if inflater == "zlib":
        monkeypatch.setattr(sr, "_zlib", zlib)
    n = 20_000
    member = 3000  # samples per member: not a multiple of 8 or of the chunk
    bounds = list(range(0, n, 8)) + list(range(0, n, chunk)) + list(range(0, n, member))
    positions = [b + d for b in bounds[:: max(1, len(bounds) // 600)] for d in (-1, 0, 1)]
    positions += [member, member + 1, 2 * member - 1]
    raw = _toggles_at(n, positions, unitsize, bit)
    path = write_sr(
        tmp_path / "a.sr", raw, total=8 * unitsize, unitsize=unitsize, chunk=member * unitsize
    )
    cap = read_sr(path, chunk_bytes=chunk * unitsize)
    for ch in cap.channels:
        assert (ch.initial, ch.edges.tolist()) == edges_by_unpacking(raw, unitsize, ch.index)
    assert cap.end == n


def test_stored_members_and_sparse_words(tmp_path: Path) -> None:
    rng = np.random.default_rng(5)
    raw = np.zeros(50_000, dtype=np.uint8)
    for p in np.sort(rng.choice(50_000, 300, replace=False)):
        raw[p:] ^= np.uint8(1 << int(rng.integers(0, 8)))
    path = tmp_path / "stored.sr"
    write_sr(path, raw, chunk=7_777, compression=zipfile.ZIP_STORED)  # the other fast path
    with zipfile.ZipFile(path) as z:
        assert {i.compress_type for i in z.infolist()} == {zipfile.ZIP_STORED, zipfile.ZIP_DEFLATED}
        assert z.getinfo("logic-1-1").compress_type == zipfile.ZIP_STORED
    for chunk in (1 << 20, 1000, 13):
        cap = read_sr(path, chunk_bytes=chunk)
        for ch in cap.channels:
            assert (ch.initial, ch.edges.tolist()) == edges_by_unpacking(raw.tobytes(), 1, ch.index)


@pytest.mark.parametrize("n", [0, 1, 7, 8, 9, 15, 16, 17, 1000])
def test_nonzero_bytes_equals_flatnonzero(n: int) -> None:
    rng = np.random.default_rng(n)
    for density in (0.0, 0.01, 0.5, 1.0):
        d = np.where(rng.random(n) < density, rng.integers(1, 256, n), 0).astype(np.uint8)
        assert _nonzero_bytes(d).tolist() == np.flatnonzero(d).tolist()
