"""The GTKWave save file opens in real GTKWave (Debian's, on a virtual X screen) with the mapped
signals shown, the markers on the worst violations and the worst violation in view.

GTKWave runs a Tcl script (``-S``) that asks it what it loaded and what its window shows (start
and end time, time unit, markers); ``make test`` installs gtkwave and xvfb from Debian's packages.
Outside CI a missing gtkwave skips; in CI it fails.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
from fractions import Fraction
from pathlib import Path

import pytest

from tests.conftest import shared_capture, write_vcd
from tests.wavecheck.report.traces import stepgen_trace
from wavecheck import check
from wavecheck.cli import main
from wavecheck.engine.outcome import Report
from wavecheck.report.gtkw import write_gtkw

REPO = Path(__file__).resolve().parents[3]
LETTERS = "ABCDEFGHIJKLMNOPQRSTUVWXYZ"

_SCRIPT = """\
set out [open "{out}" w]
puts $out "dump [gtkwave::getDumpFileName]"
puts $out "signals [gtkwave::getDisplayedSignals]"
puts $out "start [gtkwave::getWindowStartTime]"
puts $out "end [gtkwave::getWindowEndTime]"
puts $out "unit [gtkwave::getTimeDimension]"
puts $out "primary [gtkwave::getMarker]"
foreach m {{{letters}}} {{ puts $out "named$m [gtkwave::getNamedMarker $m]" }}
close $out
gtkwave::/File/Quit
"""
#: GTKWave's time dimension letter → seconds per unit of its times.
_UNIT_S = {
    "": Fraction(1),
    "m": Fraction(1, 10**3),
    "u": Fraction(1, 10**6),
    "n": Fraction(1, 10**9),
    "p": Fraction(1, 10**12),
    "f": Fraction(1, 10**15),
}


def _gtkwave(save: Path, tmp_path: Path) -> dict[str, str]:
    if not (shutil.which("gtkwave") and shutil.which("xvfb-run")):
        if os.environ.get("CI") == "true":
            pytest.fail("gtkwave/xvfb-run missing in CI (make test installs them)")
        pytest.skip("gtkwave and xvfb-run not installed (apt-get install gtkwave xvfb)")
    out = tmp_path / "gtkwave.out"
    script = tmp_path / "ask.tcl"
    script.write_text(_SCRIPT.format(out=out, letters=" ".join(LETTERS)))
    subprocess.run(
        ["xvfb-run", "-a", "gtkwave", "-S", str(script), str(save)],
        capture_output=True, timeout=120, check=False,
    )  # fmt: skip
    assert out.exists(), "GTKWave did not run the script (the save file did not load)"
    return {k: v for k, _, v in (line.partition(" ") for line in out.read_text().splitlines())}


def _named(seen: dict[str, str]) -> list[int]:
    return [int(seen[f"named{m}"]) for m in LETTERS if int(seen[f"named{m}"]) != -1]


def _assert_shows_worst(seen: dict[str, str], report: Report) -> None:
    """GTKWave's window holds both edges of the worst violation with context either side, at
    a scale where it is visible (at least a tenth of the window), and the primary marker."""
    worst = report.violations(1)[0]
    unit = _UNIT_S[seen["unit"].strip()]
    tb = report.capture.timebase
    first = tb.seconds(worst.start_tick - report.capture.start) / unit
    last = tb.seconds(worst.end_tick - report.capture.start) / unit
    start, end, primary = int(seen["start"]), int(seen["end"]), int(seen["primary"])
    context = max((last - first) / 20, Fraction(1))
    assert start <= first - context and last + context <= end, (start, end, first, last)
    assert last - first >= (end - start) / 10, "zoomed out too far to see the violation"
    assert start <= primary <= end and abs(primary - first) <= 1


@pytest.mark.gtkwave
def test_vcd_capture_opens_on_the_violation(tmp_path: Path) -> None:
    save = tmp_path / "g202.gtkw"
    vcd = REPO / "captures/golden/g202-p20-worst-dirhold.vcd"
    assert main(["check", str(vcd), "--drive", "gecko-g202", "--gtkw", str(save), "-q"]) == 1
    seen = _gtkwave(save, tmp_path)
    assert Path(seen["dump"]).resolve() == vcd.resolve()
    assert seen["signals"].split() == ["stepgen.step", "stepgen.dir"]
    assert int(seen["primary"]) == 485_011_000  # the 9 us dir_hold, in the VCD's 1 ns ticks
    # both edges of the 9 us dir_hold (STEP falls at 485.011 ms, DIR changes at 485.020 ms)
    # with context; the window was 381 ns wide, 53 us before the marker
    start, end = int(seen["start"]), int(seen["end"])
    assert start < 485_011_000 - 1_000 and 485_020_000 + 1_000 < end < 485_011_000 + 100_000
    _assert_shows_worst(seen, check(vcd, "gecko-g202"))


@pytest.mark.gtkwave
def test_sr_capture_opens_through_a_vcd_beside_it(tmp_path: Path) -> None:
    sr = shared_capture("sigrok-dumps/stepper_motor/smoothieware/smoothieware_snippet.sr")
    save = tmp_path / "sm.gtkw"
    argv = ["check", str(sr), "--drive", "gecko-g202", "--map", "step=5,dir=6", "--gtkw", str(save)]
    assert main([*argv, "--format", "json", "-o", str(tmp_path / "r.json"), "-q"]) == 1
    seen = _gtkwave(save, tmp_path)
    assert Path(seen["dump"]).resolve() == (tmp_path / "sm.vcd").resolve()
    assert seen["signals"].split() == ["wavecheck.step", "wavecheck.dir"]
    worst = json.loads((tmp_path / "r.json").read_text())["violations"]
    # the VCD beside a 12 MHz .sr is written in ps; markers are the worst violations' times
    assert seen["unit"].strip() == "p"
    marks = [int(seen["primary"]), *_named(seen)[:3]]
    expected = [round(Fraction(v["time_s"]).limit_denominator(10**12) * 10**12) for v in worst[:4]]
    assert marks == expected
    report = check(sr, "gecko-g202", map={"step": "5", "dir": "6"})
    assert report.capture.start == 0
    _assert_shows_worst(seen, report)


@pytest.mark.gtkwave
@pytest.mark.parametrize(
    ("timescale", "per_ns"), [("1 ps", 10**3), ("1 fs", 10**6), ("10 ns", Fraction(1, 10))]
)
def test_timescales_open_on_the_violation(tmp_path: Path, timescale: str, per_ns: Fraction) -> None:
    # the stepgen-like trace (three 9 us dir_hold violations) in ps, fs or 10 ns steps
    trace = {
        k: (init, [int(t * per_ns) for t in edges]) for k, (init, edges) in stepgen_trace().items()
    }
    vcd = write_vcd(tmp_path / "run.vcd", trace, timescale=timescale)
    report = check(vcd, "gecko-g202")
    assert report.violations(1)[0].measured_ns == 9_000
    save = tmp_path / "run.gtkw"
    assert write_gtkw(report, save) is None
    seen = _gtkwave(save, tmp_path)
    assert seen["unit"].strip() == timescale.split()[1][0]
    _assert_shows_worst(seen, report)


@pytest.mark.gtkwave
@pytest.mark.parametrize("tail_ns", [0, 1_000, 16_000])
def test_violation_at_the_end_of_the_dump(tmp_path: Path, tail_ns: int) -> None:
    # GTKWave opens at time 0 when the window would run past the dump's end: the view must
    # stay inside the dump and still hold the violation (the dump ends tail_ns after DIR changes)
    step_init, step = stepgen_trace()["STEP"]
    dir_init, dirs = stepgen_trace()["DIR"]
    cut = dirs[0]
    trace = {"STEP": (step_init, [t for t in step if t <= cut]), "DIR": (dir_init, [cut])}
    vcd = write_vcd(tmp_path / "run.vcd", trace, end=cut + tail_ns)
    # cut before its first change of speed, STEP is a 50 % clock to the waveform: mapped, as a
    # name alone is no STEP against the waveform (issue 33)
    report = check(vcd, "gecko-g202", map={"step": "STEP", "dir": "DIR"})
    worst = report.violations(1)[0]
    assert worst.rule == "dir_hold" and worst.end_tick == cut
    save = tmp_path / "run.gtkw"
    write_gtkw(report, save)
    seen = _gtkwave(save, tmp_path)
    start, end = int(seen["start"]), int(seen["end"])
    assert start <= worst.start_tick - 1_000 and end <= cut + tail_ns
    if tail_ns:
        assert cut + min(tail_ns, 2_000) // 2 <= end
        _assert_shows_worst(seen, report)
    else:  # the violation ends on the dump's last time: shown up to the last pixel
        assert cut - 50 <= end


@pytest.mark.gtkwave
def test_repeated_identical_violations_get_distinct_markers(tmp_path: Path) -> None:
    # grbl's Y axis against a TB6560: all 10508 pulses fail step_high, most of them alike
    sr = shared_capture("sigrok-dumps/stepper_motor/grbl_cnc/grbl_cnc_1.sr")
    report = check(sr, "tb6560", map={"step": "STEP (Y axis)"})
    assert report.total_violations == 10508
    save = tmp_path / "grbl.gtkw"
    write_gtkw(report, save)
    seen = _gtkwave(save, tmp_path)
    marks = [int(seen["primary"]), *_named(seen)]
    assert len(marks) == 27 and len(set(marks)) == 27
    _assert_shows_worst(seen, report)
