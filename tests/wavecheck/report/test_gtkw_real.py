"""The GTKWave save file opens in real GTKWave (Debian's, on a virtual X screen) with the mapped
signals shown and the markers on the worst violations.

GTKWave runs a Tcl script (``-S``) that asks it what it loaded; ``make test`` installs gtkwave and
xvfb from Debian's packages. Outside CI a missing gtkwave skips; in CI it fails.
"""

from __future__ import annotations

import os
import shutil
import subprocess
from fractions import Fraction
from pathlib import Path

import pytest

from tests.conftest import shared_capture
from wavecheck.cli import main

REPO = Path(__file__).resolve().parents[3]

_SCRIPT = """\
set out [open "{out}" w]
puts $out "dump [gtkwave::getDumpFileName]"
puts $out "signals [gtkwave::getDisplayedSignals]"
puts $out "primary [gtkwave::getMarker]"
foreach m {{A B C}} {{ puts $out "named$m [gtkwave::getNamedMarker $m]" }}
close $out
gtkwave::/File/Quit
"""


def _gtkwave(save: Path, tmp_path: Path) -> dict[str, str]:
    if not (shutil.which("gtkwave") and shutil.which("xvfb-run")):
        if os.environ.get("CI") == "true":
            pytest.fail("gtkwave/xvfb-run missing in CI (make test installs them)")
        pytest.skip("gtkwave and xvfb-run not installed (apt-get install gtkwave xvfb)")
    out = tmp_path / "gtkwave.out"
    script = tmp_path / "ask.tcl"
    script.write_text(_SCRIPT.format(out=out))
    subprocess.run(
        ["xvfb-run", "-a", "gtkwave", "-S", str(script), str(save)],
        capture_output=True, timeout=120, check=False,
    )  # fmt: skip
    assert out.exists(), "GTKWave did not run the script (the save file did not load)"
    return dict(line.split(" ", 1) for line in out.read_text().splitlines())


@pytest.mark.gtkwave
def test_vcd_capture_opens_with_marker_on_the_violation(tmp_path: Path) -> None:
    save = tmp_path / "g202.gtkw"
    vcd = REPO / "captures/golden/g202-p20-worst-dirhold.vcd"
    assert main(["check", str(vcd), "--drive", "gecko-g202", "--gtkw", str(save), "-q"]) == 1
    seen = _gtkwave(save, tmp_path)
    assert Path(seen["dump"]).resolve() == vcd.resolve()
    assert seen["signals"].split() == ["stepgen.step", "stepgen.dir"]
    assert int(seen["primary"]) == 485_011_000  # the 9 us dir_hold, in the VCD's 1 ns ticks


@pytest.mark.gtkwave
def test_sr_capture_opens_through_a_vcd_beside_it(tmp_path: Path) -> None:
    sr = shared_capture("sigrok-dumps/stepper_motor/smoothieware/smoothieware_snippet.sr")
    save = tmp_path / "sm.gtkw"
    argv = ["check", str(sr), "--drive", "gecko-g202", "--map", "step=5,dir=6", "--gtkw", str(save)]
    assert main([*argv, "--format", "json", "-o", str(tmp_path / "r.json"), "-q"]) == 1
    seen = _gtkwave(save, tmp_path)
    assert Path(seen["dump"]).resolve() == (tmp_path / "sm.vcd").resolve()
    assert seen["signals"].split() == ["wavecheck.step", "wavecheck.dir"]
    import json

    worst = json.loads((tmp_path / "r.json").read_text())["violations"]
    # the VCD beside a 12 MHz .sr is written in ps; markers are the worst violations' times
    marks = [int(seen["primary"]), *(int(seen[f"named{m}"]) for m in "ABC")]
    expected = [round(Fraction(v["time_s"]).limit_denominator(10**12) * 10**12) for v in worst[:4]]
    assert marks == expected
