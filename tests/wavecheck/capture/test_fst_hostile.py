"""Malformed and hostile FST files: a one-line error naming the file and the byte, exit 2, in
bounded memory (tracemalloc: numpy's and zlib's buffers included) and work, never a traceback.

The seeds are real files (GTKWave's vcd2fst, LZ4 and zlib packing); they are cut at every
length, given impossible block lengths, given sizes that promise gigabytes (time table,
position table, hierarchy, the gzip wrapper), and corrupted at random (hypothesis)."""

from __future__ import annotations

import shutil
import subprocess
import sys
import tracemalloc
from collections.abc import Callable
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tests.reliability.corpus import vcd_text
from wavecheck.capture.fst import FstFile, FstUnsupported
from wavecheck.capture.fst_source import read_native
from wavecheck.errors import CaptureError

pytestmark = pytest.mark.skipif(shutil.which("vcd2fst") is None, reason="needs GTKWave")
#: the most memory a read of a hostile file of a few hundred bytes may take
PEAK_BYTES = 32 << 20
HUGE = [1 << 40, (1 << 63) - 1, (1 << 64) - 1]


@pytest.fixture(scope="module")
def seeds(tmp_path_factory: pytest.TempPathFactory) -> dict[str, bytes]:
    tmp = tmp_path_factory.mktemp("fst-seeds")
    (tmp / "s.vcd").write_text(vcd_text())
    out = {}
    for name, options in {"lz4": [], "zlib": ["-Z"], "wrapped": ["-c"]}.items():
        subprocess.run(["vcd2fst", *options, str(tmp / "s.vcd"), str(tmp / f"{name}.fst")],
                       check=True, capture_output=True)  # fmt: skip
        out[name] = (tmp / f"{name}.fst").read_bytes()
    return out


def _outcome(path: Path) -> str:
    """Read ``path`` whole; "read", "unsupported" or the CaptureError's text. Any other
    exception fails the test, as does a peak above PEAK_BYTES."""
    tracemalloc.start()
    try:
        read_native(path)
        result = "read"
    except FstUnsupported:
        result = "unsupported"
    except CaptureError as err:
        result = str(err)
    finally:
        _, peak = tracemalloc.get_traced_memory()
        tracemalloc.stop()
    assert peak < PEAK_BYTES, f"{peak / 1e6:.0f} MB for {path.stat().st_size} bytes"
    return result


def _refused(path: Path, data: bytes, *, where: str = "byte ") -> str:
    path.write_bytes(data)
    got = _outcome(path)
    assert got.startswith(f"{path}: {where}") and "\n" not in got, got
    return got


def _layout(data: bytes, path: Path) -> FstFile:
    path.write_bytes(data)
    return FstFile(path)


def _put(data: bytes, at: int, value: int, size: int = 8) -> bytes:
    return data[:at] + value.to_bytes(size, "big") + data[at + size :]


@pytest.mark.parametrize("seed", ["lz4", "zlib", "wrapped"])
def test_every_cut_of_a_real_file_is_refused(
    tmp_path: Path, seeds: dict[str, bytes], seed: str
) -> None:
    data = seeds[seed]
    for n in range(len(data)):
        _refused(tmp_path / "cut.fst", data[:n], where="" if n == 0 else "byte ")


@pytest.mark.parametrize("seed", ["lz4", "zlib"])
@pytest.mark.parametrize("value", [0, 1, 7, 9, *HUGE])
def test_impossible_block_lengths_are_refused(
    tmp_path: Path, seeds: dict[str, bytes], seed: str, value: int
) -> None:
    data = seeds[seed]
    pos, starts = 0, []
    while pos < len(data):
        starts.append(pos)
        pos += 1 + int.from_bytes(data[pos + 1 : pos + 9], "big")
    for at in starts:
        _refused(tmp_path / "bad.fst", _put(data, at + 1, value))


def _vc_fields(fst: FstFile) -> dict[str, int]:
    """Offsets of a value-change block's u64 size fields, and of the hierarchy's."""
    blk = fst.blocks[0]
    end = blk.start + blk.length
    return {
        "time table, uncompressed": end - 24,
        "time table, compressed": end - 16,
        "time table, count": end - 8,
        "position table": blk.index[0] + blk.index[1],
    }


@pytest.mark.parametrize("seed", ["lz4", "zlib"])
@pytest.mark.parametrize("value", HUGE)
def test_sizes_that_promise_gigabytes_are_refused(
    tmp_path: Path, seeds: dict[str, bytes], seed: str, value: int
) -> None:
    data = seeds[seed]
    fst = _layout(data, tmp_path / "ok.fst")
    for what, at in _vc_fields(fst).items():
        got = _refused(tmp_path / "big.fst", _put(data, at, value))
        assert "byte" in got, what
    pos = 0
    while data[pos] not in (4, 6, 7):  # the hierarchy block (gzip, LZ4, LZ4 twice): its size
        pos += 1 + int.from_bytes(data[pos + 1 : pos + 9], "big")
    _refused(tmp_path / "big.fst", _put(data, pos + 9, value))


@pytest.mark.parametrize("value", HUGE)
def test_a_gzip_wrapper_promising_gigabytes_is_refused(
    tmp_path: Path, seeds: dict[str, bytes], value: int
) -> None:
    got = _refused(tmp_path / "big.fst", _put(seeds["wrapped"], 9, value))
    assert "said to expand" in got


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    seed=st.sampled_from(["lz4", "zlib"]),
    edits=st.lists(
        st.tuples(st.integers(0, 10_000), st.integers(0, 255)), min_size=1, max_size=6
    ),  # fmt: skip
    big=st.one_of(st.none(), st.tuples(st.integers(0, 10_000), st.sampled_from(HUGE))),
)
def test_random_corruption_is_read_or_refused_in_bounded_memory(
    seeds: dict[str, bytes], tmp_path_factory: pytest.TempPathFactory, seed: str,
    edits: list[tuple[int, int]], big: tuple[int, int] | None,
) -> None:  # fmt: skip
    data = bytearray(seeds[seed])
    for at, byte in edits:
        data[at % len(data)] = byte
    if big is not None:
        at = big[0] % (len(data) - 8)
        data[at : at + 8] = big[1].to_bytes(8, "big")
    path = tmp_path_factory.mktemp("fuzz") / "x.fst"
    path.write_bytes(bytes(data))
    got = _outcome(path)
    assert got in ("read", "unsupported") or (got.startswith(f"{path}: ") and "\n" not in got), got


_CLI: list[Callable[[Path], list[str]]] = [
    lambda p: ["info", str(p)],
    lambda p: ["check", str(p), "--drive", "drv8825", "--map", "step=STEP,dir=DIR"],
]


@pytest.mark.parametrize("command", _CLI, ids=["info", "check"])
def test_the_cli_says_one_line_and_exits_2(
    tmp_path: Path, seeds: dict[str, bytes], command: Callable[[Path], list[str]]
) -> None:
    data = seeds["zlib"]
    fst = _layout(data, tmp_path / "ok.fst")
    at = _vc_fields(fst)["time table, count"]
    for name, bad in {"cut.fst": data[:-5], "huge.fst": _put(data, at, 1 << 40)}.items():
        path = tmp_path / name
        path.write_bytes(bad)
        proc = subprocess.run(
            [sys.executable, "-m", "wavecheck", *command(path)],
            capture_output=True, text=True, timeout=120,
        )  # fmt: skip
        assert proc.returncode == 2, proc.stderr
        assert proc.stderr.count("\n") == 1 and f"{path}: byte " in proc.stderr, proc.stderr
        assert "Traceback" not in proc.stderr
