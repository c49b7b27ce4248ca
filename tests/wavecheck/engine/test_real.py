"""The engine on real captures (../shared/captures), against several drives.

Expected figures were derived independently of wavecheck's readers and engine, with sigrok-cli
0.7.2's decoders on the same files:

- step counts: ``sigrok-cli -i F -P counter:data=CH:data_edge=rising -A counter=edge_count``
  (last line): Smoothieware X (ch 5) 739, Y (ch 3) 739; grbl ``STEP (Y axis)`` 10508. DIR (ch 4, 6)
  has no edge (``data_edge=any`` counts nothing) and is low (``-O csv``).
- pulse widths: ``sigrok-cli -i F -P timing:data=CH -A timing=time --protocol-decoder-samplenum``,
  widths = sample-number differences, high and low alternating (STEP starts low):
  Smoothieware X high 44..63 samples, low ≥ 1269; Y high 42..50, low ≥ 1287 (12 MHz);
  grbl high 19..27 samples, low ≥ 473 (2 MHz).
  Against the G202's 4.5 µs = 54 samples at T = 1 sample: X has 530 highs ≤ 53 (fail),
  204 of exactly 54 (indeterminate), 5 ≥ 55 (pass); every Y high is ≤ 50 (fail).
"""

from __future__ import annotations

from fractions import Fraction
from pathlib import Path

import pytest

from wavecheck import check

SMOOTHIE_T = Fraction(1000, 12)  # ns per sample at 12 MHz
GRBL_T = Fraction(500)  # ns per sample at 2 MHz


def _rule(report, rule_id):
    r = report.rule(rule_id)
    assert r is not None, rule_id
    return r


@pytest.mark.parametrize(
    ("axis", "step", "dir_", "min_high", "max_high", "min_low"),
    [("X", "5", "6", 44, 63, 1269), ("Y", "3", "4", 42, 50, 1287)],
)
def test_smoothieware_axes_against_a4988(
    smoothie_sr: Path, axis, step, dir_, min_high, max_high, min_low
) -> None:
    report = check(smoothie_sr, "a4988", map={"step": step, "dir": dir_})
    assert report.steps.count == 739
    assert (report.steps.forward, report.steps.reverse, report.steps.final_position) == (
        739,
        0,
        739,
    )
    high, low = _rule(report, "step_high"), _rule(report, "step_low")
    assert high.checked == 739 and low.checked == 738
    assert high.min_measured_ns == min_high * SMOOTHIE_T
    assert high.max_measured_ns == max_high * SMOOTHIE_T
    assert low.min_measured_ns == min_low * SMOOTHIE_T
    assert _rule(report, "dir_setup").verdict == "unchecked"  # DIR never changes
    assert report.verdict == "pass" and report.exit_code == 0


def test_smoothieware_reverse_when_dir_high_is_forward(smoothie_sr: Path) -> None:
    report = check(smoothie_sr, "a4988", map={"step": "5", "dir": "6"}, forward_level=1)
    assert report.steps.final_position == -739


def test_smoothieware_against_g202(smoothie_sr: Path) -> None:
    x = check(smoothie_sr, "gecko-g202", map={"step": "5", "dir": "6"})
    high = _rule(x, "step_high")
    assert (high.violations, high.indeterminate, high.checked) == (530, 204, 739)
    assert high.min_margin_ns == 44 * SMOOTHIE_T - 4500
    assert x.verdict == "fail" and x.exit_code == 1
    y = check(smoothie_sr, "gecko-g202", map={"step": "3", "dir": "4"})
    assert _rule(y, "step_high").violations == 739
    # the worst violation is the narrowest pulse
    assert y.violations(1)[0].measured_ns == 42 * SMOOTHIE_T


def test_smoothieware_coarser_resolution_makes_results_indeterminate(smoothie_sr: Path) -> None:
    # DRV8825 high ≥ 1.9 µs at T = 2 µs: pass needs ≥ 3.9 µs (47 samples); nothing can fail.
    # sigrok-cli's timing decoder: 462 X highs of 44..46 samples, 277 of ≥ 47.
    report = check(smoothie_sr, "drv8825", map={"step": "5"}, resolution="2us")
    high = _rule(report, "step_high")
    assert (high.violations, high.indeterminate, high.checked) == (0, 462, 739)
    assert report.verdict == "indeterminate" and report.exit_code == 3


@pytest.mark.parametrize(
    ("drive", "high_fails", "verdict"),
    [
        ("gecko-g202", 0, "pass"),
        ("a4988", 0, "pass"),
        ("drv8825", 0, "pass"),
        ("tb6560", 10508, "fail"),
    ],
)
def test_grbl_y_axis(grbl_sr: Path, drive: str, high_fails: int, verdict: str) -> None:
    report = check(grbl_sr, drive, map={"step": "STEP (Y axis)"})
    assert report.steps.count == 10508
    assert report.steps.final_position is None  # no DIR channel was captured
    high = _rule(report, "step_high")
    assert high.checked == 10508 and high.violations == high_fails
    assert high.min_measured_ns == 19 * GRBL_T and high.max_measured_ns == 27 * GRBL_T
    low = report.rule("step_low")  # the TB6560 states no low time
    assert low is None or low.min_measured_ns == 473 * GRBL_T
    for rule_id in ("dir_setup", "dir_hold"):
        r = report.rule(rule_id)
        assert r is None or (r.verdict == "unchecked" and r.checked == 0)
    assert report.verdict == verdict
    assert report.rates.longest_pulse_ns == 27 * GRBL_T


@pytest.mark.sigrok
def test_counts_match_sigrok_counter(smoothie_sr: Path) -> None:
    """Re-derive the Smoothieware step counts with sigrok-cli's counter decoder."""
    import shutil
    import subprocess

    if shutil.which("sigrok-cli") is None:
        pytest.skip("sigrok-cli not installed")
    for ch in ("3", "5"):
        out = subprocess.run(
            [
                "sigrok-cli",
                "-i",
                str(smoothie_sr),
                "-P",
                f"counter:data={ch}:data_edge=rising",
                "-A",
                "counter=edge_count",
            ],
            capture_output=True,
            text=True,
            check=False,
            timeout=120,
        )
        assert out.stderr.strip() == ""
        count = int(out.stdout.strip().splitlines()[-1].split(":")[-1])
        assert count == check(smoothie_sr, "a4988", map={"step": ch}).steps.count == 739


def test_phase_channels_suggest_the_step_type() -> None:
    """Issue 12: the README's JUnit example met the shipped quadrature trace and the hint said
    'add --map' where --type 2 is the fix."""
    import pytest

    import wavecheck
    from wavecheck.errors import UsageError

    golden = Path(__file__).resolve().parents[3] / "captures" / "golden" / "stepgen1-quadrature.vcd"
    with pytest.raises(UsageError, match=r"--type 2 for quadrature"):
        wavecheck.check(golden, "gecko-g202")
    assert wavecheck.check(golden, "gecko-g202", step_type=2).steps.count > 0
