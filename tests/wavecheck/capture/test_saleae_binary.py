"""Saleae Logic 2's digital binary export (issue 16), read natively: Saleae's documented layout
(versions 0 and 1), the exact rate from the file, detection by the ``<SALEAE>`` magic, a folder
of ``digital_N.bin`` files as one capture, gaps between chunks as unknown stretches."""

from __future__ import annotations

import json
import struct
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest

from tests.conftest import write_vcd
from wavecheck.capture.edges import NEVER
from wavecheck.capture.open import detect_format, open_capture
from wavecheck.capture.saleae_binary import read_saleae_binary
from wavecheck.cli import main
from wavecheck.errors import CaptureError

RATE = 10_000_000  # 10 MHz: 100 ns samples


def chunk_v1(initial: int, rate: float, begin: float, end: float, times: list[float]) -> bytes:
    """One version-1 chunk as Saleae's article lays it out (written here, not by the reader)."""
    return struct.pack("<IdddQ", initial, rate, begin, end, len(times)) + struct.pack(
        f"<{len(times)}d", *times
    )


def file_v1(chunks: list[bytes], kind: int = 0) -> bytes:
    return b"<SALEAE>" + struct.pack("<iiQ", 1, kind, len(chunks)) + b"".join(chunks)


def file_v0(initial: int, begin: float, end: float, times: list[float]) -> bytes:
    return (b"<SALEAE>" + struct.pack("<iiIddQ", 0, 0, initial, begin, end, len(times))
            + struct.pack(f"<{len(times)}d", *times))  # fmt: skip


def _seconds(samples: list[int], begin: float = -0.25) -> list[float]:
    """Sample numbers as Logic 2 writes times: doubles, relative to the trigger."""
    return [begin + k / RATE for k in samples]


STEP = [100, 150, 500, 550, 900, 950]  # 5 us pulses every 40 us
DIR = [700]


def _export(folder: Path) -> Path:
    folder.mkdir()
    (folder / "digital_0.bin").write_bytes(
        file_v1([chunk_v1(0, RATE, -0.25, -0.25 + 1200 / RATE, _seconds(STEP))])
    )
    (folder / "digital_1.bin").write_bytes(
        file_v1([chunk_v1(1, RATE, -0.25, -0.25 + 1200 / RATE, _seconds(DIR))])
    )
    (folder / "analog_2.bin").write_bytes(b"<SALEAE>" + struct.pack("<ii", 1, 1))
    return folder


def test_folder_export_exact_ticks_and_rate(tmp_path: Path) -> None:
    cap = open_capture(_export(tmp_path / "export"))
    assert cap.format == "saleae-bin" and cap.samplerate_hz == RATE and cap.timebase.tick_ns == 100
    assert [c.name for c in cap.channels] == ["Channel 0", "Channel 1"]
    assert cap.channels[0].edges.tolist() == STEP and cap.channels[0].initial == 0
    assert cap.channels[1].edges.tolist() == DIR and cap.channels[1].initial == 1
    assert cap.end == 1200 and cap.resolution_ticks == 1
    assert any("skipped 1 analog" in n for n in cap.notes)


def test_detected_by_content(tmp_path: Path) -> None:
    folder = _export(tmp_path / "export")
    assert detect_format(folder) == "saleae-bin"
    other = tmp_path / "whatever.dat"
    other.write_bytes((folder / "digital_0.bin").read_bytes())
    assert detect_format(other) == "saleae-bin"
    assert open_capture(other).channels[0].edges.tolist() == STEP  # one file: one channel


def test_check_of_the_export_equals_the_same_vcd(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The same edges written as a VCD at the sample period give the same rule figures."""
    folder = _export(tmp_path / "export")
    vcd = write_vcd(tmp_path / "same.vcd", {"S": (0, STEP), "D": (1, DIR)}, "100 ns", end=1200)
    main(["check", str(folder), "--drive", "gecko-g202", "--map", "step=Channel 0,dir=Channel 1",
          "--format", "json"])  # fmt: skip
    a = json.loads(capsys.readouterr().out)
    main(["check", str(vcd), "--drive", "gecko-g202", "--map", "step=S,dir=D", "--samplerate",
          "10MHz", "--format", "json"])  # fmt: skip
    b = json.loads(capsys.readouterr().out)
    assert a["verdict"] == b["verdict"]
    keys = ("id", "checked", "failed", "min_measured_ns", "min_margin_ns")
    assert [{k: r.get(k) for k in keys} for r in a["rules"]] == [
        {k: r.get(k) for k in keys} for r in b["rules"]
    ]


def test_version_0_needs_the_rate(tmp_path: Path) -> None:
    path = tmp_path / "digital_3.bin"
    path.write_bytes(file_v0(0, 0.0, 1200 / RATE, _seconds(STEP, 0.0)))
    with pytest.raises(CaptureError, match="version 0 export states no sample rate.*--samplerate"):
        read_saleae_binary(path)
    cap = read_saleae_binary(path, samplerate=Fraction(RATE))
    assert cap.channels[0].name == "Channel 3" and cap.channels[0].edges.tolist() == STEP
    with pytest.raises(CaptureError, match="not on the grid"):
        read_saleae_binary(path, samplerate=Fraction(RATE * 4, 3))  # the wrong rate


def test_gap_between_chunks_is_unknown_not_bridged(tmp_path: Path) -> None:
    """Version 1: a gap (samples 400–800 missing) is an unknown stretch; the level after it
    differs, so an edge sits at its end; the other channel, shorter, is unknown to the end."""
    folder = tmp_path / "gap"
    folder.mkdir()
    first = chunk_v1(0, RATE, 0.0, 400 / RATE, [100 / RATE, 150 / RATE, 300 / RATE])  # ends high
    second = chunk_v1(0, RATE, 800 / RATE, 1200 / RATE, [900 / RATE, 950 / RATE])
    (folder / "digital_0.bin").write_bytes(file_v1([first, second]))
    (folder / "digital_1.bin").write_bytes(file_v1([chunk_v1(0, RATE, 0.0, 1000 / RATE, [])]))
    cap = open_capture(folder)
    step, other = cap.channels
    assert step.edges.tolist() == [100, 150, 300, 800, 900, 950]
    assert step.xz_times.tolist() == [400] and step.xz_ends.tolist() == [800]
    assert other.xz_times.tolist() == [1000] and other.xz_ends.tolist() == [NEVER]
    assert cap.end == 1200


@pytest.mark.parametrize(
    ("data", "match"),
    [
        (b"<SALEAE>" + struct.pack("<ii", 1, 1), "analog export"),
        (b"<SALEAE>" + struct.pack("<ii", 7, 0), "version 7 is not known"),
        (b"<SALEAE>" + struct.pack("<iiQ", 1, 0, 1) + struct.pack("<IdddQ", 0, RATE, 0, 1, 10**12),
         "declares 1000000000000 transitions"),
        (file_v1([chunk_v1(0, RATE, 0.0, 1.0, [0.5, 0.25])]), "do not increase"),
        (file_v1([chunk_v1(0, RATE, 0.0, 1.0, [0.5])])[:-3], "declares 1 transitions, more than the 5 bytes"),
        (file_v1([chunk_v1(0, RATE, 0.0, 1.0, [0.5])]) + b"xx", "2 bytes follow the data"),
        (file_v1([chunk_v1(0, RATE, 0.0, 1.0, [0.5 + 0.3 / RATE])]), "not on the grid"),
    ],
)  # fmt: skip
def test_bad_files_are_refused_in_one_line(tmp_path: Path, data: bytes, match: str) -> None:
    path = tmp_path / "digital_0.bin"
    path.write_bytes(data)
    with pytest.raises(CaptureError, match=match) as info:
        open_capture(path)
    assert "\n" not in str(info.value) and str(path) in str(info.value)


def test_info_on_the_folder(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    folder = _export(tmp_path / "export")
    assert main(["info", str(folder), "--format", "json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert [c["edges"] for c in doc["channels"]] == [6, 1]
    assert np.isclose(doc["duration_s"], 1200 / RATE)
