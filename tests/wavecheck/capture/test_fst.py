"""The native FST reader gives what GTKWave's fst2vcd piped into the VCD reader gives (issue 38).

Every capture field is compared (channels with their edges, levels, unknown stretches and edge
counts; names, aliases, skipped signals, vectors, notes, start, end, time base), and the bits
of each vector mapped as channels, on FSTs written by the real tools: Icarus Verilog's
``vvp -fst`` (zlib) at four timescales, and GTKWave's ``vcd2fst`` from the golden and example
VCDs in each of its packings (LZ4, its default; zlib; the whole file gzipped) and from real
sigrok-dumps captures. The edge builder is fed in slices of any size down to one change.
"""

from __future__ import annotations

import shutil
import subprocess
from dataclasses import fields
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tests.conftest import REPO
from wavecheck.capture.blocks import BlockSource, assemble
from wavecheck.capture.edges import Capture
from wavecheck.capture.fst import FstUnsupported, varints
from wavecheck.capture.fst_source import FstNativeBlocks, read_native
from wavecheck.capture.open import open_capture, open_source
from wavecheck.capture.wellen import FstBlocks, read_wellen
from wavecheck.errors import CaptureError

SIM = Path(__file__).parent / "sim"
needs_gtkwave = pytest.mark.skipif(
    not (shutil.which("vcd2fst") and shutil.which("fst2vcd")), reason="needs GTKWave"
)
needs_iverilog = pytest.mark.skipif(
    shutil.which("iverilog") is None or shutil.which("vvp") is None, reason="needs iverilog"
)
VCDS = sorted((REPO / "captures/golden").glob("*.vcd")) + sorted(
    (REPO / "captures/examples").glob("*.vcd")
)
#: vcd2fst's packings: LZ4 (its default), zlib, the whole file gzipped
PACKINGS = {"lz4": [], "zlib": ["-Z"], "gzip-wrapped": ["-c"]}


def _fields(cap: Capture) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for f in fields(cap):
        value = getattr(cap, f.name)
        if f.name == "bit_reader":
            continue
        if f.name == "channels":
            value = [
                (c.name, c.index, c.initial, c.edges.tolist(), c.known_from, c.xz_times.tolist(),
                 c.xz_ends.tolist(), c.never_known, c.edge_count)
                for c in value
            ]  # fmt: skip
        out[f.name] = value
    return out


def _read(source: BlockSource, bits: list[tuple[str, int]]) -> dict[str, Any]:
    for key, bit in bits:
        source.skeleton.bit(key, bit)
    blocks = list(source.blocks())
    return _fields(assemble(source.capture(), blocks))


def _same_as_fst2vcd(path: Path, slices: tuple[int, ...] = (1 << 16,)) -> bool:
    """Whether both read ``path`` (False: both refuse it); AssertionError when they differ."""
    try:
        vectors = FstNativeBlocks(path).skeleton.vectors
    except CaptureError:
        with pytest.raises(CaptureError):
            list(FstBlocks(path, str(shutil.which("fst2vcd"))).blocks())
        return False
    bits = [(k, b) for k, v in vectors.items() for b in sorted({v.msb, v.lsb})]
    want = _read(FstBlocks(path, str(shutil.which("fst2vcd"))), bits)
    for n in slices:
        got = _read(FstNativeBlocks(path, slice_changes=n), bits)
        assert got == want, (path.name, n, [k for k in got if got[k] != want[k]])
    return True


def _vcd2fst(vcd: Path, out: Path, options: list[str]) -> Path:
    subprocess.run(["vcd2fst", *options, str(vcd), str(out)], check=True, capture_output=True)
    return out


@needs_gtkwave
@pytest.mark.parametrize("packing", list(PACKINGS))
@pytest.mark.parametrize("vcd", VCDS, ids=lambda p: p.stem)
def test_vcd2fst_files_read_as_fst2vcd_reads_them(tmp_path: Path, vcd: Path, packing: str) -> None:
    fst = _vcd2fst(vcd, tmp_path / "c.fst", PACKINGS[packing])
    assert _same_as_fst2vcd(fst, (1, 7, 1 << 16) if vcd.stem == VCDS[0].stem else (1 << 16,))
    assert type(open_source(fst)) is FstNativeBlocks


SHARED_VCDS = [
    "sigrok-dumps/misc/vcd/vectors-integers.vcd",  # vectors and integers: their bits mapped
    "sigrok-dumps/misc/vcd/real-analog.vcd",  # reals only: vcd2fst writes no hierarchy
    "sigrok-dumps/spi/spiflash_read16/chronovu_la8/chronovu_la8_spiflash_read16.vcd",
]


@needs_gtkwave
@pytest.mark.parametrize("packing", list(PACKINGS))
@pytest.mark.parametrize("name", SHARED_VCDS, ids=lambda p: Path(p).stem)
def test_real_vcds_as_fst_read_or_refused_as_fst2vcd_does(
    tmp_path: Path, name: str, packing: str
) -> None:
    from tests.conftest import shared_capture

    fst = _vcd2fst(shared_capture(name), tmp_path / "c.fst", PACKINGS[packing])
    assert _same_as_fst2vcd(fst, (1, 1 << 16)) == ("real-analog" not in name)


@needs_gtkwave
@needs_iverilog
@pytest.mark.parametrize("precision", ["1fs", "1ps", "10ps", "1ns"])
def test_icarus_fst_reads_as_fst2vcd_and_pywellen_read_it(tmp_path: Path, precision: str) -> None:
    src = tmp_path / "gen.v"
    src.write_text((SIM / "gen.v").read_text().replace("TIMESCALE_PRECISION", precision))
    fst = tmp_path / "gen.fst"
    subprocess.run(["iverilog", f'-DDUMPFILE="{fst}"', "-o", "gen.vvp", str(src)], check=True,
                   cwd=tmp_path)  # fmt: skip
    subprocess.run(["vvp", "-n", "gen.vvp", "-fst"], check=True, cwd=tmp_path,
                   capture_output=True)  # fmt: skip
    assert _same_as_fst2vcd(fst, (1, 2, 1 << 16))
    native, wellen = read_native(fst), read_wellen(fst, kind="fst")
    assert native.timebase == wellen.timebase
    assert len(wellen.channels) == len(native.channels)
    for w in wellen.channels:  # pywellen names by full name (tb.step): the same signal's edges
        c = native.channel(native.aliases.get(w.name, w.name))
        assert (c.edges.tolist(), c.initial, c.never_known, c.xz_times.tolist()) == (
            w.edges.tolist(), w.initial, w.never_known, w.xz_times.tolist(),
        )  # fmt: skip
        # a never-known channel is unknown throughout: known_from is start in one, end in the other
        assert c.never_known or c.known_from == w.known_from


def _sigrok_vcd(sr: Path, out: Path) -> Path | None:
    """A sigrok-dumps capture as a VCD vcd2fst reads: sigrok-cli writes several changes on one
    line, which vcd2fst reads as none, so each goes on its own line."""
    raw = subprocess.run(["sigrok-cli", "-i", str(sr), "-O", "vcd"], capture_output=True,
                         timeout=120)  # fmt: skip
    if raw.returncode or not raw.stdout:
        return None
    head, sep, body = raw.stdout.partition(b"$enddefinitions $end")
    out.write_bytes(head + sep + b"\n".join(body.split()) + b"\n")
    return out


@needs_gtkwave
@pytest.mark.slow
@pytest.mark.skipif(shutil.which("sigrok-cli") is None, reason="needs sigrok-cli")
def test_real_captures_as_fst_read_as_fst2vcd_reads_them(tmp_path: Path) -> None:
    """Every sigrok-dumps capture under 3 MB, as a VCD, as an FST."""
    from tests.conftest import shared_capture

    root = shared_capture("sigrok-dumps")
    read = refused = 0
    for sr in sorted(root.rglob("*.sr")):
        if sr.stat().st_size > 3 << 20:
            continue
        vcd = _sigrok_vcd(sr, tmp_path / "c.vcd")
        if vcd is None:
            continue
        fst = _vcd2fst(vcd, tmp_path / "c.fst", [])
        try:
            both = _same_as_fst2vcd(fst)
        except AssertionError as err:
            raise AssertionError(f"{sr.name}: {err}") from None
        read += both
        refused += not both  # vcd2fst wrote no hierarchy (a capture of analog channels only)
    assert read >= 55 and refused <= 5, (read, refused)


def test_open_capture_reads_fst_natively(tmp_path: Path) -> None:
    fst = _seed(tmp_path)
    cap = open_capture(fst)
    assert cap.format == "fst" and [c.name for c in cap.channels]
    assert _fields(cap) == _fields(read_native(fst))


def _seed(tmp_path: Path) -> Path:
    from tests.reliability.seeds import fst_seeds

    seeds = fst_seeds()
    if not seeds:
        pytest.skip("needs GTKWave's vcd2fst")
    path = tmp_path / "seed.fst"
    path.write_bytes(seeds[0])
    return path


@needs_gtkwave
def test_fastlz_packing_falls_back_to_fst2vcd(tmp_path: Path) -> None:
    fst = _vcd2fst(VCDS[0], tmp_path / "c.fst", ["-F"])
    with pytest.raises(FstUnsupported):
        FstNativeBlocks(fst)
    assert type(open_source(fst)) is FstBlocks
    assert open_capture(fst).channels  # read through fst2vcd


def _leb128(values: list[int]) -> bytes:
    out = bytearray()
    for x in values:
        while True:
            low, x = x & 0x7F, x >> 7
            out.append(low | (0x80 if x else 0))
            if not x:
                break
    return bytes(out)


@settings(max_examples=200, deadline=None)
@given(st.lists(st.one_of(st.integers(0, 300), st.integers(0, (1 << 64) - 1)), max_size=60))
def test_varints_decode_what_leb128_encodes(values: list[int]) -> None:
    got = varints(np.frombuffer(_leb128(values), np.uint8))
    assert got.tolist() == values


@pytest.mark.parametrize(
    ("data", "message"),
    [(b"\x80", "cut off"), (b"\x01\x81", "cut off"), (b"\xff" * 10 + b"\x01", "11 bytes")],
)
def test_varints_refuse_cut_or_overlong_numbers(data: bytes, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        varints(np.frombuffer(data, np.uint8))
