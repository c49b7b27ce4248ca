"""The seed's story as end-to-end checks: plan → stepgen simulate worst:J:RULE → wavecheck check.

The numbers the seed states live once, in ``tools/seed_numbers.toml`` (the story tool prints the
same file); every value asserted here against them is computed by the loop (plan, simulation,
validator). Each case there cites where the seed states it.
"""

from __future__ import annotations

import json
from fractions import Fraction
from pathlib import Path

import pytest

from stepgen.cli import main as stepgen_main
from tools.story import (
    RULES,
    CaseRun,
    SweepRow,
    command_csv,
    library_sweep,
    load_numbers,
    report,
    reversal_motion,
    run_case,
    worst_case,
)
from wavecheck.cli import main as wavecheck_main

US = 1000
NUMBERS = load_numbers()
J = NUMBERS.latency_ns


def _us(value: Fraction | int) -> int:
    """A stated µs figure as whole ns."""
    ns = Fraction(value) * US
    assert ns.denominator == 1
    return int(ns)


@pytest.fixture(scope="module")
def runs() -> dict[str, CaseRun]:
    """Every case of the seed's numbers, planned, simulated under every worst case and checked."""
    return {c.id: run_case(c, J) for c in NUMBERS.cases}


# ------------------------------------------------------------------------- the seed's numbers


def test_numbers_cover_the_seed() -> None:
    """The stated cases are the seed's G202 and Xylotex examples and the LinuxCNC defect."""
    assert J == 11 * US
    assert {c.drive for c in NUMBERS.cases} == {"gecko-g202", "xylotex"}
    assert set(NUMBERS.sections) == {c.section for c in NUMBERS.cases}
    assert all(c.expect for c in NUMBERS.cases)


@pytest.mark.parametrize("case_id", [c.id for c in NUMBERS.cases])
def test_seed_number(case_id: str, runs: dict[str, CaseRun]) -> None:
    """What the loop computes for each case equals what seed_numbers.toml states."""
    run = runs[case_id]
    for key, stated in run.case.expect.items():
        got = run.value(key)
        if key == "fails_include":
            assert set(stated) <= set(got), (key, stated, got)
        else:
            assert got == stated, (key, stated, got)


def test_g202_p20_worst_run_is_the_dir_hold_one(runs: dict[str, CaseRun]) -> None:
    """The 9 µs hold comes from the run that puts the latency where it hurts dir_hold."""
    out = runs["g202-p20-defaults"].outcome
    assert out.rules["dir_hold"].worst_run.endswith(":dir_hold")


def test_g202_inverted_plan_fails_on_a_plain_pin(runs: dict[str, CaseRun]) -> None:
    """The inverted-pin plan (dirhold 1) read the seed's way (pin not inverted) is the seed's
    failing dirhold-1 case: the mapping matters."""
    inv, plain = runs["g202-p16-inverted"], runs["g202-p16-dirhold1"]
    assert inv.periods == plain.periods
    out = worst_case(inv.outcome.drive, J, inv.plan.base_period_ns, inv.periods)
    assert out.failed == plain.outcome.failed == ("dir_hold",)
    assert out.measured("dir_hold") == plain.outcome.measured("dir_hold")


def test_zero_velocity_reversal_is_stated_by_plan(runs: dict[str, CaseRun]) -> None:
    """Reference §2.4 / LinuxCNC #2332: no parameter prevents it, and the plan says so."""
    px = runs["xylotex-p16-through-zero"].plan
    assert any("#2332" in a and "No parameter prevents it" in a for a in px.assumptions)


def test_g202_zero_crossing_setup_is_steplen_p_minus_j(runs: dict[str, CaseRun]) -> None:
    """The G202 reading keeps steplen·P − J of DIR setup across a reversal through v = 0."""
    run = runs["g202-p31-through-zero"]
    setup = run.periods["steplen"] * run.plan.base_period_ns - J
    assert run.outcome.measured("dir_setup") == setup == _us(run.case.expect["dir_setup_us"])


# ------------------------------------------------------------------------- the whole library


@pytest.fixture(scope="module")
def sweep() -> list[SweepRow]:
    return library_sweep(NUMBERS.sweep_latencies_ns, NUMBERS.short_period_latency_ns)


def test_sweep_covers_the_library(sweep: list[SweepRow]) -> None:
    ids = {r.drive.id for r in sweep}
    assert {"gecko-g202", "xylotex"} <= ids
    assert len(ids) >= 10
    assert {r.latency_ns for r in sweep} == set(NUMBERS.sweep_latencies_ns)
    assert J in NUMBERS.sweep_latencies_ns
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
    text, ok = report(NUMBERS, sweep=False)
    assert ok, text
    assert text.count("[ok]") == len(NUMBERS.cases) and "MISMATCH" not in text


# ------------------------------------------------------------------------- through the CLIs


def _cli_chain(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], case_id: str, extra: list[str]
) -> tuple[int, dict]:
    """stepgen plan --format hal → stepgen simulate worst:J:dir_hold → wavecheck check, for the
    drive, latency and BASE_PERIOD of a case of the seed's numbers."""
    case = NUMBERS.case(case_id)
    assert isinstance(case.base_period, int)
    period = case.base_period * US
    plan_argv = [
        "plan",
        "--drive",
        case.drive,
        "--latency",
        f"{J}ns",
        "--base-period",
        f"{period}ns",
    ]
    assert stepgen_main([*plan_argv, "--format", "hal", *extra]) == 0
    hal = capsys.readouterr().out
    params = {
        line.split()[1].rsplit(".", 1)[1]: int(line.split()[2])
        for line in hal.splitlines()
        if line.startswith("setp stepgen.0.")
    }
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
        "--latency", f"worst:{J}ns:dir_hold", "--active-edge", "falling", "-q", "-o", str(vcd),
    ]  # fmt: skip
    assert stepgen_main(argv) == 0
    capsys.readouterr()
    code = wavecheck_main(["check", str(vcd), "--drive", case.drive, "--format", "json"])
    return code, json.loads(capsys.readouterr().out)


def test_cli_chain_g202_p16(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code, doc = _cli_chain(tmp_path, capsys, "g202-p16-planned", [])
    hold = next(r for r in doc["rules"] if r["id"] == "dir_hold")
    expect = NUMBERS.case("g202-p16-planned").expect
    assert code == 0 and doc["verdict"] == expect["verdict"] == "pass"
    assert hold["min_measured_ns"] == _us(expect["dir_hold_us"])


def test_cli_chain_g202_p16_inverted_plan_on_plain_pin_fails(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The inverted-pin plan (dirhold 1) wired without the inversion: the mapping matters — it is
    the seed's failing dirhold-1 case."""
    code, doc = _cli_chain(tmp_path, capsys, "g202-p16-inverted", ["--invert-step"])
    hold = next(r for r in doc["rules"] if r["id"] == "dir_hold")
    expect = NUMBERS.case("g202-p16-dirhold1").expect
    assert code == 1 and hold["verdict"] == expect["verdict"] == "fail"
    assert hold["min_measured_ns"] == _us(expect["dir_hold_us"])
