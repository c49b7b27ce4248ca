"""stepgen plan --latency CAPTURE: the worst lateness inferred from a capture feeds the plan (issue 17)."""

from __future__ import annotations

from pathlib import Path

import pytest

from stepgen.cli import main as stepgen_main
from wavecheck.capture.open import open_capture
from wavecheck.latency import analyse


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
    worst = analyse(open_capture(vcd), ["step", "dir"]).max_lateness_ns
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
