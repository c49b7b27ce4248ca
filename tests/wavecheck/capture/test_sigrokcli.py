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
    cap = read_with_sigrok(path, "binary:numchannels=2", samplerate=Fraction(10**6))
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
        ("csv:bogus=1", b"a\n1\n", "x.dat: sigrok-cli: failed"),
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


# --- issue 12: CSV conversions are checked, and sigrok-cli's own CSV is understood ------------


def test_csv_written_by_sigrok_cli_gives_rate_and_names(smoothie_sr: Path, tmp_path: Path) -> None:
    """``sigrok-cli -i X.sr -O csv`` states "; Samplerate: 12 MHz" and "; Channels (8/8): 0, …"
    (its header row says ``logic`` for every column): both are used, and the capture equals the
    native read of the .sr (it was refused for want of a rate, and every channel was ``logic``)."""
    csv = convert(smoothie_sr, tmp_path / "smoothie.csv", output_format="csv")
    head = csv.read_bytes()[:400].decode()
    assert "; Samplerate: 12 MHz" in head and "logic,logic" in head
    cap = open_capture(csv)
    native = read_sr(smoothie_sr)
    assert cap.samplerate_hz == native.samplerate_hz == 12_000_000
    assert [c.name for c in cap.channels] == [c.name for c in native.channels]
    assert cap.end == native.end
    for a, b in zip(cap.channels, native.channels, strict=True):
        assert a.initial == b.initial
        np.testing.assert_array_equal(a.edges, b.edges)
    assert any("Samplerate" in n for n in cap.notes) and any("Channels" in n for n in cap.notes)


@pytest.mark.parametrize(
    "body",
    [
        b"1,0\n0,1\n1,\x001\n0,0\n1,0\n",
        b"1,0\n0,1\n\x001,1\n0,0\n1,0\n",
        b"1,0\n0,1\n1,1\n\x00\n0,0\n",
    ],
    ids=["mid-line", "line-start", "own-line"],
)
def test_csv_with_nul_byte_is_refused(tmp_path: Path, body: bytes) -> None:
    """sigrok-cli stops at a NUL without a word (2 or 3 of 5 rows, exit 0): the rest of the
    capture would go unchecked, so the file is refused, naming the byte."""
    path = tmp_path / "nul.csv"
    path.write_bytes(b"STEP,DIR\n" + body)
    with pytest.raises(CaptureError, match=f"byte {path.read_bytes().index(0)}: is a NUL byte"):
        open_capture(path, samplerate=Fraction(1000))


def test_csv_first_row_taken_as_header_is_refused(tmp_path: Path) -> None:
    """Without a header line sigrok-cli silently eats the first row of samples as channel
    names: refused with the fix; with ``csv:header=false`` every row is a sample."""
    path = tmp_path / "nohdr.csv"
    path.write_bytes(b"1,0\n0,1\n1,1\n0,0\n1,0\n")
    with pytest.raises(CaptureError, match="header=false"):
        open_capture(path, samplerate=Fraction(1000))
    cap = open_capture(path, samplerate=Fraction(1000), input_format="csv:header=false")
    assert cap.end == 5 and cap.channels[0].edges.tolist() == [1, 2, 3, 4]


def test_utf8_channel_names_in_sigrok_cli_vcd(tmp_path: Path) -> None:
    """sigrok-cli writes a probe named ``STÉP`` into its VCD as UTF-8: the name is read as
    ``STÉP`` (it was latin-1 mojibake, ``STÃ\\x89P``) and can be mapped."""
    from wavecheck.capture.srzip import write_sr_edges

    src = tmp_path / "utf8.sr"
    edges = [np.array([10, 12, 20, 22], dtype=np.int64), np.array([15], dtype=np.int64)]
    write_sr_edges(src, ["STÉP", "DIR→"], edges, [0, 0], 30, samplerate=1_000_000)
    vcd = convert(src, tmp_path / "utf8.vcd", output_format="vcd")
    assert "STÉP".encode() in vcd.read_bytes()
    cap = read_vcd(vcd)
    assert [c.name for c in cap.channels] == ["STÉP", "DIR→"]
    assert not any("latin-1" in n for n in cap.notes)
    scale = int(read_sr(src).timebase.tick_s / cap.timebase.tick_s)
    assert cap.channel("STÉP").edges.tolist() == [t * scale for t in (10, 12, 20, 22)]
    from wavecheck.steps.interface import build_interface

    iface = build_interface(cap, {"step": "STÉP", "dir": "DIR→"})
    assert iface is not None
