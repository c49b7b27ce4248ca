"""``wavecheck compare``: a capture against a golden VCD made by ``stepgen simulate``."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from stepgen.cli import main as stepgen_main
from tests.conftest import write_vcd
from wavecheck.capture.open import open_capture
from wavecheck.cli import main


@pytest.fixture(scope="module")
def golden(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """40 steps at 2 kHz, P = 25 µs, no latency: a stepgen golden trace."""
    out = tmp_path_factory.mktemp("golden") / "golden.vcd"
    code = stepgen_main(
        [
            "simulate",
            "--base-period",
            "25us",
            "--mode",
            "velocity",
            "--velocity",
            "2000",
            "--duration",
            "20ms",
            "-q",
            "-o",
            str(out),
        ]
    )
    assert code == 0
    return out


def _as_capture(
    golden: Path,
    path: Path,
    shift: int,
    nudge: dict[int, int] | None = None,
    drop_last: bool = False,
) -> Path:
    """The golden's STEP/DIR as a 'logic analyzer' capture: shifted by ``shift`` ns, falling
    edge ``k`` moved by ``nudge[k]`` ns, optionally without the last pulse."""
    cap = open_capture(golden)
    step, dirs = cap.channel("step"), cap.channel("dir")
    edges = [int(t) + shift for t in step.edges]
    for k, dt in (nudge or {}).items():
        edges[2 * k + 1] += dt  # the k-th falling (active) edge
    if drop_last:
        edges = edges[:-2]
    signals = {
        "STEP": (step.initial, edges),
        "DIR": (dirs.initial, [int(t) + shift for t in dirs.edges]),
    }
    return write_vcd(path, signals)


def _compare(capsys, *argv: str) -> tuple[int, dict]:
    code = main(["compare", *argv, "--drive", "gecko-g202", "--format", "json"])
    out, _ = capsys.readouterr()
    return code, json.loads(out)


def test_same_trace_shifted_passes(golden: Path, tmp_path: Path, capsys) -> None:
    cap = _as_capture(golden, tmp_path / "c.vcd", shift=1_234_567)
    code, data = _compare(capsys, str(cap), str(golden))
    assert code == 0 and data["verdict"] == "pass"
    assert data["steps"]["count"] == {"capture": 40, "golden": 40}
    assert data["timing"]["max_abs_diff_ns"] == 0 and data["timing"]["compared"] == 40
    assert {r["change"] for r in data["rules"]} == {"same"}


def test_no_alignment_sees_the_shift(golden: Path, tmp_path: Path, capsys) -> None:
    cap = _as_capture(golden, tmp_path / "c.vcd", shift=5_000)
    code, data = _compare(capsys, str(cap), str(golden), "--align", "none")
    assert code == 1 and data["timing"]["max_abs_diff_ns"] == 5000
    assert data["timing"]["beyond_tolerance"] == 40  # every step, at the 2 µs default
    code, data = _compare(capsys, str(cap), str(golden), "--align", "none", "--tolerance", "5us")
    assert code == 0  # exactly at the tolerance passes


def test_one_late_step_beyond_tolerance(golden: Path, tmp_path: Path, capsys) -> None:
    cap = _as_capture(golden, tmp_path / "c.vcd", shift=0, nudge={7: 3_000})
    code, data = _compare(capsys, str(cap), str(golden))
    assert code == 1
    assert data["timing"]["max_abs_diff_ns"] == 3000 and data["timing"]["max_at_step"] == 7
    assert data["timing"]["beyond_tolerance"] == 1
    code, data = _compare(capsys, str(cap), str(golden), "--tolerance", "5us")
    assert code == 0


def test_missing_step_fails_with_the_counts(golden: Path, tmp_path: Path, capsys) -> None:
    cap = _as_capture(golden, tmp_path / "c.vcd", shift=0, drop_last=True)
    code = main(["compare", str(cap), str(golden), "--drive", "gecko-g202"])
    out, _ = capsys.readouterr()
    assert code == 1
    assert "step count:     39 vs 40 (DIFFERENT)" in out
    assert "final position: +39 vs +40 (DIFFERENT)" in out


def test_rule_regression_against_the_seed_goldens(capsys) -> None:
    repo = Path(__file__).resolve().parents[3]
    cap = repo / "captures" / "golden" / "g202-p20-worst-dirhold.vcd"
    gold = repo / "captures" / "golden" / "g202-p16-dirhold2-worst.vcd"
    if not (cap.exists() and gold.exists()):
        pytest.skip("golden captures not generated yet")
    code, data = _compare(capsys, str(cap), str(gold), "--tolerance", "10us")
    hold = next(r for r in data["rules"] if r["id"] == "dir_hold")
    assert hold["golden"]["verdict"] == "pass" and hold["capture"]["verdict"] == "fail"
    assert hold["change"] == "worse" and hold["delta_margin_ns"] == -12000
    assert code == 1 and data["verdict"] == "fail"


def test_bad_tolerance_is_exit_2(golden: Path, capsys) -> None:
    code = main(
        ["compare", str(golden), str(golden), "--drive", "gecko-g202", "--tolerance", "2 parsecs"]
    )
    _, err = capsys.readouterr()
    assert code == 2 and len(err.strip().splitlines()) == 1


def test_identical_captures_without_dir_pass(golden: Path, tmp_path: Path, capsys) -> None:
    """Issue 12: with no DIR channel both final positions are unknown; compare said 'unknown vs
    unknown (DIFFERENT)' and failed, so no grbl capture could ever pass."""
    cap = open_capture(golden)
    step = cap.channel("step")
    only_step = write_vcd(
        tmp_path / "s.vcd", {"STEP": (step.initial, [int(t) for t in step.edges])}
    )
    code, data = _compare(capsys, str(only_step), str(only_step))
    assert code == 0 and data["verdict"] == "pass" and data["failures"] == []
    assert main(["compare", str(only_step), str(only_step), "--drive", "gecko-g202"]) == 0
    assert "no DIR on either: not compared" in capsys.readouterr().out


def test_a_fail_says_which_line_failed(golden: Path, tmp_path: Path, capsys) -> None:
    cap = _as_capture(golden, tmp_path / "c.vcd", shift=0, drop_last=True)
    code, data = _compare(capsys, str(cap), str(golden))
    assert code == 1 and "step count 39 vs 40" in data["failures"]
    assert main(["compare", str(cap), str(golden), "--drive", "gecko-g202"]) == 1
    assert capsys.readouterr().out.splitlines()[0].startswith("verdict: FAIL (step count 39 vs 40")


def test_golden_mapping_error_hints_golden_map(golden: Path, tmp_path: Path, capsys) -> None:
    cap = _as_capture(golden, tmp_path / "c.vcd", shift=0)
    code = main(
        ["compare", str(cap), str(golden), "--drive", "gecko-g202", "--golden-map", "step=NOPE"]
    )
    err = capsys.readouterr().err
    assert code == 2 and "--golden-map" in err and len(err.strip().splitlines()) == 1


@pytest.mark.parametrize("tolerance", ["2000", "2 kHz"])
def test_tolerance_needs_a_time_with_its_unit(golden: Path, capsys, tolerance: str) -> None:
    """Issue 12's units policy: a bare number is refused with the fix spelled out."""
    assert (
        main(
            ["compare", str(golden), str(golden), "--drive", "gecko-g202", "--tolerance", tolerance]
        )
        == 2
    )
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--tolerance" in err[0]


def test_a_failing_capture_against_its_failing_golden_says_both_fail(capsys) -> None:
    """Issue 34: compare of a failing capture against a failing golden printed a bare
    ``verdict: PASS``. The line says what was compared: it matches the golden trace, and both
    fail the rule."""
    from wavecheck.cli import main

    golden = Path(__file__).resolve().parents[3] / "captures" / "golden"
    bad = str(golden / "g202-p20-worst-dirhold.vcd")
    assert main(["check", bad, "--drive", "gecko-g202"]) == 1  # the golden itself fails
    capsys.readouterr()
    assert main(["compare", bad, bad, "--drive", "gecko-g202"]) == 0
    first = capsys.readouterr().out.splitlines()[0]
    assert first == (
        "verdict: PASS (matches the golden trace: 4 steps, times within ±2 us, no rule worse; "
        "both fail dir_hold: the capture fails as its golden does)"
    )
    assert main(["compare", bad, bad, "--drive", "gecko-g202", "--format", "json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["said"][1] == "both fail dir_hold: the capture fails as its golden does"
    good = str(golden / "a4988-spike.vcd")
    assert main(["compare", good, good, "--drive", "a4988"]) == 0
    first = capsys.readouterr().out.splitlines()[0]
    assert (
        first.startswith("verdict: PASS (matches the golden trace: 800 steps")
        and "both" not in first
    )
