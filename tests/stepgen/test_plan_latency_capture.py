"""stepgen plan --latency CAPTURE: the worst lateness inferred from a capture feeds the plan
(issue 17), and none is planned from when it is not established (issue 25)."""

from __future__ import annotations

from pathlib import Path

import pytest

from stepgen.cli import main as stepgen_main
from wavecheck.step_latency import latency_of


def test_plan_from_capture_equals_plan_from_the_figure(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    vcd = tmp_path / "run.vcd"
    assert (
        stepgen_main(
            [
                "simulate",
                "--base-period",
                "25us",
                "--position-scale",
                "1000",
                "--maxvel",
                "15",
                "--maxaccel",
                "200",
                "--move",
                "1",
                "--latency",
                "uniform:9us",
                "--seed",
                "2",
                "-o",
                str(vcd),
                "-q",
            ]
        )
        == 0
    )
    worst = latency_of(str(vcd)).max_lateness_ns
    assert worst is not None and worst.denominator == 1
    capsys.readouterr()
    plans = []
    for opts in (
        ["--latency", str(vcd)],
        ["--latency-from", str(vcd)],
        ["--latency", f"{worst}ns"],
    ):
        assert stepgen_main(["plan", "--drive", "gecko-g202", "--format", "json", *opts]) == 0
        text = capsys.readouterr().out
        plans.append(text.replace(str(vcd), "X"))
    import json

    docs = [json.loads(p) for p in plans]
    for d in docs:
        d.pop("latency_source", None)
        d.get("latency", {}).pop("source", None) if isinstance(d.get("latency"), dict) else None
    assert docs[0] == docs[1] == docs[2]


def test_plan_refuses_a_hardware_timed_capture(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert stepgen_main(["plan", "--drive", "gecko-g202"]) == 2
    assert "one of them" in capsys.readouterr().err


def _simulate(tmp_path: Path, latency: str) -> Path:
    vcd = tmp_path / "run.vcd"
    argv = ["simulate", "--base-period", "34us", "--position-scale", "1000", "--maxvel", "14"]
    argv += ["--maxaccel", "200", "--move", "1, pause 10ms, 0.2", "--latency", latency]
    assert stepgen_main([*argv, "--seed", "2", "-o", str(vcd), "-q"]) == 0
    return vcd


def test_plan_from_a_worst_case_capture_uses_j_not_p_minus_j(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # issue 25: worst:31us at P = 34 us read as 3 us gave BASE_PERIOD 6 us
    vcd = _simulate(tmp_path, "worst:31us:step_high")
    capsys.readouterr()
    assert (
        stepgen_main(
            ["plan", "--drive", "gecko-g202", "--format", "json", "--latency-from", str(vcd)]
        )
        == 0
    )
    import json

    doc = json.loads(capsys.readouterr().out)
    # every edge of this exact VCD is on a 1 us grid (P 34 us, J 31 us), which a 1 MHz analyzer
    # would make too: planned from J plus that grid (issue 33), never from P − J
    assert doc["latency"]["ns"] == 32_000 and doc["base_period_ns"] > 32_000


@pytest.mark.parametrize(
    ("capture", "why"),
    [
        ("captures/golden/a4988-spike.vcd", "lower bound"),
        ("captures/golden/xylotex-dirsetup-zero.vcd", "too few edges"),
    ],
)
def test_plan_refuses_a_capture_without_an_established_latency(
    capture: str, why: str, capsys: pytest.CaptureFixture[str]
) -> None:
    path = Path(__file__).resolve().parents[2] / capture
    assert stepgen_main(["plan", "--drive", "gecko-g202", "--latency-from", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "no latency to plan from" in err and why in err
