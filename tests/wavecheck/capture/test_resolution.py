"""Resolution of sampled captures (DESIGN.md "Resolution and verdicts"): for every measured
interval W' the true interval must lie in (W' − T', W' + T'), T' = ``resolution_ticks``."""

from __future__ import annotations

from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest

from tests.wavecheck.capture.srutil import write_sr
from wavecheck.capture.edges import Capture
from wavecheck.capture.sigrokcli import convert, find_sigrok_cli
from wavecheck.capture.sr import read_sr
from wavecheck.capture.vcd import read_vcd, read_vcd_reference

SAMPLES = [1, 2, 4, 5, 7, 10, 11, 13, 20, 23, 30, 31, 37, 40]  # edge sample numbers


def _sigrok_style_vcd(path: Path, rate: str, hz: Fraction, timescale: str, tick: Fraction) -> Path:
    """A VCD as sigrok-cli writes one from a .sr: each sample number i at round(i·T / tick)
    (half to even, as observed with libsigrok 0.5.2), the rate in a $comment."""
    stamps = [round(Fraction(i) / hz / tick) for i in [*SAMPLES, 45]]
    lines = [f"$comment\n  Acquisition with 1/1 channels at {rate}\n$end"]
    lines += [f"$timescale {timescale} $end", "$scope module libsigrok $end"]
    lines += ["$var wire 1 ! D0 $end", "$upscope $end", "$enddefinitions $end", "#0 0!"]
    lines += [f"#{t} {k % 2 ^ 1}!" for k, t in enumerate(stamps[:-1])] + [f"#{stamps[-1]}"]
    path.write_text("\n".join(lines) + "\n")
    return path


def _assert_sound(cap: Capture, true_s: list[Fraction], period_s: Fraction) -> None:
    """Every interval between two edges: its true length (sample period T: an edge seen at sample
    i is in ((i−1)T, iT]) must be within the resolution of the measured one."""
    (ch,) = cap.channels
    t = [cap.timebase.seconds(int(e)) for e in ch.edges]
    res = cap.timebase.seconds(cap.resolution_ticks)
    for a in range(len(t)):
        for b in range(a + 1, len(t)):
            measured = t[b] - t[a]
            true_lo = true_s[b] - true_s[a] - period_s
            true_hi = true_s[b] - true_s[a] + period_s
            assert measured - res <= true_lo and true_hi <= measured + res, (a, b)


@pytest.mark.parametrize(
    ("rate", "hz", "timescale", "tick"),
    [
        ("3 MHz", Fraction(3_000_000), "1 ns", Fraction(1, 10**9)),
        ("7 kHz", Fraction(7000), "1 us", Fraction(1, 10**6)),
        ("1.234567 MHz", Fraction(1_234_567), "1 ns", Fraction(1, 10**9)),
        ("333 kHz", Fraction(333_000), "10 ns", Fraction(1, 10**8)),
        ("3.2 MHz", Fraction(3_200_000), "1 ns", Fraction(1, 10**9)),
        ("12.5 MHz", Fraction(12_500_000), "10 ns", Fraction(1, 10**8)),
    ],
)
def test_sigrok_vcd_with_rounded_timestamps_is_conservative(
    tmp_path: Path, rate: str, hz: Fraction, timescale: str, tick: Fraction
) -> None:
    path = _sigrok_style_vcd(tmp_path / "s.vcd", rate, hz, timescale, tick)
    for cap in (read_vcd(path), read_vcd_reference(path)):
        assert cap.samplerate_hz == hz
        assert len(cap.channels[0].edges) == len(SAMPLES)
        _assert_sound(cap, [Fraction(i) / hz for i in SAMPLES], 1 / hz)


@pytest.mark.parametrize("rate", ["7 kHz", "1.234567 MHz", "3 MHz", "2 MHz"])
def test_vcd_written_by_sigrok_cli_from_sr(tmp_path: Path, rate: str) -> None:
    if find_sigrok_cli() is None:
        pytest.skip("sigrok-cli not installed")
    bits = np.zeros(45, dtype=np.uint8)
    level = 0
    for k in range(45):
        level ^= int(k in SAMPLES)
        bits[k] = level
    sr = read_sr(write_sr(tmp_path / "a.sr", bits, samplerate=rate, probes={0: "D0"}, total=1))
    vcd = read_vcd(convert(tmp_path / "a.sr", tmp_path / "a.vcd", output_format="vcd"))
    assert sr.channels[0].edges.tolist() == SAMPLES
    assert vcd.samplerate_hz == sr.samplerate_hz
    # the end timestamp is rounded to the timescale like every other
    assert abs(vcd.duration_s - sr.duration_s) <= vcd.timebase.tick_s / 2
    period = sr.timebase.tick_s
    _assert_sound(vcd, [i * period for i in SAMPLES], period)


def test_vcd_resolution_never_finer_than_the_sample_period(tmp_path: Path) -> None:
    path = _sigrok_style_vcd(
        tmp_path / "s.vcd", "200 kHz", Fraction(200_000), "1 us", Fraction(1, 10**6)
    )
    assert read_vcd(path).resolution_ticks == 5
    for res in (Fraction(1, 10**6), Fraction(0)):
        cap = read_vcd(path, resolution_s=res)
        assert cap.resolution_ticks == 5
        assert any("sample period" in n for n in cap.notes)
    assert read_vcd(path, resolution_s=Fraction(8, 10**6)).resolution_ticks == 8
    # the user's sample rate counts the same way
    cap = read_vcd(path, samplerate=Fraction(100_000), resolution_s=Fraction(2, 10**6))
    assert cap.resolution_ticks == 10


def test_sr_resolution_finer_than_a_sample_is_raised_with_a_note(tmp_path: Path) -> None:
    path = write_sr(tmp_path / "a.sr", bytes([0, 1, 0, 1]), samplerate="1 MHz")
    cap = read_sr(path, resolution_s=Fraction(1, 10**7))
    assert cap.resolution_ticks == 1
    assert any("sample period" in n for n in cap.notes)
    assert read_sr(path, resolution_s=Fraction(25, 10**7)).resolution_ticks == 3
