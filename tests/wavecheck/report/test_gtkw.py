"""GTKWave save files: markers at the violations, signals by their VCD names, a VCD for .sr."""

from __future__ import annotations

import re
from fractions import Fraction
from pathlib import Path

from tests.conftest import write_vcd
from tests.wavecheck.report.traces import stepgen_trace, write_stepgen_vcd
from tests.wavecheck.waves import capture, g202
from wavecheck.capture.open import open_capture
from wavecheck.engine import run_check
from wavecheck.report import gtkw
from wavecheck.report.gtkw import vcd_timescale, write_gtkw


def _markers(text: str) -> list[int]:
    line = next(ln for ln in text.splitlines() if ln.startswith("*"))
    return [int(v) for v in line.split()[1:] if v != "-1"]


def test_vcd_capture_is_opened_as_is(tmp_path: Path) -> None:
    vcd = write_stepgen_vcd(tmp_path / "run.vcd")
    report = run_check(open_capture(vcd), g202())
    out = tmp_path / "run.gtkw"
    assert write_gtkw(report, out) is None
    text = out.read_text()
    assert f'[dumpfile] "{vcd}"' in text
    assert "+{STEP} top.STEP" in text and "+{DIR} top.DIR" in text
    # primary marker + A + B at the three dir_hold violations (1 ns timescale: ns)
    starts = [v.start_tick for v in report.violations()]
    assert _markers(text) == starts
    assert text.count("dir_hold FAIL") == 3


def test_markers_follow_the_vcd_time_unit(tmp_path: Path) -> None:
    trace = stepgen_trace()
    ten_ns = {k: (init, [t // 10 for t in edges]) for k, (init, edges) in trace.items()}
    vcd = write_vcd(tmp_path / "run.vcd", ten_ns, timescale="10 ns")
    report = run_check(open_capture(vcd), g202())
    out = tmp_path / "run.gtkw"
    write_gtkw(report, out)
    # GTKWave counts in the unit (ns), not in timescale steps
    assert _markers(out.read_text()) == [10 * v.start_tick for v in report.violations()]


def test_non_vcd_capture_gets_a_vcd_beside_the_save_file(tmp_path: Path) -> None:
    vcd = write_stepgen_vcd(tmp_path / "src.vcd")
    cap = open_capture(vcd)
    cap.format = "sr"  # as if read from a .sr: the save file cannot open it directly
    report = run_check(cap, g202(), {"step": "STEP", "dir": "DIR"}, invert=["step"])
    out = tmp_path / "out" / "run.gtkw"
    out.parent.mkdir()
    written = write_gtkw(report, out)
    assert written == out.with_suffix(".vcd")
    text = out.read_text()
    assert f'[dumpfile] "{written}"' in text
    assert re.search(r"^@68\n\+\{STEP\} wavecheck\.step$", text, re.M)  # 0x40 = invert
    # the VCD written holds the raw channels: reading it back gives the same edges
    back = open_capture(written)
    assert [c.name for c in back.channels] == ["step", "dir"]
    for ch, orig in zip(back.channels, (cap.channel("STEP"), cap.channel("DIR")), strict=True):
        assert ch.initial == orig.initial
        assert list(ch.edges) == list(orig.edges)
    assert sorted(p.name for p in out.parent.iterdir()) == ["run.gtkw", "run.vcd"]


def test_sr_like_capture_at_2mhz(tmp_path: Path) -> None:
    # 500 ns ticks: the VCD beside is on a 100 ns timescale (5 steps a tick), markers in ns
    trace = stepgen_trace()
    cap = capture(
        {k: (init, [t // 500 for t in edges]) for k, (init, edges) in trace.items()},
        tick_ns=500,
        resolution_ticks=1,
    )
    cap.format = "sr"
    report = run_check(cap, g202())
    out = tmp_path / "run.gtkw"
    vcd = write_gtkw(report, out)
    assert vcd is not None and "$timescale 100 ns $end" in vcd.read_text()
    assert _markers(out.read_text()) == [500 * v.start_tick for v in report.violations()]
    back = open_capture(vcd)
    assert list(back.channel("step").edges) == [5 * t for t in cap.channel("STEP").edges]


def test_vcd_timescale() -> None:
    assert vcd_timescale(Fraction(1, 2_000_000)) == (100, "ns", 5)  # 2 MHz: 500 ns
    assert vcd_timescale(Fraction(1, 10**9)) == (1, "ns", 1)
    assert vcd_timescale(Fraction(1, 24_000_000)) == (1, "ps", Fraction(125_000, 3))  # rounded


def test_header_names_come_from_the_shared_vcd_header(tmp_path: Path) -> None:
    vcd = tmp_path / "two.vcd"
    vcd.write_text(
        "$timescale 100 ps $end\n$scope module top $end\n$scope module x $end\n"
        "$var wire 1 ! step $end\n$upscope $end\n$scope module y $end\n"
        '$var wire 1 " step $end\n$var wire 1 # dir $end\n$upscope $end\n$upscope $end\n'
        '$enddefinitions $end\n#0\n0!\n0"\n0#\n#10\n'
    )
    names, magnitude = gtkw._vcd_header_names(str(vcd))
    assert magnitude == 100
    assert names["dir"] == "top.y.dir" and names["top.x.step"] == "top.x.step"
    assert "step" not in names  # two leaves named step: only their full names
