"""The block readers (``.sr``: :class:`wavecheck.capture.sr.SrBlocks`, VCD:
:class:`wavecheck.capture.vcd.reader.VcdBlocks`) feed the engine to the report of the whole read
given as one block, at small read sizes (many blocks), on the golden traces and the shared real
captures."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.wavecheck.engine.corpus import engine_check
from wavecheck.capture.blocks import WHOLE, MemorySource
from wavecheck.capture.open import open_capture, open_source
from wavecheck.capture.srzip import write_sr_edges
from wavecheck.drives.library import load_drive
from wavecheck.report.machine import machine_dict
from wavecheck.steps.mapping import AxisMap

ROOT = Path(__file__).resolve().parents[3]
GOLDEN = ROOT / "captures" / "golden"
GRBL = ROOT.parent / "shared/captures/sigrok-dumps/stepper_motor/grbl_cnc/grbl_cnc_1.sr"


def _agree(
    path: Path, axes: list[AxisMap], drive: str, chunk: int, block: int, **kw: object
) -> None:
    drives = {a.name: load_drive(drive) for a in axes}
    whole = engine_check(MemorySource(open_capture(path)), axes, drives, WHOLE, **kw)
    streamed = engine_check(open_source(str(path), chunk_bytes=chunk), axes, drives, block, **kw)
    assert machine_dict(streamed, 10**6) == machine_dict(whole, 10**6)


@pytest.mark.parametrize(("chunk", "block"), [(7, 1), (64, 5), (1 << 16, 1 << 18)])
@pytest.mark.parametrize(
    ("name", "typ"),
    [("g202-p20-worst-dirhold.vcd", None), ("a4988-spike.vcd", None), ("updown-uniform.vcd", 1),
     ("stepgen1-quadrature.vcd", 2)],
)  # fmt: skip
def test_vcd_blocks(name: str, typ: int | None, chunk: int, block: int) -> None:
    _agree(GOLDEN / name, [AxisMap(None, {})], "gecko-g202", chunk, block,
           step_types={None: typ} if typ is not None else None)  # fmt: skip


@pytest.mark.parametrize(("chunk", "block"), [(4096, 1), (50_000, 7), (1 << 20, 1 << 18)])
def test_sr_blocks(tmp_path: Path, chunk: int, block: int) -> None:
    cap = open_capture(GOLDEN / "g202-p20-worst-dirhold.vcd")  # 1 us ticks: 1 MHz samples
    sr = tmp_path / "g.sr"
    chans = cap.channels
    write_sr_edges(sr, [c.name for c in chans], [c.edges for c in chans],
                   [c.initial for c in chans], cap.end + 1, samplerate=10**6, chunk_bytes=4096)  # fmt: skip
    _agree(sr, [AxisMap(None, {})], "gecko-g202", chunk, block)


SMOOTHIE = GRBL.parent.parent / "smoothieware" / "smoothieware_snippet.sr"


@pytest.mark.skipif(not SMOOTHIE.exists(), reason="shared captures not present")
def test_smoothieware_snippet() -> None:
    names = [c.name for c in open_capture(SMOOTHIE).channels]
    _agree(SMOOTHIE, [AxisMap(None, {"step": names[0], "dir": names[1]})], "gecko-g202", 999, 3)


@pytest.mark.skipif(not GRBL.exists(), reason="shared captures not present")
@pytest.mark.parametrize(("chunk", "block"), [(1 << 16, 1 << 12), (1 << 20, 1 << 18)])
def test_grbl_two_axes(chunk: int, block: int) -> None:
    names = [c.name for c in open_capture(GRBL).channels]
    axes = [
        AxisMap("x", {"step": names[0], "dir": names[1]}),
        AxisMap("y", {"step": names[2], "dir": names[3]}),
    ]
    _agree(GRBL, axes, "gecko-g202", chunk, block)
