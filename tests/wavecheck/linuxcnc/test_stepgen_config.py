"""LinuxCNC INI/HAL files: stepgen settings of a channel, config and latency-safe rates."""

from __future__ import annotations

from fractions import Fraction
from pathlib import Path

import pytest

from tests.wavecheck.waves import g202
from wavecheck.errors import ConfigError
from wavecheck.linuxcnc.files import read_ini
from wavecheck.linuxcnc.stepgen_config import config_rates, read_config

INI = """\
# a LinuxCNC configuration
[EMCMOT]
EMCMOT = motmod
BASE_PERIOD = 16000
SERVO_PERIOD = 1000000

[JOINT_0]
STEPLEN = 16000
DIRHOLD = 32000
"""

HAL = """\
loadrt [KINS]KINEMATICS
loadrt stepgen step_type=0,0,2 ctrl_type=p,v,p
addf stepgen.make-pulses base-thread
setp stepgen.0.steplen [JOINT_0]STEPLEN   # one period
setp stepgen.0.stepspace 0
setp stepgen.0.dirsetup 16000
setp stepgen.0.dirhold [JOINT_0]DIRHOLD
setp stepgen.0.position-scale 200
stepgen.1.steplen = 5000
net xstep stepgen.0.step => parport.0.pin-02-out
"""


@pytest.fixture
def files(tmp_path: Path) -> tuple[Path, Path]:
    ini = tmp_path / "machine.ini"
    hal = tmp_path / "machine.hal"
    ini.write_text(INI)
    hal.write_text(HAL)
    return ini, hal


def test_read_channel_0(files: tuple[Path, Path]) -> None:
    ini, hal = files
    cfg = read_config(ini, hal, channel=0)
    assert (cfg.base_period_ns, cfg.servo_period_ns) == (16000, 1_000_000)
    assert (cfg.step_type, cfg.ctrl_type) == (0, "position")
    assert cfg.params == {"steplen": 16000, "stepspace": 0, "dirsetup": 16000, "dirhold": 32000}
    assert cfg.floats == {"position-scale": 200.0}
    assert cfg.sources["dirhold"] == f"{hal}:7"
    assert cfg.sources["BASE_PERIOD"] == f"{ini}:4"
    assert cfg.periods() == {"steplen": 1, "stepspace": 0, "dirsetup": 1, "dirhold": 2}
    kw = cfg.stepgen_kwargs()
    assert kw["base_period_ns"] == 16000 and kw["dirhold"] == 32000 and kw["position_scale"] == 200


def test_other_channels(files: tuple[Path, Path]) -> None:
    ini, hal = files
    one = read_config(ini, hal, channel=1)
    assert (one.step_type, one.ctrl_type, one.params) == (0, "velocity", {"steplen": 5000})
    assert read_config(ini, hal, channel=2).step_type == 2
    with pytest.raises(ConfigError, match=r"channel 3 is not loaded \(use --channel 0..2\)"):
        read_config(ini, hal, channel=3)


def test_seed_rates_g202_16us_dirhold_2(tmp_path: Path) -> None:
    # the seed: P = 16 µs, steplen = stepspace = 1, dirhold = 2 → 31,250 steps/s, safe at 11 µs
    ini = tmp_path / "a.ini"
    ini.write_text("[EMCMOT]\nBASE_PERIOD = 16000\n")
    hal = tmp_path / "a.hal"
    hal.write_text("setp stepgen.0.dirhold 32000\n")
    rates = config_rates(read_config(ini, hal), g202(), 11_000)
    assert rates.config == Fraction(31_250)
    assert rates.latency_safe == Fraction(31_250)


def test_seed_rates_g202_20us_dirhold_1_is_never_safe(tmp_path: Path) -> None:
    ini = tmp_path / "a.ini"
    ini.write_text("[EMCMOT]\nBASE_PERIOD = 20000\n")
    rates = config_rates(read_config(ini), g202(), 11_000)
    assert rates.config == Fraction(25_000)
    assert rates.latency_safe is None
    assert "dir_hold (dirhold·P − J) is 9000 ns < 20000 ns" in rates.notes[0]


def test_stepspace_too_short_lowers_the_safe_rate(tmp_path: Path) -> None:
    # P = 10 µs, J = 9.8 µs: stepspace 1 gives 200 ns < 500 ns, so 2 periods of space are needed
    ini = tmp_path / "a.ini"
    ini.write_text("[EMCMOT]\nBASE_PERIOD = 10000\n")
    hal = tmp_path / "a.hal"
    hal.write_text(
        "setp stepgen.0.steplen 20000\nsetp stepgen.0.dirhold 40000\nsetp stepgen.0.dirsetup 20000\n"
    )
    rates = config_rates(read_config(ini, hal), g202(), 9_800)
    assert rates.config == Fraction(10**9, 30_000)  # steplen 2 + stepspace 1
    assert rates.latency_safe == Fraction(10**9, 40_000)  # steplen 2 + 2 periods of space


@pytest.mark.parametrize(
    ("ini", "hal", "needle"),
    [
        (
            "[EMCMOT]\nBASE_PERIOD = fast\n",
            "",
            r"a\.ini:2: \[EMCMOT\]BASE_PERIOD 'fast' is not a number",
        ),
        ("BASE_PERIOD = 1\n", "", r"line 1: 'BASE_PERIOD = 1' comes before any \[SECTION\]"),
        ("[EMCMOT]\n", "setp stepgen.0.steplen -5\n", r"a\.hal:1: stepgen\.0\.steplen '-5' is not"),
        ("[EMCMOT]\n", "setp stepgen.0.steplen [X]Y\n", r"\[X\]Y is not in"),
    ],
)
def test_errors_name_file_and_line(tmp_path: Path, ini: str, hal: str, needle: str) -> None:
    (tmp_path / "a.ini").write_text(ini)
    (tmp_path / "a.hal").write_text(hal)
    with pytest.raises(ConfigError, match=needle):
        read_config(tmp_path / "a.ini", tmp_path / "a.hal")


def test_no_base_period(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="no BASE_PERIOD"):
        read_config(None, None).periods()


def test_read_ini_keeps_duplicates(tmp_path: Path) -> None:
    p = tmp_path / "m.ini"
    p.write_text("[HAL]\nHALFILE = a.hal\nHALFILE = b.hal\n")
    ini = read_ini(p)
    assert ini.get("HAL", "HALFILE") == ("a.hal", 2)
    assert len(ini.sections["HAL"]["HALFILE"]) == 2


def test_config_rate_of_a_phase_type_has_no_stepspace(files: tuple[Path, Path]) -> None:
    # DESIGN "Maximum achievable step rate": config is stepgen's own clamp. For step types ≥ 2
    # stepgen has no stepspace (the reference: "For types ≥ 2 stepspace is 0 → 1e9 / steplen_ns";
    # stepgen/reference.py does the same), so channel 2 (type 2, default steplen 1 ns → one 16 µs
    # period) steps at up to 62,500/s, not 31,250/s; latency_safe is not the step/dir plan's.
    ini, hal = files
    cfg = read_config(ini, hal, channel=2)
    rates = config_rates(cfg, g202(), 11_000)
    assert rates.config == Fraction(62_500)
    assert rates.latency_safe is None and "step type" in rates.notes[0]
    # the check's own --type wins over the HAL file (same channel decoded as step/dir)
    assert config_rates(cfg, g202(), None, step_type=0).config == Fraction(31_250)


def test_threads_and_addf_give_the_periods_and_order(tmp_path: Path) -> None:
    """Reference §1/§3/§8: make-pulses' thread period is the base period, update-freq's the servo
    period; in one thread the addf order decides which runs first. The HAL wins over an INI
    BASE_PERIOD that no motmod line uses, and says so."""
    ini = tmp_path / "a.ini"
    ini.write_text("[EMCMOT]\nBASE_PERIOD = 25000\n")
    hal = tmp_path / "a.hal"
    hal.write_text(
        "loadrt threads name1=fast period1=100000\n"
        "loadrt stepgen step_type=0\n"
        "addf stepgen.make-pulses fast\n"
        "addf stepgen.update-freq fast 1\n"  # position 1: runs first
        "setp stepgen.0.position-cmd .04\n"
        "setp stepgen.0.enable 1\n"
    )
    cfg = read_config(ini, hal)
    assert (cfg.base_period_ns, cfg.servo_period_ns) == (100_000, 100_000)
    assert cfg.sources["BASE_PERIOD"] == f"{hal}:1"
    assert cfg.functions["fast"] == ["stepgen.update-freq", "stepgen.make-pulses"]
    assert cfg.thread_order == "update-first"
    assert cfg.command == ("position", 0.04) and cfg.enable is True
    assert cfg.stepgen_kwargs()["thread_order"] == "update-first"
    assert cfg.ignored == [
        f"ignored: [EMCMOT]BASE_PERIOD 25000 ns ({ini}:2): stepgen.make-pulses runs in thread "
        f"fast, period 100000 ns ({hal}:1)"
    ]


def test_motmod_threads_come_from_the_ini(tmp_path: Path) -> None:
    """A stock configuration: motmod's base-thread and servo-thread periods are INI references."""
    ini = tmp_path / "a.ini"
    ini.write_text("[EMCMOT]\nBASE_PERIOD = 20000\nSERVO_PERIOD = 1000000\n")
    hal = tmp_path / "a.hal"
    hal.write_text(
        "loadrt motmod base_period_nsec=[EMCMOT]BASE_PERIOD servo_period_nsec=[EMCMOT]SERVO_PERIOD\n"
        "loadrt stepgen step_type=0\n"
        "addf stepgen.make-pulses base-thread\n"
        "addf stepgen.update-freq servo-thread\n"
        "net xen joint.0.amp-enable-out => stepgen.0.enable\n"
    )
    cfg = read_config(ini, hal)
    assert (cfg.base_period_ns, cfg.servo_period_ns, cfg.thread_order) == (20_000, 1_000_000, None)
    assert cfg.ignored == [
        f"ignored: net xen joint.0.amp-enable-out => stepgen.0.enable ({hal}:5) (the model keeps "
        "enable on)"
    ]


def test_only_one_stepgen_function_added_is_named(tmp_path: Path) -> None:
    hal = tmp_path / "a.hal"
    hal.write_text(
        "loadrt threads name1=fast period1=50000\nloadrt stepgen step_type=0\n"
        "addf stepgen.make-pulses fast\nsetp stepgen.0.enable 1\n"
    )
    cfg = read_config(None, hal)
    assert cfg.base_period_ns == 50_000 and cfg.servo_period_ns is None
    assert len(cfg.ignored) == 1 and "stepgen.update-freq is not" in cfg.ignored[0]


def test_bad_thread_period_names_the_line(tmp_path: Path) -> None:
    hal = tmp_path / "a.hal"
    hal.write_text("\nloadrt threads name1=fast period1=soon\n")
    with pytest.raises(ConfigError, match=rf"{hal}:2: period1 'soon'"):
        read_config(None, hal)


def test_parenthesised_ini_references_resolve(tmp_path: Path) -> None:
    """halcmd substitutes [SECTION](KEY) as well as [SECTION]KEY; the real hm2-stepper HAL file
    loads its driver with config=[HOSTMOT2](CONFIG)."""
    ini = tmp_path / "m.ini"
    ini.write_text("[EMCMOT]\nBASE_PERIOD = 25000\n[JOINT_0]\nSTEPLEN = 5000\n")
    hal = tmp_path / "m.hal"
    hal.write_text("loadrt stepgen step_type=0\nsetp stepgen.0.steplen [JOINT_0](STEPLEN)\n")
    assert read_config(ini, [hal]).params["steplen"] == 5000


def test_the_real_hm2_configuration_reads(tmp_path: Path) -> None:
    from tests.conftest import SHARED_CAPTURES

    folder = SHARED_CAPTURES.parent / "firmware" / "linuxcnc" / "hm2-stepper"
    if not folder.exists():
        pytest.skip(f"shared firmware folder not present: {folder}")
    cfg = read_config(folder / "5i20.ini", [folder / "hm2-stepper.hal"])
    assert cfg.base_period_ns is None or cfg.base_period_ns > 0


def test_no_stepgen_loaded_gives_no_stepgen_rates(tmp_path: Path) -> None:
    """issue 24: `check --ini` reported "config 500 Hz" for a stepgen the HAL files never load
    (a Mesa configuration): with HAL files read and no `loadrt stepgen`, there are no rates."""
    ini = tmp_path / "m.ini"
    ini.write_text("[EMCMOT]\nBASE_PERIOD = 1000000\n")
    hal = tmp_path / "m.hal"
    hal.write_text("loadrt hostmot2\nloadrt hm2_pci\nsetp hm2_5i20.0.stepgen.00.steplen 1250\n")
    rates = config_rates(read_config(ini, hal), g202(), 10_000)
    assert rates.config is None and rates.latency_safe is None
    assert "no software stepgen" in rates.notes[0]
