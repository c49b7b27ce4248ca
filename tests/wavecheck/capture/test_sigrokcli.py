"""sigrok-cli: other formats through a temporary .sr, its lies caught, and cross-checks."""

from __future__ import annotations

import os
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest

from tests.conftest import write_vcd
from wavecheck.capture.open import open_capture
from wavecheck.capture.sigrokcli import convert, find_sigrok_cli, read_with_sigrok, show
from wavecheck.capture.sr import read_sr
from wavecheck.capture.vcd import read_vcd
from wavecheck.errors import CaptureError

pytestmark = pytest.mark.sigrok


@pytest.fixture(autouse=True)
def _need_sigrok() -> None:
    if find_sigrok_cli() is None:
        if os.environ.get("CI") == "true":
            pytest.fail("sigrok-cli missing in CI")
        pytest.skip("sigrok-cli not installed")


def test_grbl_to_vcd_by_sigrok_reads_back_identical(grbl_sr: Path, tmp_path: Path) -> None:
    native = read_sr(grbl_sr)
    vcd = read_vcd(convert(grbl_sr, tmp_path / "grbl.vcd", output_format="vcd"))
    assert [c.name for c in vcd.channels] == [c.name for c in native.channels]
    assert vcd.samplerate_hz == native.samplerate_hz  # from sigrok's $comment
    ratio = native.timebase.tick_s / vcd.timebase.tick_s
    assert ratio.denominator == 1
    assert vcd.duration_s == native.duration_s
    for a, b in zip(vcd.channels, native.channels, strict=True):
        assert a.initial == b.initial
        np.testing.assert_array_equal(a.edges, b.edges * int(ratio))
    assert vcd.resolution_ticks * vcd.timebase.tick_s == native.timebase.tick_s


def test_show_sample_count_matches_native(grbl_sr: Path) -> None:
    info = show(grbl_sr)
    cap = read_sr(grbl_sr)
    assert (info.sample_count, info.samplerate) == (cap.end, cap.samplerate_hz)


def test_binary_input(tmp_path: Path) -> None:
    rng = np.random.default_rng(7)
    bits = (np.cumsum(rng.random((500, 2)) < 0.2, axis=0) % 2).astype(np.uint8)
    raw = (bits[:, 0] | (bits[:, 1] << 1)).astype(np.uint8)
    path = tmp_path / "x.bin"
    path.write_bytes(raw.tobytes())
    cap = open_capture(path, input_format="binary:numchannels=2", samplerate=Fraction(10**6))
    assert cap.format == "sigrok:binary" and cap.samplerate_hz == 10**6 and cap.path == str(path)
    for i, ch in enumerate(cap.channels):
        assert ch.initial == bits[0, i]
        assert ch.edges.tolist() == (np.flatnonzero(np.diff(bits[:, i].astype(int))) + 1).tolist()
    with pytest.raises(CaptureError, match="x.bin: .*no sample rate.*--samplerate"):
        open_capture(path, input_format="binary:numchannels=2")


def test_vcd_through_sigrok_matches_native(tmp_path: Path) -> None:
    path = write_vcd(tmp_path / "a.vcd", {"STEP": (0, [10, 12, 40, 41]), "DIR": (1, [30])}, "1 us")
    native = read_vcd(path)
    via = read_with_sigrok(path, "vcd:skip=0")
    assert via.samplerate_hz == 10**6
    for a, b in zip(via.channels, native.channels, strict=True):
        assert (a.name, a.initial, a.edges.tolist()) == (b.name, b.initial, b.edges.tolist())


@pytest.mark.parametrize(
    ("fmt", "content", "match"),
    [
        ("csv", b"garbage\n", "x.dat: sigrok-cli: "),
        ("nosuchformat", b"\0\1", "x.dat: sigrok-cli: failed: .*nosuchformat"),
        ("binary:bogus=1", b"\0\1", "x.dat: sigrok-cli: failed"),
    ],
)
def test_failures_become_capture_errors(
    tmp_path: Path, fmt: str, content: bytes, match: str
) -> None:
    path = tmp_path / "x.dat"
    path.write_bytes(content)
    with pytest.raises(CaptureError, match=match) as info:
        open_capture(path, input_format=fmt, samplerate=Fraction(1000))
    assert "\n" not in str(info.value)
