"""What the firmware does not enforce is never a PASS or a FAIL (issue 32, class 1).

Each fact is read from the firmware's own code: Klipper at ``../shared/firmware-src/klipper``
(``src/stepper.c``), LinuxCNC's stepgen from its issue #2332."""

from __future__ import annotations

import json
from fractions import Fraction as F
from pathlib import Path

import pytest

from tests.conftest import SHARED
from tools.firmware_corpus import CORPUS
from wavecheck.cli import main
from wavecheck.firmware import read_firmware

KLIPPER = CORPUS / "klipper"
pytestmark = pytest.mark.skipif(not CORPUS.is_dir(), reason="shared firmware corpus not present")
_NOTE = "not enforced by the firmware: measure it"


def _rules(capsys: pytest.CaptureFixture[str], *argv: str) -> dict[str, dict]:  # type: ignore[type-arg]
    main(["config", *argv, "--format", "json"])
    doc = json.loads(capsys.readouterr().out)
    return {r["rule"]: r for r in doc["pairs"][0]["rules"]}


def test_klipper_avr_fast_path_decides_nothing(capsys: pytest.CaptureFixture[str]) -> None:
    """printer-creality-ender3-2018.cfg names an atmega1284p (line 2): the 2 us default is <= 40
    ticks, so stepper_event_avr runs (src/stepper.c:238-240). It writes both STEP edges in one
    event (163, 168) and never applies step_pulse_ticks; the low time and DIR setup are the
    host's schedule (167, 126-127): they gave a FAIL/PASS from a 2 us figure."""
    rules = _rules(capsys, str(KLIPPER / "printer-creality-ender3-2018.cfg"),
                   "--drive", "leadshine-dm542", "--limit", "dir_hold=1us")  # fmt: skip
    for rule in ("step_high", "step_low", "dir_setup", "dir_hold"):
        assert rules[rule]["verdict"] == "indeterminate", rule
        assert _NOTE in rules[rule]["note"] and "stepper.c" in rules[rule]["note"]


def test_klipper_edge_path_dir_hold_is_no_pass(capsys: pytest.CaptureFixture[str]) -> None:
    """skr-mini-e3-v2.0: TMC2209 over UART -> 100 ns, both edges (klippy/extras/tmc.py:487);
    6-7 ticks <= EDGE_STEP_TICKS (src/stepper.c:132, 233-235): stepper_event_edge, and DIR is
    toggled in stepper_load_next right after the last STEP toggle (150 -> 126-127). A drive
    asking 100 ns of DIR hold got a PASS."""
    rules = _rules(capsys, str(KLIPPER / "generic-bigtreetech-skr-mini-e3-v2.0.cfg"),
                   "--drive", "leadshine-dm542", "--limit", "dir_hold=100ns")  # fmt: skip
    assert rules["dir_hold"]["verdict"] == "indeterminate"
    assert "stepper_load_next" in rules["dir_hold"]["note"] and _NOTE in rules["dir_hold"]["note"]


def test_klipper_both_edge_full_path_is_enforced(tmp_path: Path) -> None:
    """A both-edge pulse over EDGE_STEP_TICKS (400 ns = 25 or 28 ticks on an STM32F103 > 8-9)
    runs stepper_event_full with SF_SINGLE_SCHED: edges >= step_pulse_ticks apart
    (src/stepper.c:184-195), DIR toggled only after that time (113-116)."""
    cfg = tmp_path / "printer.cfg"
    cfg.write_text(
        "# This file contains common pin mappings for an STM32F103 board.\n"
        "[stepper_x]\nstep_pin: PB13\ndir_pin: PB12\nmicrosteps: 16\nrotation_distance: 40\n"
        "step_pulse_duration: 0.0000004\n"
        "[tmc2209 stepper_x]\nuart_pin: PC11\n"
        "[printer]\nkinematics: cartesian\nmax_velocity: 300\n"
    )
    x = read_firmware(cfg).axis("x")
    assert x.both_edges
    made = F(28 * 10**9, 72_000_000)  # int(400 ns x 72 MHz) = 28 ticks (388.9 ns), the shorter
    assert x.pulse.value == made and x.dir_hold.value == made and x.dir_setup.value == made


@pytest.mark.parametrize(("chip", "enforced"), [("STM32H723", True), ("STM32F407", False)])
def test_klipper_stm32h7_has_no_edge_path(tmp_path: Path, chip: str, enforced: bool) -> None:
    """src/stm32/Kconfig:16 selects HAVE_STEPPER_OPTIMIZED_BOTH_EDGE "if !MACH_STM32H7", so an H7
    build has no stepper_event_edge (src/stepper.c:19-28): TMC both-edge steps run
    stepper_event_full with SF_SINGLE_SCHED (224-227, 233-237), each edge >= step_pulse_ticks
    after the last (184-195). 100 ns at 520 MHz (src/stm32/Kconfig:214) is 52 ticks: 100 ns,
    enforced; it was read as the unenforced edge path. An STM32F407 (168 MHz: 16 ticks <=
    EDGE_STEP_TICKS 21) does run the edge path."""
    cfg = tmp_path / "printer.cfg"
    cfg.write_text(
        f"# This file contains common pin mappings for an {chip} board.\n"
        "[stepper_x]\nstep_pin: PF13\ndir_pin: PF12\nmicrosteps: 16\nrotation_distance: 40\n"
        "[tmc2209 stepper_x]\nuart_pin: PC4\n"
        "[printer]\nkinematics: cartesian\nmax_velocity: 300\n"
    )
    x = read_firmware(cfg).axis("x")
    assert x.both_edges
    if enforced:
        assert x.pulse.value == x.dir_setup.value == x.dir_hold.value == 100
    else:
        assert x.pulse.value is None and x.pulse.status == "not_enforced"


def test_klipper_arm_full_path_stays_enforced(capsys: pytest.CaptureFixture[str]) -> None:
    """duet3-6xd (no TMC section, SAME70): stepper_event_full; the pulse, space and DIR setup are
    each >= step_pulse_ticks (src/stepper.c:185-195, 117-120): decided."""
    rules = _rules(capsys, str(KLIPPER / "generic-duet3-6xd.cfg"), "--drive", "leadshine-dm542")
    assert rules["step_high"]["verdict"] == "fail" and rules["step_high"]["generator_ns"] == 2000


def test_linuxcnc_dirsetup_pass_rests_on_issue_2332(capsys: pytest.CaptureFixture[str]) -> None:
    """stepper_mm: dirsetup 1 period of 50 us would PASS a 5 us DIR setup; the software stepgen
    can fail to obey dirsetup (LinuxCNC issue #2332), so it is no PASS, and says so."""
    ini = CORPUS / "linuxcnc/configs/by_interface/parport/stepper/stepper_mm.ini"
    rules = _rules(capsys, str(ini), "--drive", "leadshine-dm542")
    assert rules["dir_setup"]["verdict"] == "indeterminate"
    assert "#2332" in rules["dir_setup"]["note"]
    assert rules["step_high"]["verdict"] == "pass"  # steplen is enforced


def test_linuxcnc_dirsetup_too_short_still_fails(capsys: pytest.CaptureFixture[str]) -> None:
    """A dirsetup shorter than the drive's figure fails whatever stepgen keeps."""
    ini = CORPUS / "linuxcnc/configs/by_interface/parport/stepper/stepper_mm.ini"
    rules = _rules(capsys, str(ini), "--drive", "leadshine-dm542", "--limit", "dir_setup=60us")
    assert rules["dir_setup"]["verdict"] == "fail" and "#2332" in rules["dir_setup"]["note"]


def test_pair_rate_is_the_smaller_of_generator_and_drive(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """Class 7: skr-mini-e3's stepper_x is configured for 300 mm/s x 80 steps/mm = 24 kHz; the
    DM542 allows 200 kHz: "max step rate this pair allows" said 200 kHz."""
    main(["config", str(KLIPPER / "generic-bigtreetech-skr-mini-e3-v2.0.cfg"),
          "--drive", "leadshine-dm542", "--format", "json"])  # fmt: skip
    doc = json.loads(capsys.readouterr().out)
    assert doc["pairs"][0]["max_rate_hz"] == 24000


@pytest.mark.parametrize(
    ("steplen", "dirhold", "lead", "trailing"),
    [
        # hostmot2 kubstepgenz.vhd (IgorYeremin/hostmot2-firmware@8a8dcbd) under GHDL 2.0.0 at
        # 100 MHz, the rate reversed just after a rising STEP edge: registers 201/102 -> DIR
        # changed 103 clocks after the rising edge while STEP was high (it fell at 202); 450/2000
        # -> 2001 clocks after the rising edge, 1550 after the falling one
        (2010, 1020, 1030, 0),
        (4500, 20000, 20010, 15500),
    ],
)
def test_hm2_dir_hold_counts_from_the_pulse_start(
    tmp_path: Path, steplen: int, dirhold: int, lead: int, trailing: int
) -> None:
    """Class 2: the hold counter is loaded with the pulse (kubstepgenz.vhd:212-213) and DIR may
    change when it runs out (215-219), even during the pulse: dirhold + 1 clock after the
    leading edge, dirhold - steplen after the trailing one (0 when DIR may change while STEP is
    high); the driver truncates ns x f to clocks (mesa-hostmot2/stepgen.c:348-387), the pulse is
    steplen clocks + 1 (here 2020 / 4510 ns)."""
    src = SHARED / "firmware/linuxcnc/hm2-stepper"
    for f in src.iterdir():
        text = f.read_text()
        if f.suffix == ".ini":
            text = text.replace("DIRHOLD    =              200", f"DIRHOLD = {dirhold}")
            text = text.replace("STEPLEN    =              40000", f"STEPLEN = {steplen}")
        (tmp_path / f.name).write_text(text)
    cfg = read_firmware(tmp_path / "5i20.ini", clock_hz=F(100_000_000))
    s = cfg.axis("stepgen.00")
    assert s.dir_hold.value == lead and s.dir_hold_trailing is not None
    assert s.dir_hold_trailing.value == trailing
