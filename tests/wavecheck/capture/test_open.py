"""open_capture: reader choice by content/extension/--input-format, and bad paths."""

from __future__ import annotations

from fractions import Fraction
from pathlib import Path

import pytest

from tests.conftest import write_vcd
from tests.wavecheck.capture.srutil import write_sr
from wavecheck.capture.open import detect_format, open_capture
from wavecheck.capture.sigrokcli import find_sigrok_cli
from wavecheck.errors import CaptureError, UsageError


def test_reader_by_content(tmp_path: Path) -> None:
    sr = write_sr(tmp_path / "x.dat", bytes([0, 1, 1, 0]))
    vcd = write_vcd(tmp_path / "y.txt", {"STEP": (0, [5, 9])})
    assert detect_format(sr) == "sr" and open_capture(sr).format == "sr"
    assert detect_format(vcd) == "vcd" and open_capture(vcd).channel("STEP").edges.tolist() == [
        5,
        9,
    ]


@pytest.mark.parametrize(
    ("name", "content", "match"),
    [
        ("e.sr", b"", "the file is empty"),
        ("e.vcd", b"  \n", "the file is empty"),
        ("g.sr", b"garbage\n", "is not a sigrok .sr"),
        ("g.vcd", b"garbage\n", "is not a VCD"),
        ("g.xyz", b"garbage\n", "cannot be told.*--input-format"),
    ],
)
def test_bad_files(tmp_path: Path, name: str, content: bytes, match: str) -> None:
    (tmp_path / name).write_bytes(content)
    with pytest.raises(CaptureError, match=match) as info:
        open_capture(tmp_path / name)
    assert str(tmp_path / name) in str(info.value)


def test_missing_and_folder(tmp_path: Path) -> None:
    with pytest.raises(CaptureError, match="no such file"):
        open_capture(tmp_path / "nope.sr")
    with pytest.raises(CaptureError, match="folder"):
        open_capture(tmp_path)
    with pytest.raises(CaptureError, match="no such file"):
        open_capture(tmp_path / "nope.sr", input_format="sr")


def test_explicit_format_and_options(tmp_path: Path) -> None:
    vcd = write_vcd(tmp_path / "y.log", {"STEP": (1, [5])})
    cap = open_capture(vcd, input_format="vcd", samplerate=Fraction(10**8))
    assert cap.resolution_ticks == 10 and cap.samplerate_hz == 10**8
    with pytest.raises(UsageError, match="positive"):
        open_capture(vcd, samplerate=Fraction(0))


def test_options_on_a_native_format_are_not_dropped(tmp_path: Path) -> None:
    """--input-format 'vcd:downsample=2' names sigrok-cli input options: they must be used (the
    VCD goes through sigrok-cli), not silently ignored by the native reader."""
    vcd = write_vcd(tmp_path / "a.vcd", {"STEP": (0, [10, 20, 30])}, "1 us", end=40)
    if find_sigrok_cli() is not None:
        cap = open_capture(vcd, input_format="vcd:downsample=2:skip=0")
        assert cap.format == "sigrok:vcd" and cap.samplerate_hz == 500_000
        assert cap.channel("STEP").edges.tolist() == [5, 10, 15]
    with pytest.raises(UsageError, match="sr.*no options"):
        open_capture(write_sr(tmp_path / "a.sr", bytes([0, 1])), input_format="sr:foo=1")
