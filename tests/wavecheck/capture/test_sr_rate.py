"""A ``.sr`` whose metadata states a sample rate no capture has (issue 34): a warning, and the
capture is still read at the stated rate (the user may give the true one)."""

from __future__ import annotations

import shutil
import subprocess
import zipfile
from fractions import Fraction
from pathlib import Path

import pytest

from tests.conftest import shared_capture
from tests.wavecheck.capture.srutil import write_sr
from wavecheck.capture.open import open_capture
from wavecheck.capture.sr import SrBlocks
from wavecheck.cli import main

SPI = "sigrok-dumps/spi/nes_gamepad/nes_gamepad_generated/b.sr"  # 10 MHz, 500 samples


def _with_rate(src: Path, dst: Path, rate: str) -> Path:
    """``src`` with its metadata's samplerate line replaced, every other member unchanged."""
    with zipfile.ZipFile(src) as zin, zipfile.ZipFile(dst, "w", zipfile.ZIP_DEFLATED) as zout:
        for info in zin.infolist():
            data = zin.read(info)
            if info.filename == "metadata":
                lines = data.decode().splitlines()
                data = (
                    "\n".join(
                        f"samplerate={rate}"
                        if ln.replace(" ", "").startswith("samplerate=")
                        else ln
                        for ln in lines
                    ).encode()
                    + b"\n"
                )
            zout.writestr(info, data)
    return dst


def _warnings(notes: list[str]) -> list[str]:
    return [n for n in notes if n.startswith("warning: ")]


def test_sigrok_cli_writes_5_hz_and_is_warned(tmp_path: Path) -> None:
    """sigrok-cli itself records what it was told: its demo device at 5 Hz."""
    if shutil.which("sigrok-cli") is None:
        pytest.skip("needs sigrok-cli (make system-deps)")
    out = tmp_path / "slow.sr"
    subprocess.run(
        ["sigrok-cli", "-d", "demo", "--config", "samplerate=5", "--samples", "20", "-o", str(out)],
        check=True, capture_output=True, timeout=60,
    )  # fmt: skip
    cap = open_capture(out)
    assert cap.samplerate_hz == 5
    (warning,) = _warnings(cap.notes)
    assert "samplerate=5 Hz" in warning and "20 samples would last 4 s" in warning
    assert "--samplerate" in warning


def test_a_real_spi_capture_stated_at_5_hz(tmp_path: Path) -> None:
    cap = open_capture(_with_rate(shared_capture(SPI), tmp_path / "spi-5hz.sr", "5 Hz"))
    (warning,) = _warnings(cap.notes)
    assert "500 samples would last 100 s" in warning and "below 1 kHz" in warning
    # the true rate given: no warning, and the note says whose rate is used
    fixed = open_capture(tmp_path / "spi-5hz.sr", samplerate=10**7)
    assert not _warnings(fixed.notes) and fixed.duration_s == Fraction(500, 10**7)


def test_the_unchanged_capture_is_not_warned() -> None:
    assert not _warnings(open_capture(shared_capture(SPI)).notes)


def test_a_length_of_days_is_warned(tmp_path: Path) -> None:
    """1 kHz is a rate some analyzer has, but 90 M samples of it last 25 h."""
    path = write_sr(tmp_path / "long.sr", b"", samplerate="1 kHz", members={})
    with zipfile.ZipFile(path, "a", zipfile.ZIP_DEFLATED) as zf, zf.open("logic-1-1", "w") as f:
        for _ in range(90):
            f.write(bytes(1 << 20))
    (warning,) = _warnings(SrBlocks(path).skeleton.notes)
    assert "would last 26.2 h" in warning and "unlikely length" in warning


def test_the_report_prints_it_as_a_warning(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = _with_rate(shared_capture(SPI), tmp_path / "spi-5hz.sr", "5 Hz")
    main(["info", str(path)])
    out = capsys.readouterr().out
    assert "\nwarning: the metadata states samplerate=5 Hz" in out
    assert "note: warning" not in out
