"""The seed's story as end-to-end checks: plan → stepgen simulate worst:J:RULE → wavecheck check.

Every number asserted here is computed by the loop (plan, simulation, validator); the comments
cite where the seed states it.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from stepgen.cli import main as stepgen_main
from stepgen.plan import plan
from stepgen.story import (
    RULES,
    SweepRow,
    command_csv,
    library_sweep,
    report,
    reversal_motion,
    seed_story,
    worst_case,
    zero_crossing_story,
)
from wavecheck.cli import main as wavecheck_main
from wavecheck.drives.library import load_drive
from wavecheck.drives.model import Drive

US = 1000
J = 11 * US
ONES = {"steplen": 1, "stepspace": 1, "dirsetup": 1, "dirhold": 1}


@pytest.fixture(scope="module")
def g202() -> Drive:
    return load_drive("gecko-g202")


@pytest.fixture(scope="module")
def xylotex() -> Drive:
    return load_drive("xylotex")


# ------------------------------------------------------------------------- Gecko G202, J = 11 us


def test_g202_p20_defaults_fail_dir_hold_9us(g202: Drive) -> None:
    """Seed 000: 'If one run ... is 11 us late, and the next one is on time, the delay ... is
    only 9 us' → violates the 20 us hold."""
    out = worst_case(g202, J, 20 * US, ONES)
    assert out.failed == ("dir_hold",)
    assert out.measured("dir_hold") == 9 * US
    assert out.rules["dir_hold"].worst_run.endswith(":dir_hold")


def test_g202_p31_simple_passes_at_16129(g202: Drive) -> None:
    """Seed 000: BASE_PERIOD 20 + 11 = 31 us, 'guaranteed to meet the drive's timing
    requirements', max 16,129 steps/s."""
    p = plan(g202, J, plan(g202, J).simple_base_period_ns)
    assert p.base_period_ns == 31 * US
    assert all(prm.periods == 1 for prm in p.params.values())
    out = worst_case(g202, J, p.base_period_ns, p.with_params())
    assert out.verdict == "pass", out.failed
    assert int(p.max_step_rate_hz) == 16_129
    assert out.observed_rate_hz == p.max_step_rate_hz


def test_g202_p16_dirhold2_passes_at_31250(g202: Drive) -> None:
    """Seed 000: 16 us with dirhold 2: 5 + 16 = 21 us ≥ 20 us, 31,250 steps/s."""
    p = plan(g202, J, 16 * US)
    assert p.params["dirhold"].periods == 2
    out = worst_case(g202, J, 16 * US, p.with_params())
    assert out.verdict == "pass", out.failed
    assert out.measured("dir_hold") == 21 * US
    assert int(p.max_step_rate_hz) == 31_250 and out.observed_rate_hz == 31_250


def test_g202_p16_dirhold1_fails(g202: Drive) -> None:
    """Seed 000: 'If we leave dirhold at 1 ... 16 − 11 = 5 us, which is not enough'."""
    out = worst_case(g202, J, 16 * US, ONES)
    assert out.failed == ("dir_hold",)
    assert out.measured("dir_hold") == 5 * US


def test_g202_inverted_pin_other_reading(g202: Drive) -> None:
    """DESIGN: inverting the pin moves the active edge to the start of the pulse; the hold is then
    (steplen + dirhold)·P − J, so dirhold 1 is enough at 16 us."""
    p = plan(g202, J, 16 * US, step_inverted=True)
    assert p.params["dirhold"].periods == 1
    out = worst_case(g202, J, 16 * US, p.with_params(), step_inverted=True)
    assert out.verdict == "pass", out.failed
    assert out.measured("dir_hold") == 21 * US
    # ... and the seed's (non-inverted) reading of the same settings fails, as computed above
    assert worst_case(g202, J, 16 * US, p.with_params()).failed == ("dir_hold",)


# ------------------------------------------------------------------------- Xylotex, J = 11 us


def test_xylotex_minimum_13us_38461(xylotex: Drive) -> None:
    """Seed 000: 'you can set the BASE_PERIOD as low as 11+2=13 us ... 38,461 steps per second'."""
    p = plan(xylotex, J)
    assert p.min_base_period_ns == 13 * US and p.base_period_ns == 13 * US
    assert int(p.min_base_period_rate_hz) == 38_461
    out = worst_case(xylotex, J, p.base_period_ns, p.with_params())
    assert out.verdict == "pass", out.failed
    assert out.observed_rate_hz == p.max_step_rate_hz


def test_xylotex_p16_passes_with_5us(xylotex: Drive) -> None:
    """Seed 000: 'With a 16 us period and 11 us latency, the shortest output time will be
    16-11 = 5 us' and 31,250 steps/s."""
    p = plan(xylotex, J, 16 * US)
    out = worst_case(xylotex, J, 16 * US, p.with_params())
    assert out.verdict == "pass", out.failed
    assert out.shortest_ns >= 5 * US
    assert out.shortest_ns == 5 * US  # the bound is reached, not just respected
    assert int(p.max_step_rate_hz) == 31_250 and out.observed_rate_hz == 31_250


# ------------------------------------------------------------------------- the LinuxCNC defect


def test_zero_velocity_reversal(xylotex: Drive, g202: Drive) -> None:
    """Reference §2.4 / LinuxCNC #2332: a reversal through exactly v = 0 flips DIR in the same
    period as the next pulse starts. No parameter prevents it (plan states it); the seed's G202
    reading keeps steplen·P − J of setup."""
    px = plan(xylotex, J, 16 * US)
    out = worst_case(xylotex, J, 16 * US, px.with_params(), through_zero=True)
    assert "dir_setup" in out.failed and out.measured("dir_setup") == 0
    assert any("#2332" in a and "No parameter prevents it" in a for a in px.assumptions)
    pg = plan(g202, J, 31 * US)
    og = worst_case(g202, J, 31 * US, pg.with_params(), through_zero=True)
    assert og.verdict == "pass" and og.measured("dir_setup") == 31 * US - J


# ------------------------------------------------------------------------- the whole library


@pytest.fixture(scope="module")
def sweep() -> list[SweepRow]:
    return library_sweep()


def test_sweep_covers_the_library(sweep: list[SweepRow]) -> None:
    ids = {r.drive.id for r in sweep}
    assert {"gecko-g202", "xylotex"} <= ids
    assert len(ids) >= 10
    assert {r.latency_ns for r in sweep} == {5 * US, 11 * US, 25 * US}
    assert all(set(RULES) - {"step_period"} <= set(r.outcome.rules) for r in sweep)


def test_sweep_planned_configurations_pass(sweep: list[SweepRow]) -> None:
    """Every plan passes under the worst-case latency of every rule."""
    bad = [
        (r.drive.id, r.latency_ns, r.outcome.failed) for r in sweep if r.outcome.verdict != "pass"
    ]
    assert not bad


def test_sweep_each_lengthened_parameter_is_needed(sweep: list[SweepRow]) -> None:
    """For each parameter above one period, one period less fails under some worst case, and it
    fails the very rule the plan gives as the reason for that parameter."""
    checked = 0
    for r in sweep:
        for name, prm in r.plan.params.items():
            if prm.periods == 1:
                assert name not in r.shorter
                continue
            shorter = r.shorter[name]
            assert shorter.verdict == "fail", (r.drive.id, r.latency_ns, name)
            assert any(rule in prm.reason for rule in shorter.failed), (
                name,
                prm.reason,
                shorter.failed,
            )
            checked += 1
    assert checked >= 10  # G202 dirhold, preset dirsetup/dirhold ...
    # every parameter is exercised (steplen/stepspace by the rows below the minimum period)
    for name in ("steplen", "stepspace", "dirsetup", "dirhold"):
        assert any(name in r.shorter for r in sweep), name
    assert any(r.plan.base_period_ns < r.plan.min_base_period_ns for r in sweep)


def test_report_all_expectations_hold() -> None:
    text, ok = report(sweep=False)
    assert ok, text
    assert text.count("[ok]") == len(seed_story()) + len(zero_crossing_story())


# ------------------------------------------------------------------------- through the CLIs


def _cli_chain(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], base: str, extra: list[str]
) -> tuple[int, dict]:
    """stepgen plan --format hal → stepgen simulate worst:11us:dir_hold → wavecheck check."""
    assert (
        stepgen_main(
            [
                "plan",
                "--drive",
                "gecko-g202",
                "--latency",
                "11us",
                "--base-period",
                base,
                "--format",
                "hal",
                *extra,
            ]
        )
        == 0
    )
    hal = capsys.readouterr().out
    params = {
        line.split()[1].rsplit(".", 1)[1]: int(line.split()[2])
        for line in hal.splitlines()
        if line.startswith("setp stepgen.0.")
    }
    period = int(base.removesuffix("us")) * US
    motion, n = reversal_motion(period, {k: v // period for k, v in params.items()})
    csv = tmp_path / "reversals.csv"
    csv.write_text(command_csv(motion))
    vcd = tmp_path / "run.vcd"
    argv = [
        "simulate",
        "--base-period",
        f"{period}ns",
        "--servo-period",
        f"{period}ns",
        "--mode",
        "velocity",
    ]
    for name, ns in params.items():
        argv += [f"--{name}", f"{ns}ns"]  # the HAL's bare ns, with the unit an option needs
    argv += [
        "--thread-order", "pulses-first", "--command", str(csv), "--periods", str(n),
        "--latency", "worst:11us:dir_hold", "--active-edge", "falling", "-q", "-o", str(vcd),
    ]  # fmt: skip
    assert stepgen_main(argv) == 0
    capsys.readouterr()
    code = wavecheck_main(["check", str(vcd), "--drive", "gecko-g202", "--format", "json"])
    return code, json.loads(capsys.readouterr().out)


def test_cli_chain_g202_p16(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code, doc = _cli_chain(tmp_path, capsys, "16us", [])
    hold = next(r for r in doc["rules"] if r["id"] == "dir_hold")
    assert code == 0 and doc["verdict"] == "pass"
    assert hold["min_measured_ns"] == 21 * US


def test_cli_chain_g202_p16_inverted_plan_on_plain_pin_fails(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The inverted-pin plan (dirhold 1) wired without the inversion: the mapping matters."""
    code, doc = _cli_chain(tmp_path, capsys, "16us", ["--invert-step"])
    hold = next(r for r in doc["rules"] if r["id"] == "dir_hold")
    assert code == 1 and hold["verdict"] == "fail" and hold["min_measured_ns"] == 5 * US
