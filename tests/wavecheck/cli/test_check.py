"""``wavecheck check`` end to end on small VCDs whose every interval is known by construction."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from tests.conftest import write_vcd
from tests.wavecheck.waves import pulses
from wavecheck.cli import main

US = 1000  # 1 ns timescale


def _run(capsys, *argv: str) -> tuple[int, str, str]:
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def _a4988_vcd(tmp_path: Path, width: int) -> Path:
    # A4988: rising edge, high ≥ 1 µs, low ≥ 1 µs, DIR setup/hold ≥ 200 ns
    step = pulses([10 * US, 20 * US, 30 * US], 1 * US) + [40 * US, 40 * US + width]
    return write_vcd(tmp_path / "w.vcd", {"STEP": (0, step), "DIR": (0, [15 * US])})


def test_pulse_exactly_at_minimum_passes(tmp_path: Path, capsys) -> None:
    code, out, _ = _run(capsys, "check", str(_a4988_vcd(tmp_path, 1 * US)), "--drive", "a4988")
    assert code == 0 and out.startswith("verdict: PASS")
    assert "map:     step='STEP', dir='DIR'" in out  # mapped by channel name


def test_one_tick_shorter_fails(tmp_path: Path, capsys) -> None:
    vcd = _a4988_vcd(tmp_path, 1 * US - 1)
    out_file = tmp_path / "r.json"
    code, out, _ = _run(
        capsys, "check", str(vcd), "--drive", "a4988", "--format", "json", "-o", str(out_file)
    )
    assert code == 1 and "report written to" in out
    data = json.loads(out_file.read_text())
    assert data["verdict"] == "fail" and data["violations_total"] == 1
    assert data["violations"][0] == {
        "rule": "step_high",
        "time_s": 40e-6,
        "measured_ns": 999,
        "limit_ns": 1000,
        "margin_ns": -1,
    }
    assert data["capture"]["resolution_ns"] == 0
    assert data["steps"]["count"] == 4 and data["steps"]["final_position"] == -2


def test_resolution_turns_it_indeterminate(tmp_path: Path, capsys) -> None:
    vcd = _a4988_vcd(tmp_path, 1 * US)
    code, out, _ = _run(capsys, "check", str(vcd), "--drive", "a4988", "--resolution", "10ns")
    assert code == 3 and out.startswith("verdict: INDETERMINATE")
    assert "indeterminate at this resolution" in out


def test_dir_change_one_tick_after_active_edge(tmp_path: Path, capsys) -> None:
    # G202 (falling edge, hold ≥ 20 µs): DIR changes 1 ns after the falling edge at 15 µs
    step = pulses([10 * US, 60 * US], 5 * US)
    vcd = write_vcd(tmp_path / "h.vcd", {"S": (0, step), "D": (0, [15 * US + 1])})
    code, out, _ = _run(
        capsys,
        "check",
        str(vcd),
        "--drive",
        "gecko-g202",
        "--map",
        "step=S,dir=D",
        "--format",
        "json",
    )
    data = json.loads(out)
    hold = next(r for r in data["rules"] if r["id"] == "dir_hold")
    assert code == 1 and hold["violations"] == 1 and hold["min_margin_ns"] == 1 - 20 * US
    assert hold["min_margin_at_s"] == 15e-6


def test_seed_g202_story_as_a_vcd(tmp_path: Path, capsys) -> None:
    p, late = 20 * US, 11 * US
    edges = []
    for r in (0, 3 * p, 6 * p, 9 * p, 13 * p):
        edges += [r, r + p + (late if r == 9 * p else 0)]
    vcd = write_vcd(
        tmp_path / "g202.vcd", {"stepgen.0.step": (0, edges), "stepgen.0.dir": (0, [11 * p])}
    )
    code, out, _ = _run(capsys, "check", str(vcd), "--drive", "gecko-g202", "--format", "json")
    data = json.loads(out)
    assert code == 1
    assert [(v["rule"], v["measured_ns"]) for v in data["violations"]] == [("dir_hold", 9 * US)]


def test_type_option_and_user_table(tmp_path: Path, capsys) -> None:
    # quadrature A/B, 3 steps forward
    vcd = write_vcd(
        tmp_path / "q.vcd", {"phase-A": (1, [200 * US]), "phase-B": (0, [100 * US, 300 * US])}
    )
    code, out, _ = _run(
        capsys, "check", str(vcd), "--drive", "a4988", "--type", "2", "--format", "json"
    )
    data = json.loads(out)
    assert data["steps"]["count"] == 3 and data["steps"]["final_position"] == 3
    assert [r["id"] for r in data["rules"]] == ["step_period", "state_sequence"]
    code, out, _ = _run(
        capsys,
        "check",
        str(vcd),
        "--drive",
        "a4988",
        "--type",
        "15",
        "--user-step-type",
        "1,3,2,0",
        "--format",
        "json",
    )
    assert json.loads(out)["steps"]["final_position"] == 3


@pytest.mark.parametrize(
    ("extra", "needle"),
    [
        (["--drive", "no-such-drive"], "no-such-drive"),
        (["--drive", "a4988", "--map", "step=NOPE"], "NOPE"),
        (["--drive", "a4988", "--type", "16"], "step type 16"),
        (["--drive", "a4988", "--invert", "up"], "--invert"),
        (["--drive", "a4988", "--user-step-type", "x"], "--user-step-type"),
        (["--drive", "a4988", "--resolution", "fast"], "fast"),
    ],
)
def test_unusable_input_is_one_line_exit_2(tmp_path: Path, capsys, extra, needle) -> None:
    vcd = _a4988_vcd(tmp_path, 1 * US)
    code, out, err = _run(capsys, "check", str(vcd), *extra)
    assert code == 2 and out == ""
    assert len(err.strip().splitlines()) == 1 and needle in err and "Traceback" not in err


def test_missing_capture_exit_2(tmp_path: Path, capsys) -> None:
    code, _, err = _run(capsys, "check", str(tmp_path / "none.vcd"), "--drive", "a4988")
    assert code == 2 and len(err.strip().splitlines()) == 1


def test_output_folder_missing_leaves_nothing(tmp_path: Path, capsys) -> None:
    vcd = _a4988_vcd(tmp_path, 1 * US)
    code, _, err = _run(
        capsys, "check", str(vcd), "--drive", "a4988", "-o", str(tmp_path / "no" / "r.txt")
    )
    assert code == 2 and "does not exist" in err


def test_real_capture_cli(smoothie_sr: Path, capsys) -> None:
    code, out, _ = _run(
        capsys, "check", str(smoothie_sr), "--drive", "gecko-g202", "--map", "step=5,dir=6"
    )
    assert code == 1
    assert "steps:   739" in out and "… and 361 more, not identical to these" in out
    assert "169 × step_high" in out  # the whole capture's count of the group shown


def test_json_says_how_many_violations_it_lists_of_how_many(capsys) -> None:
    """Issue 34: the JSON listed 1000 of 5054 violations without saying so in the document."""
    from tests.conftest import shared_capture

    grbl = str(shared_capture("sigrok-dumps/stepper_motor/grbl_cnc/grbl_cnc_1.sr"))
    args = ["check", grbl, "--drive", "drv8825", "--map", "step=1", "--limit", "step_high=10us"]
    for extra, listed, cut in (([], 1000, True), (["--max-violations", "6000"], 5054, False)):
        assert main([*args, "--format", "json", *extra]) == 1
        doc = json.loads(capsys.readouterr().out)
        assert doc["violations_total"] == 5054
        assert doc["violations_listed"] == len(doc["violations"]) == listed
        assert doc["violations_truncated"] is cut
