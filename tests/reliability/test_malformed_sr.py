"""Malformed ``.sr`` files: a fixed corpus, truncations, byte mutations, decompression bombs."""

from __future__ import annotations

import zipfile
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tests.reliability.corpus import (
    Case,
    base_sr_raw,
    samples_from_edges,
    sr_bytes,
    sr_cases,
    truncation_offsets,
)
from tests.reliability.helpers import (
    info_then_check,
    write_case,
)
from wavecheck.capture.sr import read_sr
from wavecheck.errors import CaptureError

CASES = list(sr_cases())
#: Fixed in wavecheck/capture/sr.py (zipfile's NotImplementedError / RuntimeError / ValueError
#: escaped: encryption and other flags, 'version needed', unknown methods, a non-UTF-8 name under
#: the UTF-8 flag, and OSError from seeking to a negative offset when reading the metadata).
GOOD = sr_bytes(base_sr_raw())
FUZZ = settings(
    max_examples=150,
    deadline=None,
    derandomize=True,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)


def _info_and_check(folder: Path, case: Case) -> None:
    info_then_check(folder, case, missing_channels_ok=True)


@pytest.mark.parametrize("case", CASES, ids=[c.name for c in CASES])
def test_corpus(tmp_path: Path, case: Case) -> None:
    _info_and_check(tmp_path, case)


@pytest.mark.parametrize("offset", truncation_offsets(len(GOOD), 96))
def test_truncated(tmp_path: Path, offset: int) -> None:
    _info_and_check(tmp_path, Case(f"cut-{offset}", GOOD[:offset], ".sr", "either"))


@FUZZ
@given(
    flips=st.lists(
        st.tuples(st.integers(0, len(GOOD) - 1), st.integers(1, 255)), min_size=1, max_size=6
    )
)
def test_fuzz_byte_flips(tmp_path: Path, flips: list[tuple[int, int]]) -> None:
    data = bytearray(GOOD)
    for pos, x in flips:
        data[pos] ^= x
    _info_and_check(tmp_path, Case("flipped", bytes(data), ".sr", "either"))


@FUZZ
@given(
    meta=st.dictionaries(
        st.sampled_from(
            ["samplerate", "unitsize", "total probes", "probe1", "probe2", "capturefile"]
        ),
        st.one_of(
            st.text(max_size=12),
            st.integers(-(2**70), 2**70).map(str),
            st.sampled_from(["0", "1 GHz", "1.5 MHz", "12.5M", "65", "9", "logic-1", "-0", " 1 "]),
        ),
        min_size=1,
        max_size=3,
    )
)
def test_fuzz_metadata_values(tmp_path: Path, meta: dict[str, str]) -> None:
    lines = ["[global]", "sigrok version=0.5.2", "", "[device 1]"]
    base = {"capturefile": "logic-1", "total probes": "2", "samplerate": "1 MHz",
            "probe1": "STEP", "probe2": "DIR", "unitsize": "1"}  # fmt: skip
    base.update({k: v.replace("\n", " ").replace("\r", " ") for k, v in meta.items()})
    lines += [f"{k}={v}" for k, v in base.items()]
    data = sr_bytes(base_sr_raw(), metadata="\n".join(lines) + "\n")
    _info_and_check(tmp_path, Case("meta", data, ".sr", "either"))


def test_bomb_refused_past_member_limit(tmp_path: Path) -> None:
    """A chunk of 8 MiB of zeros (a few KiB packed) is refused past a 1 MiB per-member limit."""
    path = tmp_path / "bomb.sr"
    path.write_bytes(sr_bytes(bytes(8 << 20), chunk=8 << 20))
    assert path.stat().st_size < 64 << 10
    with pytest.raises(CaptureError, match="limit") as exc:
        read_sr(path, max_member_bytes=1 << 20)
    assert str(path) in str(exc.value)
    with pytest.raises(CaptureError, match="limit"):
        read_sr(path, max_total_bytes=4 << 20)
    assert read_sr(path).end == 8 << 20  # within the default limits it is just a long capture


def test_bomb_lying_about_size(tmp_path: Path) -> None:
    """Headers declare 4 KiB, the data inflates to 64 MiB: refused, and quickly."""
    case = next(c for c in CASES if c.name == "size-lie-inflates-more")
    path = write_case(tmp_path, case)
    with zipfile.ZipFile(path) as z:
        assert z.getinfo("logic-1-1").file_size <= 4096
    with pytest.raises(CaptureError) as exc:
        read_sr(path)
    assert str(path) in str(exc.value)


@settings(max_examples=60, deadline=None, derandomize=True)
@given(
    nsamples=st.integers(2, 300),
    edges=st.lists(st.integers(1, 299), max_size=40, unique=True),
    chunk=st.integers(1, 40),
    read_chunk=st.integers(1, 33),
    unitsize=st.sampled_from([1, 2, 3]),
)
def test_edges_survive_any_chunking(
    tmp_path_factory: pytest.TempPathFactory,
    nsamples: int,
    edges: list[int],
    chunk: int,
    read_chunk: int,
    unitsize: int,
) -> None:
    """Edges at member and read-block boundaries are neither lost nor doubled."""
    ticks = sorted(t for t in edges if t < nsamples)
    raw = samples_from_edges(nsamples, [(1, ticks), (0, ticks[::2])], unitsize=unitsize).tobytes()
    from tests.reliability.corpus import sr_metadata

    meta = sr_metadata(unitsize=unitsize)
    path = tmp_path_factory.mktemp("sr") / "c.sr"
    path.write_bytes(sr_bytes(raw, metadata=meta, chunk=chunk * unitsize))
    cap = read_sr(path, chunk_bytes=read_chunk)
    assert cap.end == nsamples
    assert cap.channels[0].initial == 1 and cap.channels[0].edges.tolist() == ticks
    assert cap.channels[1].edges.tolist() == ticks[::2]
