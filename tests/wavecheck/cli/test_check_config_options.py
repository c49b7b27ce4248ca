"""check takes a stepgen configuration as options (--base-period, --steplen ...), as DESIGN.md's
"Maximum achievable step rate" says, besides LinuxCNC's INI/HAL files."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from wavecheck.cli import main

REPO = Path(__file__).resolve().parents[3]
GOOD = str(REPO / "captures/golden/g202-p16-dirhold2-worst.vcd")


def _rates(capsys: pytest.CaptureFixture[str], *argv: str) -> dict:
    assert main(["check", GOOD, "--drive", "gecko-g202", "--format", "json", *argv]) == 0
    return json.loads(capsys.readouterr().out)["max_step_rate_hz"]


@pytest.mark.parametrize(
    ("argv", "config", "latency_safe"),
    [
        # seed: P = 16 us, dirhold 2 periods, J = 11 us -> 1/(2 x 16 us) = 31,250 steps/s
        (["--base-period", "16us", "--dirhold", "32000ns", "--latency", "11us"], 31250, 31250),
        # the same drive at P = 16 us but dirhold 1: hold 16 - 11 = 5 us < 20 us at any rate
        (["--base-period", "16us", "--latency", "11us"], 31250, None),
        # P = 31 us, defaults: 1/(2 x 31 us) = 16,129 steps/s
        (["--base-period", "31us", "--latency", "11us"], 1 / 62e-6, 1 / 62e-6),
        # steplen 2 periods at 20 us: 1/(3 x 20 us)
        (["--base-period", "20000ns", "--steplen", "40us"], 1 / 60e-6, None),
    ],
)
def test_config_rates_from_options(
    capsys: pytest.CaptureFixture[str], argv: list[str], config: float, latency_safe: float | None
) -> None:
    rates = _rates(capsys, *argv)
    assert rates["config"] == pytest.approx(config)
    assert rates.get("latency_safe") == (
        None if latency_safe is None else pytest.approx(latency_safe)
    )


@pytest.mark.parametrize(
    "bad", [["--base-period", "0"], ["--steplen", "1.5ns"], ["--dirhold", "5 kHz"]]
)
def test_bad_config_options_exit_2(capsys: pytest.CaptureFixture[str], bad: list[str]) -> None:
    assert main(["check", GOOD, "--drive", "gecko-g202", "--base-period", "16us", *bad]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("wavecheck: error:")
