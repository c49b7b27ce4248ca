"""One rule for numbers and units in both tools (README "Numbers and units", issue 12).

Every time or frequency option of ``wavecheck`` and ``stepgen`` needs its unit (a bare ``0``
excepted); a bare number is refused with the fix spelled out. Values that cannot be a time or a
frequency (``1e400us``) end in exit 2 with one short line. A base period below 1 us and a sample
rate below 1 kHz are refused, a latency below 100 ns is warned about. ``--resolution`` is kept
exact, a fraction of a VCD tick included.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from tests.conftest import write_vcd
from tests.reliability.helpers import cli

ROOT = Path(__file__).resolve().parents[3]
G202 = str(ROOT / "captures" / "golden" / "g202-p20-worst-dirhold.vcd")
CHECK = ["check", G202, "--drive", "gecko-g202"]
PLAN = ["plan", "--drive", "gecko-g202"]
SIM = ["simulate", "--base-period", "25us", "--servo-period", "1ms", "--mode", "velocity",
       "--velocity", "100", "--duration", "2ms", "-q"]  # fmt: skip
BIG = "1" * 400


def _sim(tmp_path: Path, *extra: str) -> list[str]:
    return [*SIM, *extra, "-o", str(tmp_path / "t.vcd")]


#: (program, argv after the program, option, the fix that must be spelled out)
BARE: list[tuple[str, list[str], str, str]] = [
    ("wavecheck", [*CHECK, "--base-period", "16"], "--base-period 16", "16us or 16000ns"),
    (
        "wavecheck",
        [*CHECK, "--base-period", "16us", "--steplen", "5000"],
        "--steplen 5000",
        "5000us",
    ),
    ("wavecheck", [*CHECK, "--base-period", "16us", "--latency", "11"], "--latency 11", "11us"),
    ("wavecheck", [*CHECK, "--samplerate", "12"], "--samplerate 12", "12MHz or 12kHz"),
    ("wavecheck", [*CHECK, "--resolution", "500"], "--resolution 500", "500us or 500000ns"),
    ("stepgen", [*PLAN, "--latency", "11"], "--latency 11", "11us or 11000ns"),
    ("stepgen", [*PLAN, "--latency", "11us", "--base-period", "16"], "--base-period 16", "16us"),
    ("stepgen", ["SIM", "--base-period", "16"], "--base-period 16", "16us or 16000ns"),
    ("stepgen", ["SIM", "--servo-period", "1000000"], "--servo-period 1000000", "1000000us"),
    ("stepgen", ["SIM", "--steplen", "5000"], "--steplen 5000", "5000us or 5000000ns"),
    ("stepgen", ["SIM", "--duration", "100"], "--duration 100", "100us or 100000ns"),
    ("stepgen", ["SIM", "--catchup", "1000"], "--catchup 1000", "1000us"),
    ("stepgen", ["SIM", "--latency", "uniform:11"], "J 11", "11us or 11000ns"),
    ("stepgen", ["SIM", "--latency", "worst:11000:dir_hold"], "J 11000", "11000us"),
]


def _argv(tmp_path: Path, argv: list[str]) -> list[str]:
    return _sim(tmp_path, *argv[1:]) if argv[0] == "SIM" else argv


@pytest.mark.parametrize(
    ("prog", "argv", "option", "fix"), BARE, ids=[f"{p}-{o}" for p, _, o, _ in BARE]
)
def test_a_bare_number_is_refused_with_the_fix(
    tmp_path: Path, prog: str, argv: list[str], option: str, fix: str
) -> None:
    rc, _, err = cli(prog, _argv(tmp_path, argv))
    assert rc == 2, err
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err, err
    assert option in err and "give a unit" in err and fix in err, err
    assert not (tmp_path / "t.vcd").exists()


#: values that cannot be a time or frequency of anything: exit 2, one short line
HUGE: list[tuple[str, list[str]]] = [
    ("wavecheck", [*CHECK, "--resolution", "1e400s"]),
    ("wavecheck", [*CHECK, "--samplerate", "1e400Hz"]),
    ("wavecheck", [*CHECK, "--samplerate", "1e-400 Hz"]),
    ("wavecheck", [*CHECK, "--base-period", "16us", "--latency", "1e400s"]),
    ("wavecheck", [*CHECK, "--base-period", "1e400us"]),
    ("wavecheck", [*CHECK, "--resolution", BIG + "us"]),
    ("wavecheck", [*CHECK, "--resolution", BIG]),
    ("wavecheck", [*CHECK, "--resolution", "1e30s"]),
    ("stepgen", [*PLAN, "--latency", "1e400s"]),
    ("stepgen", [*PLAN, "--latency", BIG + "ns"]),
    ("stepgen", [*PLAN, "--latency", "11us", "--base-period", "1e400us"]),
    ("stepgen", ["SIM", "--duration", "1e400s"]),
    ("stepgen", ["SIM", "--duration", "1e400"]),
    ("stepgen", ["SIM", "--base-period", "1e400us"]),
    ("stepgen", ["SIM", "--latency", "uniform:1e400us"]),
    ("stepgen", ["SIM", "--move", f"0.01, pause {BIG}s, 0"]),
]


@pytest.mark.parametrize(("prog", "argv"), HUGE, ids=[" ".join(a[-2:])[:40] for _, a in HUGE])
def test_an_absurd_value_is_one_short_line(tmp_path: Path, prog: str, argv: list[str]) -> None:
    rc, _, err = cli(prog, _argv(tmp_path, argv))
    assert rc == 2, err
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err, err
    assert len(err) < 250 and "1111111111111111111111111" not in err, err


#: a unit slip: (program, argv, what the message says)
IMPLAUSIBLE: list[tuple[str, list[str], str]] = [
    ("wavecheck", [*CHECK, "--base-period", "500ns"], "below 1 us"),
    ("wavecheck", [*CHECK, "--base-period", "20ns", "--latency", "11us"], "below 1 us"),
    ("wavecheck", [*CHECK, "--samplerate", "12Hz"], "below 1 kHz"),
    ("stepgen", [*PLAN, "--latency", "11us", "--base-period", "999ns"], "below 1 us"),
    ("stepgen", ["SIM", "--base-period", "20ns"], "below 1 us"),
]


@pytest.mark.parametrize(
    ("prog", "argv", "says"), IMPLAUSIBLE, ids=[" ".join(a[-2:]) for _, a, _ in IMPLAUSIBLE]
)
def test_a_unit_slip_is_refused(tmp_path: Path, prog: str, argv: list[str], says: str) -> None:
    rc, _, err = cli(prog, _argv(tmp_path, argv))
    assert rc == 2, err
    assert len(err.strip().splitlines()) == 1 and says in err and "check the unit" in err, err


WARNED: list[tuple[str, list[str]]] = [
    ("wavecheck", [*CHECK, "--base-period", "20us", "--latency", "50ns"]),
    ("stepgen", [*PLAN, "--latency", "50ns"]),
    ("stepgen", ["SIM", "--latency", "uniform:50ns"]),
]


@pytest.mark.parametrize(("prog", "argv"), WARNED, ids=[a[-1] for _, a in WARNED])
def test_a_tiny_latency_is_warned_about(tmp_path: Path, prog: str, argv: list[str]) -> None:
    rc, _, err = cli(prog, _argv(tmp_path, argv))
    assert rc in (0, 1), err  # the run goes on (check: the golden trace fails dir_hold)
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "warning:" in lines[0] and "below 100 ns" in lines[0], err


def test_the_warning_is_given_once_for_several_captures(tmp_path: Path) -> None:
    rc, _, err = cli(
        "wavecheck", ["check", G202, G202, "--drive", "gecko-g202", "--base-period", "20us",
                      "--latency", "50ns"],
    )  # fmt: skip
    assert rc == 1 and err.count("warning:") == 1, err


@pytest.mark.parametrize(
    ("argv", "zero_ok"),
    [(["--resolution", "0"], True), (["--resolution", "-0"], True), (["--samplerate", "0"], False)],
)
def test_a_bare_zero_is_zero(argv: list[str], zero_ok: bool) -> None:
    """The one exception: 0 is zero in every unit (and is then judged as 0)."""
    rc, _, err = cli("wavecheck", [*CHECK, *argv])
    if zero_ok:
        assert rc == 1 and err == "", err  # the golden trace fails dir_hold at T = 0
    else:
        assert rc == 2 and "must be positive" in err, err


def test_the_same_value_reads_the_same_in_both_tools(tmp_path: Path) -> None:
    """--base-period 16us and --latency 11us mean the same to check and to plan (bare, plan read
    11 as 11 us and check as 11 ns): plan's dirhold of 2 periods gives check 31,250 steps/s."""
    rc, out, err = cli("stepgen", [*PLAN, "--latency", "11us", "--base-period", "16us",
                                   "--format", "json"])  # fmt: skip
    assert rc == 0, err
    plan = json.loads(out)
    assert plan["latency"]["ns"] == 11000 and plan["base_period_ns"] == 16000
    assert plan["params"]["dirhold"]["ns"] == 32000
    rc, out, err = cli("wavecheck", [*CHECK, "--format", "json", "--base-period", "16us",
                                     "--dirhold", "32us", "--latency", "11us"])  # fmt: skip
    assert rc == 1, err
    rates = json.loads(out)["max_step_rate_hz"]
    assert rates["config"] == 31250 and rates["latency_safe"] == 31250


def test_resolution_below_a_vcd_tick_stays_exact(tmp_path: Path) -> None:
    """A 2 us pulse against a 1.5 us limit at T = 100 ns on a 1 us timescale: 2 − 0.1 ≥ 1.5, a
    pass (rounded up to one whole tick it was indeterminate: 2 − 1 < 1.5)."""
    drive = tmp_path / "high15.toml"
    drive.write_text(
        'id = "high15"\nname = "step_high 1.5 us"\nkind = "user"\ninterface = "step-dir"\n'
        'active_edge = "rising"\n[limits.step_high]\nvalue = "1.5us"\nsource = "T"\n'
        'status = "datasheet"\n[sources]\nT = "this test"\n'
    )
    vcd = write_vcd(tmp_path / "p.vcd", {"STEP": (0, [10, 12])}, timescale="1 us", end=20)
    argv = ["check", str(vcd), "--drive", str(drive), "--format", "json"]
    rc, out, err = cli("wavecheck", [*argv, "--resolution", "100ns"])
    assert rc == 0, err
    doc = json.loads(out)
    assert doc["verdict"] == "pass" and doc["capture"]["resolution_ns"] == 100
    rc, out, _ = cli("wavecheck", [*argv, "--resolution", "1500ns"])  # 2 − 1.5 ≥ 1.5 is false
    assert rc == 3 and json.loads(out)["capture"]["resolution_ns"] == 1500


def test_linuxcnc_files_stay_bare_ns(tmp_path: Path) -> None:
    """INI BASE_PERIOD and HAL setp values are LinuxCNC's bare ns, in both tools."""
    ini = tmp_path / "m.ini"
    ini.write_text("[EMCMOT]\nBASE_PERIOD = 20000\nSERVO_PERIOD = 1000000\n")
    hal = tmp_path / "m.hal"
    hal.write_text(
        "loadrt stepgen step_type=0\nsetp stepgen.0.steplen 1\nsetp stepgen.0.stepspace 1\n"
        "setp stepgen.0.dirhold 20000\nsetp stepgen.0.dirsetup 20000\n"
    )
    rc, out, err = cli("stepgen", ["simulate", "--ini", str(ini), "--hal", str(hal),
                                   "--mode", "velocity", "--velocity", "100",
                                   "--duration", "2ms", "-o", str(tmp_path / "t.vcd")])  # fmt: skip
    assert rc == 0, err
    assert "P = 20000 ns" in out
    rc, out, err = cli("wavecheck", [*CHECK, "--ini", str(ini), "--hal", str(hal), "--format",
                                     "json"])  # fmt: skip
    assert rc == 1, err
    assert json.loads(out)["max_step_rate_hz"]["config"] == 25000  # 1 / ((1 + 1) periods x 20 us)
