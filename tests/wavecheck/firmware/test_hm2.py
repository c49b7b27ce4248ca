"""hm2 figures and fixes at a known stepgen clock (``--hm2-clock``, issue 32).

The hm2 driver turns each ns parameter into a register with C doubles, truncating, at most 0x3FFF
(LinuxCNC ``src/hal/drivers/mesa-hostmot2/stepgen.c`` 348-387 at git f1270d6ed7), so a printed
fix is a ns value the driver turns into the clocks the rule needs; applied to a copy, the rule
no longer fails at that clock."""

from __future__ import annotations

import json
from fractions import Fraction as F
from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

from tests.wavecheck.firmware.fixapply import apply, copy_case
from tests.wavecheck.firmware.test_fixes_work import _drives
from tools.firmware_corpus import CORPUS
from wavecheck.cli import main
from wavecheck.firmware import read_firmware
from wavecheck.firmware.evaluate import evaluate_config
from wavecheck.firmware.hm2 import ns_for, register

MESA = CORPUS / "linuxcnc/configs/by_interface/mesa"
HM2 = [MESA / "plasma-5i20/plasma-5i20.ini", MESA / "hm2-modbus/7i96s-modbus-bldc.ini"]
CLOCKS = [F(33_000_000), F(50_000_000), F(100_000_000), F(40_000_000)]


@given(st.integers(0, 0x3FFF), st.sampled_from(CLOCKS + [F(48_000_000), F(125_000_000)]))
def test_ns_for_gives_the_register(clocks: int, f: F) -> None:
    """The ns printed is the smallest whole ns the driver's double arithmetic turns into
    exactly ``clocks`` (``reg = ns * (f / 1e9)``, truncated: stepgen.c 381)."""
    ns = ns_for(clocks, f)
    assert register(F(ns), f) == clocks and (ns == 0 or register(F(ns - 1), f) < clocks)
    assert int(float(ns) * (float(f) / 1e9)) == clocks  # the C expression, with doubles


def test_figures_at_the_clock() -> None:
    """plasma-5i20 at 33 MHz: STEPLEN 1000 -> 33 clocks, held 34; STEPSPACE 2000 -> 66 -> 67;
    DIRHOLD 200 -> 6 clocks, DIR may change 7 clocks after the rising edge (kubstepgenz.vhd
    212-219) while STEP is still high: 0 from the trailing edge."""
    s = read_firmware(HM2[0], clock_hz=F(33_000_000)).axis("stepgen.00")
    f = F(33_000_000)
    assert s.pulse.value == 34 * 10**9 / f and s.idle.value == 67 * 10**9 / f
    assert s.dir_hold.value == 7 * 10**9 / f and s.dir_hold_trailing is not None
    assert s.dir_hold_trailing.value == 0 and "while STEP is high" in s.dir_hold_trailing.note


@pytest.mark.skipif(not CORPUS.is_dir(), reason="shared firmware corpus not present")
@pytest.mark.parametrize("clock", CLOCKS, ids=lambda f: f"{int(f) // 10**6}MHz")
@pytest.mark.parametrize("ini", HM2, ids=lambda p: p.name)
def test_every_fix_at_the_clock_works(ini: Path, clock: F, tmp_path: Path) -> None:
    """Each fix printed at ``clock`` names whole ns the driver makes into the clocks it says,
    and applied to a copy it makes the rule pass at that clock (issue 32, class 5)."""
    cfg = read_firmware(ini, clock_hz=clock)
    checked = 0
    for d_no, drive in enumerate(_drives()):
        result = evaluate_config(cfg, [(a, drive) for a in cfg.axes])
        for pair in result.pairs:
            for row in pair.rows:
                if row.verdict != "fail" or not row.fix or "maxvel" in row.fix:
                    continue
                values = [w.split()[2] for w in row.fix.split("`")[1::2]]
                assert all(v.isdigit() for v in values), row.fix  # whole ns, as u32 params
                if "clocks at" in row.fix:
                    clocks = int(row.fix.split("(ns: ")[1].split(" clocks")[0])
                    assert register(F(values[0]), clock) == clocks, row.fix
                copy = copy_case(cfg, CORPUS, tmp_path / f"{d_no}-{checked}")
                apply(cfg.firmware, copy, row.fix, cfg)
                again = read_firmware(copy, clock_hz=clock)
                rows = evaluate_config(again, [(a, drive) for a in again.axes]).pairs
                verdict = {(p.axis.axis, r.rule): r.verdict for p in rows for r in p.rows}
                assert verdict[(pair.axis.axis, row.rule)] != "fail", (drive.id, row.fix)
                checked += 1
    assert checked >= 4


def test_dir_change_during_the_pulse_is_a_setup_for_a_trailing_edge_drive(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """plasma-5i20 (STEPLEN 1000, DIRHOLD 200, DIRSETUP 200): DIR may change 200 ns into the
    1 us pulse (kubstepgenz.vhd 212-219), so a G202, which counts the falling edge, sees DIR
    change only 800 ns before it (was dirsetup + steplen = 1.2 us, a PASS against 1 us)."""
    code = main(["config", str(HM2[0]), "--drive", "gecko-g202", "--format", "json"])
    doc = json.loads(capsys.readouterr().out)
    setup = next(r for r in doc["pairs"][0]["rules"] if r["rule"] == "dir_setup")
    assert code == 1 and setup["generator_ns"] == 800 and setup["verdict"] == "fail"
    assert "dirhold 1000" in setup["fix"]  # keep DIR through the pulse
    # the axis entry says it too (it listed dir_hold_trailing but not this figure)
    axis = doc["axes"][0]
    assert axis["dir_setup_trailing_ns"]["value"] == 800
    assert axis["dir_setup_trailing_ns"]["setting"] == "steplen - dirhold"


def test_a_capture_of_what_the_hardware_does_is_no_finding(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """STEP 1 us high every 4 us, DIR changed 200 ns into a pulse, as kubstepgenz.vhd does with
    plasma-5i20's STEPLEN 1000, DIRHOLD 200: 800 ns from the DIR change to the falling edge a
    G202 counts. `check --firmware` compared it with dirsetup + steplen = 1.2 us and called the
    capture a violation of its own configuration; the configured figure is steplen - dirhold."""
    events = sorted([(t, "1s") for t in range(1000, 41000, 4000)]
                    + [(t + 1000, "0s") for t in range(1000, 41000, 4000)] + [(17200, "1d")])  # fmt: skip
    head = "$timescale 1ns $end\n$scope module top $end\n$var wire 1 s STEP $end\n"
    head += "$var wire 1 d DIR $end\n$upscope $end\n$enddefinitions $end\n#0\n0s\n0d\n"
    vcd = tmp_path / "midpulse.vcd"
    vcd.write_text(head + "".join(f"#{t}\n{v}\n" for t, v in events) + "#42000\n")
    main(["check", str(vcd), "--drive", "gecko-g202", "--firmware", str(HM2[0]),
          "--axis", "stepgen.00", "--format", "json"])  # fmt: skip
    fw = json.loads(capsys.readouterr().out)["firmware"]
    setup = next(c for c in fw["comparisons"] if c["what"] == "dir_setup")
    assert (setup["configured"], setup["measured"], setup["verdict"]) == (800, 800, "pass")
