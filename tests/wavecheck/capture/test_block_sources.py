"""Every block source gives the capture the whole read gives, field for field (issue 23: one
engine; the block readers are the only readers the checks use).

For each source :func:`wavecheck.capture.open.open_source` picks (``.sr``, VCD from a file and
from a pipe, raw binary samples from a file and from a pipe, the one-block source of the other
formats), the skeleton before any block and the capture assembled from the blocks are compared
with :func:`wavecheck.capture.open.open_capture`'s capture of the same input, at several block
sizes.
"""

from __future__ import annotations

import dataclasses
import os
import subprocess
import threading
from pathlib import Path

import numpy as np
import pytest

from tests.conftest import REPO, shared_capture
from wavecheck.capture.binary import BinaryBlocks
from wavecheck.capture.blocks import MemorySource, assemble
from wavecheck.capture.edges import Capture
from wavecheck.capture.fst_source import FstNativeBlocks
from wavecheck.capture.open import open_capture, open_source
from wavecheck.capture.sr import SrBlocks
from wavecheck.capture.vcd.reader import VcdBlocks
from wavecheck.capture.wellen import FstBlocks
from wavecheck.errors import CaptureError


def _channel_fields(capture: Capture) -> list[dict[str, object]]:
    out = []
    for ch in capture.channels:
        row = {}
        for f in dataclasses.fields(ch):
            v = getattr(ch, f.name)
            row[f.name] = v.tolist() if isinstance(v, np.ndarray) else v
        out.append(row)
    return out


def _same(got: Capture, ref: Capture, *, skeleton: bool = False) -> None:
    """``got`` equals ``ref`` field for field (a skeleton: every field but the edges, the levels
    learnt from them and the end)."""
    for f in dataclasses.fields(ref):
        if not f.compare or f.name in ("path", "channels", "notes", "bit_source"):
            continue  # path: a pipe's; bit_source/bit_reader: how bits of vectors are read
        if skeleton and f.name == "end":
            continue
        assert getattr(got, f.name) == getattr(ref, f.name), f.name
    assert [n for n in got.notes if "one block" not in n] == ref.notes
    a, b = _channel_fields(got), _channel_fields(ref)
    if skeleton:
        keep = ("name", "index")
        a = [{k: r[k] for k in keep} for r in a]
        b = [{k: r[k] for k in keep} for r in b]
    assert a == b


def _pipe(path: Path, tmp: Path) -> Path:
    """A FIFO that a thread fills with ``path``'s bytes."""
    fifo = tmp / f"pipe{path.suffix}"
    os.mkfifo(fifo)
    threading.Thread(target=lambda: fifo.write_bytes(path.read_bytes()), daemon=True).start()
    return fifo


def _raw(tmp: Path) -> Path:
    """Raw 16-channel samples (unitsize 2): channel 3 toggling every 5 samples, 9 every 37."""
    n = 40_000
    k = np.arange(n)
    words = ((k // 5) % 2) << 3 | ((k // 37) % 2) << 9
    path = tmp / "raw.bin"
    path.write_bytes(words.astype("<u2").tobytes())
    return path


def _fst(tmp: Path, *options: str) -> Path:
    """The VCD below as an FST, made by GTKWave's vcd2fst (LZ4-packed, its default; ``-F``:
    FastLZ, which only fst2vcd reads)."""
    path = tmp / "c.fst"
    subprocess.run(["vcd2fst", *options, str(VCD), str(path)], check=True, capture_output=True)
    return path


VCD = REPO / "captures/golden/g202-p16-dirhold2-worst.vcd"
SR = "sigrok-dumps/stepper_motor/smoothieware/smoothieware_snippet.sr"
RAW = "binary:numchannels=16:samplerate=1000000"
#: case → (input, --input-format, the source open_source must pick); "pipe": through a FIFO
CASES = {
    "vcd file": ("vcd", None, VcdBlocks),
    "vcd pipe": ("vcd", None, VcdBlocks),
    "sr file": ("sr", None, SrBlocks),
    "fst file": ("fst", None, FstNativeBlocks),
    "fst file, FastLZ (fst2vcd)": ("fst-fastlz", None, FstBlocks),
    "raw file": ("raw", RAW, BinaryBlocks),
    "raw pipe": ("raw", RAW, BinaryBlocks),
    "vcd through sigrok-cli, one block": ("vcd", "vcd:downsample=1", MemorySource),
}


@pytest.mark.parametrize("chunk", [64, 1000, 1 << 20])
@pytest.mark.parametrize("case", list(CASES))
def test_a_block_source_gives_the_whole_reads_capture(
    tmp_path: Path, case: str, chunk: int
) -> None:
    what, fmt, kind = CASES[case]
    make = {
        "vcd": lambda: VCD, "raw": lambda: _raw(tmp_path), "fst": lambda: _fst(tmp_path),
        "fst-fastlz": lambda: _fst(tmp_path, "-F"),
    }  # fmt: skip
    path = make[what]() if what in make else shared_capture(SR)
    ref = open_capture(path, input_format=fmt)
    source = open_source(
        _pipe(path, tmp_path) if case.endswith("pipe") else path, input_format=fmt,
        chunk_bytes=chunk,
    )  # fmt: skip
    assert type(source) is kind
    _same(source.skeleton, ref, skeleton=True)
    blocks = list(source.blocks())
    if kind is not MemorySource and chunk == 64:
        assert len(blocks) > 1
    got = assemble(source.capture(), blocks)
    whole_read = [n for n in got.notes if "checked as one block" in n]
    assert len(whole_read) == (kind is MemorySource)  # said once, where it is so
    if not case.endswith("pipe"):
        assert got.path == ref.path
    _same(got, ref)


@pytest.mark.parametrize(
    ("data", "message"),
    [
        (b"\x01\x02\x03", "byte 2: the data ends in a partial sample (1 of 2 bytes)"),
        (b"", "the file is empty"),
    ],
)
def test_raw_samples_cut_short_or_empty_are_refused_as_the_whole_read_refuses_them(
    tmp_path: Path, data: bytes, message: str
) -> None:
    path = tmp_path / "raw.bin"
    path.write_bytes(data)
    with pytest.raises(CaptureError) as block_err:
        source = open_source(path, input_format=RAW, chunk_bytes=2)
        assert isinstance(source, BinaryBlocks)
        list(source.blocks())
    with pytest.raises(CaptureError) as whole_err:
        open_capture(path, input_format=RAW)
    assert message in str(block_err.value)
    assert str(block_err.value) == str(whole_err.value)
