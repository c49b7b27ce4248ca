"""The report model and its text / JSON renderers."""

from __future__ import annotations

import json

from tests.engine_probe import run_check
from tests.wavecheck.waves import capture, drive, g202, pulses
from wavecheck.report import overall_verdict, render_json, render_text, report_dict

US = 1000


def _failing_report():
    # 30 pulses; pulses i ≡ 0 mod 3 are (4500 − i) ns high: 10 step_high violations
    starts = [i * 40 * US for i in range(30)]
    edges = []
    for i, s in enumerate(starts):
        edges += [s + 100, s + 100 + (4500 - i if i % 3 == 0 else 5 * US)]
    cap = capture({"S": (0, edges), "D": (0, [15 * 40 * US + 30 * US])})
    return run_check(cap, g202(), {"step": "S", "dir": "D"}, invert=["dir"])


def test_overall_verdict() -> None:
    assert overall_verdict(["pass", "fail", "indeterminate"]) == "fail"
    assert overall_verdict(["pass", "indeterminate", "unchecked"]) == "indeterminate"
    assert overall_verdict(["pass", "unchecked"]) == "pass"
    assert overall_verdict(["unchecked"]) == "unchecked"


def test_violations_worst_first_and_capped() -> None:
    report = _failing_report()
    assert report.total_violations == 9  # i = 3, 6, …, 27 (i = 0 is exactly 4.5 µs)
    worst = report.violations(4)
    assert [v.measured_ns for v in worst] == [4473, 4476, 4479, 4482]
    assert len(report.violations()) == 9


def test_json_keys_and_values() -> None:
    report = _failing_report()
    data = json.loads(render_json(report, violation_cap=3))
    assert set(data) == {
        "capture",
        "drive",
        "steps",
        "rules",
        "violations",
        "violations_total",
        *("violations_listed", "violations_truncated"),  # issue 34: the document says it
        "max_step_rate_hz",
        "verdict",
        *("verdict_line", "unchecked", "required", "exit_code"),  # issue 26: what it claims
    }
    assert {"path", "format", "resolution_ns", "duration_s", "channels"} <= set(data["capture"])
    assert {"id", "name", "source"} <= set(data["drive"])
    assert {"count", "forward", "reverse", "final_position"} <= set(data["steps"])
    for r in data["rules"]:
        assert {
            "id",
            "limit_ns",
            "checked",
            "violations",
            "indeterminate",
            "min_margin_ns",
            "min_margin_at_s",
            "verdict",
        } <= set(r)
    assert len(data["violations"]) == 3 and data["violations_total"] == 9
    assert data["violations_listed"] == 3 and data["violations_truncated"] is True
    whole = json.loads(render_json(report, violation_cap=100))
    assert whole["violations_listed"] == 9 and whole["violations_truncated"] is False
    v = data["violations"][0]
    assert v == {
        "rule": "step_high",
        "time_s": v["time_s"],
        "measured_ns": 4473,
        "limit_ns": 4500,
        "margin_ns": -27,
    }
    assert abs(v["time_s"] - (27 * 40 + 0.1) * 1e-6) < 1e-12
    assert {"drive", "observed", "headroom"} <= set(data["max_step_rate_hz"])
    assert data["verdict"] == "fail"
    steps = data["steps"]
    # DIR inverted: captured low → drive-side high → reverse for the first 16 steps, then forward
    assert (steps["count"], steps["forward"], steps["reverse"], steps["final_position"]) == (
        30,
        14,
        16,
        -2,
    )
    high = next(r for r in data["rules"] if r["id"] == "step_high")
    assert high["min_margin_ns"] == -27 and high["checked"] == 30


def test_text_report() -> None:
    text = render_text(_failing_report(), max_violations=2)
    assert text.startswith("verdict: FAIL")
    assert "step_high" in text and "… and 7 more" in text
    assert "max step rate:" in text
    ok = run_check(capture({"S": (0, pulses([10, 100], 5))}), drive(step_high=1), {"step": "S"})
    text = render_text(ok)
    assert text.startswith("verdict: PASS") and "direction unknown" in text
    assert report_dict(ok)["steps"]["final_position"] is None
