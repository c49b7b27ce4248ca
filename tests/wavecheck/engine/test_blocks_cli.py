"""``wavecheck check`` streams a .sr or VCD by default; ``--no-stream`` (the whole-capture path)
prints the same JSON, for one axis and several, at any ``--block-edges``."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[3]
GOLDEN = ROOT / "captures" / "golden"
GRBL = ROOT.parent / "shared/captures/sigrok-dumps/stepper_motor/grbl_cnc/grbl_cnc_1.sr"


def _check(*args: str) -> tuple[int, str]:
    p = subprocess.run(
        [sys.executable, "-m", "wavecheck", "check", *args, "--format", "json", "-q"],
        capture_output=True, text=True, cwd=ROOT,
    )  # fmt: skip
    assert not p.stderr, p.stderr
    return p.returncode, p.stdout


@pytest.mark.parametrize("block", ["1", "5", "262144"])
def test_golden_streamed_equals_whole(block: str) -> None:
    args = [str(GOLDEN / "g202-p20-worst-dirhold.vcd"), "--drive", "gecko-g202"]
    assert _check(*args, "--block-edges", block) == _check(*args, "--no-stream")


@pytest.mark.skipif(not GRBL.exists(), reason="shared captures not present")
def test_grbl_two_axes_streamed_equals_whole() -> None:
    args = [
        str(GRBL),
        "--drive",
        "gecko-g202",
        "--map",
        "x.step=0,x.dir=1",
        "--map",
        "y.step=2,y.dir=3",
    ]
    assert _check(*args, "--block-edges", "4096") == _check(*args, "--no-stream")


def test_block_edges_must_be_positive() -> None:
    p = subprocess.run(
        [sys.executable, "-m", "wavecheck", "check", str(GOLDEN / "stepgen0.vcd"), "--drive",
         "gecko-g202", "--block-edges", "0"],
        capture_output=True, text=True, cwd=ROOT,
    )  # fmt: skip
    assert p.returncode == 2 and "--block-edges must be 1 or more" in p.stderr


@pytest.mark.skipif(not GRBL.exists(), reason="shared captures not present")
def test_the_samples_are_read_once_for_every_axis(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    from wavecheck.capture.sr import SrBlocks
    from wavecheck.cli import _capture_args, main

    passes = []
    real = SrBlocks.blocks

    def counting(self: SrBlocks):  # type: ignore[no-untyped-def]
        passes.append(self.wanted)
        return real(self)

    monkeypatch.setattr(SrBlocks, "blocks", counting)
    monkeypatch.setattr(_capture_args, "open_capture", None)  # the whole path is not taken
    main(
        [
            "check",
            str(GRBL),
            "--drive",
            "gecko-g202",
            "--map",
            "x.step=0,x.dir=1",
            "--map",
            "y.step=2,y.dir=3",
        ]
    )
    assert passes == [{0, 1, 2, 3}]  # one pass; only the mapped channels' edges extracted
    capsys.readouterr()
