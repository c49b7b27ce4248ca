"""``wavecheck config``: firmware x drive pairs whose answers follow from the datasheet and the
firmware figures, incl. one passing exactly at the boundary and one failing by 1 ns."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from tests.conftest import SHARED
from wavecheck.cli import main

FW = SHARED / "firmware"
pytestmark = pytest.mark.skipif(not FW.is_dir(), reason="shared firmware files not present")

ORTUR = FW / "marlin/Ortur_4_release-2.0.9.7/Configuration.h"
CNC_ONE = FW / "reprapfirmware/cnc-one/config.g"


def _run(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, dict]:  # type: ignore[type-arg]
    code = main(["config", *argv, "--format", "json"])
    return code, json.loads(capsys.readouterr().out)


def _rule(doc: dict, axis: str, rule: str) -> dict:  # type: ignore[type-arg]
    pair = next(p for p in doc["pairs"] if p["axis"] == axis)
    return next(r for r in pair["rules"] if r["rule"] == rule)


PAIRS = [
    # (file, drive, axis, rule, verdict): why
    # Ortur: A4988 1 us pulse vs A4988 datasheet 1 us: the aim meets it, but Marlin's pulse may
    # be 1.5 pulse-timer ticks (750 ns) short (stepper.cpp NS_TO_PULSE_TIMER_TICKS rounds to the
    # nearest tick, AWAIT_TIMED_PULSE counts from any phase) -> indeterminate
    (ORTUR, "a4988", "X", "step_high", "indeterminate"),
    # Ortur: POST_DIR_DELAY 200 ns vs A4988 200 ns setup -> pass exactly
    (ORTUR, "a4988", "X", "dir_setup", "pass"),
    # Ortur: 1 us pulse vs DRV8825 1.9 us -> fail
    (ORTUR, "drv8825", "X", "step_high", "fail"),
    # cnc-one: T5:5:10:0 vs DM542 2.5 us / 5 us setup -> pass; DIR setup 10 us >= 5 us
    (CNC_ONE, "leadshine-dm542", "X", "step_high", "pass"),
    (CNC_ONE, "leadshine-dm542", "X", "dir_setup", "pass"),
    # grbl: DIR written just before STEP: 0 < DM542's 5 us setup -> fail
    # grbl keeps no DIR setup (stepper.c:323-333: a few cycles of code, no delay): not enforced
    (FW / "grbl/settings.md", "leadshine-dm542", "X", "dir_setup", "indeterminate"),
    # grbl $0=10 us vs DM542 2.5 us -> pass
    (FW / "grbl/settings.md", "leadshine-dm542", "X", "step_high", "pass"),
    # Klipper 6XD 2 us default vs DM542 2.5 us -> fail
    (FW / "klipper/generic-duet3-6xd.cfg", "leadshine-dm542", "stepper_x", "step_high", "fail"),
    # Klipper Mellow 4 us vs DM542 2.5 us -> pass
    (
        FW / "klipper/generic-mellow-fly-e3-v2.cfg",
        "leadshine-dm542",
        "stepper_x",
        "step_high",
        "pass",
    ),
    # Marlin VORON DRV8825 default 2000 ns vs DRV8825 1.9 us: 1.25 us at the band's worst end
    # (750 ns short) -> indeterminate
    (FW / "marlin/VORONDesign", "drv8825", "X", "step_high", "indeterminate"),
    # hm2 5i20 40 us / 40 us vs Gecko G202 4.5 us high -> pass; 12 kHz <= 200 kHz
    (FW / "linuxcnc/hm2-stepper/5i20.ini", "gecko-g202", "stepgen.00", "step_period", "pass"),
    # Smoothie 1 us pulse vs DM542 2.5 us -> fail
    (FW / "smoothieware/Smoothieboard/config", "leadshine-dm542", "alpha", "step_high", "fail"),
]


@pytest.mark.parametrize(("path", "drive", "axis", "rule", "verdict"), PAIRS)
def test_pairs(
    capsys: pytest.CaptureFixture[str], path: Path, drive: str, axis: str, rule: str, verdict: str
) -> None:
    _, doc = _run(capsys, str(path), "--drive", drive)
    assert _rule(doc, axis, rule)["verdict"] == verdict


def test_boundary_exact_pass_and_fail_by_one_ns(capsys: pytest.CaptureFixture[str]) -> None:
    # Ortur MINIMUM_STEPPER_PULSE 1 (us) = 1000 ns, which Marlin may make 750 ns short (1.5
    # ticks of a 2 MHz pulse timer): its band is 250 ns .. 1000 ns. The worst end exactly equal
    # to the limit passes; a ns more is inside the band; the aim a ns short fails.
    code, doc = _run(capsys, str(ORTUR), "--drive", "a4988", "--limit", "step_high=250ns")
    r = _rule(doc, "X", "step_high")
    assert (r["verdict"], r["worst_ns"], r["short_by_ns"]) == ("pass", 250, 750)
    code, doc = _run(capsys, str(ORTUR), "--drive", "a4988", "--limit", "step_high=251ns")
    assert _rule(doc, "X", "step_high")["verdict"] == "indeterminate"
    code, doc = _run(capsys, str(ORTUR), "--drive", "a4988", "--limit", "step_high=1000ns")
    r = _rule(doc, "X", "step_high")
    assert (r["verdict"], r["margin_ns"], r["limit_datasheet_ns"]) == ("indeterminate", 0, 1000)
    assert r["fix"] == "Marlin: define MINIMUM_STEPPER_PULSE 2 (us)"  # 1000 + 750 ns, whole us
    code, doc = _run(capsys, str(ORTUR), "--drive", "a4988", "--limit", "step_high=1001ns")
    r = _rule(doc, "X", "step_high")
    assert (r["verdict"], r["margin_ns"]) == ("fail", -1)
    assert r["fix"] == "Marlin: define MINIMUM_STEPPER_PULSE 2 (us)"
    assert code == 1


def test_margin_doubles_and_fix_names_the_setting(capsys: pytest.CaptureFixture[str]) -> None:
    # cnc-one 5 us vs DM542 2.5 us x 2 = 5 us: exactly at the boundary
    _, doc = _run(capsys, str(CNC_ONE), "--drive", "leadshine-dm542", "--margin", "2x")
    r = _rule(doc, "X", "step_high")
    assert (r["verdict"], r["limit_ns"], r["limit_datasheet_ns"]) == ("pass", 5000, 2500)
    _, doc = _run(
        capsys,
        str(FW / "grbl/settings.md"),
        "--drive",
        "leadshine-dm542",
        "--limit",
        "step_high=12us",
    )
    assert _rule(doc, "X", "step_high")["fix"] == "set `$0=13` (us)"  # 12 us + 562.5 ns short


def test_per_axis_drives_and_text(capsys: pytest.CaptureFixture[str]) -> None:
    code = main(["config", str(CNC_ONE), "--drive", "leadshine-dm542", "--drive", "Z=gecko-g202"])
    out = capsys.readouterr().out
    assert "drive gecko-g202" in out and "max step rate this pair allows" in out
    assert code in (0, 1, 3)


def test_user_rule_file_extends(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    mine = tmp_path / "my-g202.toml"
    mine.write_text('id = "g202-slow"\nextends = "gecko-g202"\n[limits]\nstep_high = "40us"\n')
    _, doc = _run(capsys, str(FW / "linuxcnc/hm2-stepper/5i20.ini"), "--drive", str(mine))
    r = _rule(doc, "stepgen.00", "step_high")
    assert (r["verdict"], r["limit_ns"], r["limit_status"]) == (
        "pass",
        40000,
        "user",
    )  # 40 us = 40 us
    assert _rule(doc, "stepgen.00", "dir_hold")["limit_ns"] == 20000  # from gecko-g202


def test_linuxcnc_software_stepgen_latency(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    (tmp_path / "m.hal").write_text(
        "loadrt stepgen step_type=0\nsetp stepgen.0.steplen 5000\nsetp stepgen.0.stepspace 5000\n"
        "setp stepgen.0.dirsetup 10000\nsetp stepgen.0.dirhold 10000\n"
    )
    (tmp_path / "m.ini").write_text("[EMCMOT]\nBASE_PERIOD = 25000\n[HAL]\nHALFILE = m.hal\n")
    # one 25 us period each; J = 11 us -> 14 us guaranteed pulse
    _, doc = _run(
        capsys, str(tmp_path / "m.ini"), "--drive", "leadshine-dm542", "--latency", "11us"
    )
    assert doc["firmware"] == "linuxcnc"
    r = _rule(doc, "stepgen.0", "step_high")
    assert (r["generator_ns"], r["verdict"]) == (14000, "pass")


def test_user_file_errors_all_at_once(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    bad = tmp_path / "bad.toml"
    bad.write_text(
        'id = "bad"\nextends = "gecko-g202"\ninterface = "pwm"\n[limits]\nstep_hi = "1us"\n'
        'step_low = "2 furlongs"\n'
    )
    assert main(["config", str(CNC_ONE), "--drive", str(bad)]) == 2
    err = capsys.readouterr().err
    assert "3 errors" in err and "interface" in err and "step_hi" in err and "step_low" in err
