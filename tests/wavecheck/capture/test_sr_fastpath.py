"""The .sr reader's fast paths give the same edges as the simple path (unpackbits over all samples).

The fast paths are: members inflated straight from the file (zlib-ng or zlib, stored or
deflated), and changed samples found by comparing 8-byte words with the same bytes one sample
earlier (``_changed_words``). Edges are put exactly on, and one sample
either side of, word boundaries (every 8 samples), read boundaries (``chunk_bytes``) and member
boundaries, so a carry or an off-by-one at any of them shows up.
"""

from __future__ import annotations

import zipfile
import zlib
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tests.wavecheck.capture.srutil import edges_by_unpacking, write_sr
from wavecheck.capture import sr
from wavecheck.capture.sr import _changed_words, _EdgeFinder, read_sr


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


def _simple_changes(block: np.ndarray, step: int) -> list[int]:
    """8·byte + bit for every bit of ``block[step:]`` that differs from ``step`` bytes earlier."""
    d = block[step:] ^ block[: len(block) - step] if len(block) > step else block[:0]
    return np.flatnonzero(np.unpackbits(d, bitorder="little")).tolist()


@pytest.mark.parametrize("n", [0, 1, 2, 7, 8, 9, 15, 16, 17, 24, 25, 1000])
@pytest.mark.parametrize("step", [1, 2, 3, 8, 9])
def test_changed_words_equal_xor_and_unpackbits(n: int, step: int) -> None:
    """Sparse and dense changes, one or several bits a byte, one or several bytes a word."""
    rng = np.random.default_rng(n * 10 + step)
    for density in (0.0, 0.01, 0.5, 1.0):
        for one_bit in (True, False):
            flips = rng.integers(1, 256, n) if not one_bit else 1 << rng.integers(0, 8, n)
            level = np.where(rng.random(n) < density, flips, 0).astype(np.uint8)
            block = np.bitwise_xor.accumulate(level) if n else level  # changes where level != 0
            for scratch in (None, np.zeros(2, dtype=bool), np.ones(n // 8 + 1, dtype=bool)):
                changed = _changed_words(block, step, scratch)
                assert changed is not None
                at, xor = changed
                bits = np.unpackbits(xor.view(np.uint8), bitorder="little").reshape(-1, 64)
                word, bit = np.nonzero(bits)  # bit b of a word: byte b // 8 from its start
                got = (at[word] + bit // 8) * 8 + bit % 8
                assert got.tolist() == _simple_changes(block, step)
                assert (np.diff(at) > 0).all() and (at % 8 == 0).all()


@settings(max_examples=300)
@given(
    unitsize=st.integers(1, 5),
    data=st.data(),
)
def test_edge_finder_equals_unpackbits(unitsize: int, data: st.DataObject) -> None:
    """Any samples, any enabled bits, any split into blocks (whole samples), dense or sparse
    blocks: the same edges as unpackbits over all samples for the wanted bits, including changes
    exactly at block and word boundaries, and the same number of changes for every bit."""
    n = data.draw(st.integers(1, 80), label="samples")
    flips = data.draw(
        st.lists(st.tuples(st.integers(0, n - 1), st.integers(0, 8 * unitsize - 1)), max_size=60),
        label="flips",
    )
    first = data.draw(st.binary(min_size=unitsize, max_size=unitsize), label="first sample")
    u8 = np.tile(np.frombuffer(first, np.uint8), (n, 1))
    for at, bit in flips:  # the bit toggles from sample ``at`` on
        u8[at:, bit // 8] ^= np.uint8(1 << (bit % 8))
    raw = u8.tobytes()
    bits = sorted(
        data.draw(st.sets(st.integers(0, 8 * unitsize - 1), min_size=1), label="enabled bits")
    )
    cuts = (
        sorted(data.draw(st.sets(st.integers(1, n - 1), max_size=6), label="cuts")) if n > 1 else []
    )
    wanted = data.draw(st.sets(st.sampled_from(range(len(bits)))), label="wanted slots")
    # the share of changed words above which a block is XORed whole: 0 always, 2 never
    dense = data.draw(st.sampled_from([0.0, sr.DENSE_WORDS, 2.0]), label="dense")
    peek = data.draw(st.booleans(), label="edges read after every block (streaming)")
    finder = _EdgeFinder(unitsize, bits)
    finder.want(wanted)
    got: list[list[int]] = [[] for _ in bits]
    saved, sr.DENSE_WORDS = sr.DENSE_WORDS, dense
    try:
        for a, b in zip([0, *cuts], [*cuts, n], strict=True):
            finder.add(np.frombuffer(raw, np.uint8)[a * unitsize : b * unitsize])
            if peek:  # as a streamed read: everything up to the block's end is known
                for slot, bit in enumerate(bits):
                    so_far = [e for e in edges_by_unpacking(raw, unitsize, bit)[1] if e < b]
                    assert finder.counted[slot] == len(so_far)
                    got[slot] += finder.edges(slot).tolist()
    finally:
        sr.DENSE_WORDS = saved
    assert finder.nsamples == n
    for slot, bit in enumerate(bits):
        initial, edges = edges_by_unpacking(raw, unitsize, bit)
        got[slot] += finder.edges(slot).tolist()
        assert (finder.initial[slot], got[slot]) == (initial, edges if slot in wanted else [])
        assert finder.counted[slot] == len(edges)  # unwanted bits: only counted
