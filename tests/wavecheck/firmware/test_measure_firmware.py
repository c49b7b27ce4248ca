"""``measure --firmware`` (issue 15: "--firmware FILE on check, measure and config"): the measured
minima against the configured figures, compared as ``check --firmware`` compares a report."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from tests.conftest import SHARED, write_vcd
from wavecheck.cli import main

GRBL = SHARED / "firmware/grbl/settings.md"  # line 32: $0=10 (us); X max 2083.3 Hz
pytestmark = pytest.mark.skipif(not GRBL.is_file(), reason="shared firmware files not present")


def _capture(tmp_path: Path, width_ns: int, period_ns: int = 1_000_000) -> Path:
    starts = [1000 + k * period_ns for k in range(5)]
    edges = [t for s in starts for t in (s, s + width_ns)]
    dir_edge = [starts[2] - 3000]  # 3 us DIR setup before the 3rd step
    return write_vcd(tmp_path / "run.vcd", {"STEP": (0, edges), "DIR": (0, dir_edge)},
                     end=starts[-1] + period_ns)  # fmt: skip


def _measure(capsys: pytest.CaptureFixture[str], vcd: Path, *extra: str) -> tuple[int, dict]:  # type: ignore[type-arg]
    code = main(["measure", str(vcd), "--map", "step=STEP,dir=DIR", "--firmware", str(GRBL),
                 "--format", "json", "-q", *extra])  # fmt: skip
    return code, json.loads(capsys.readouterr().out)


@pytest.mark.parametrize(
    ("width_ns", "period_ns", "failing", "code"),
    [
        (2500, 1_000_000, {"pulse"}, 1),  # 2.5 us pulses, configured $0=10 us
        (10_000, 1_000_000, set(), 0),  # as configured
        (10_000, 100_000, {"rate"}, 1),  # 10 kHz, configured at most 2083.3 Hz
    ],
)
def test_measured_minima_against_the_configuration(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], width_ns: int, period_ns: int,
    failing: set[str], code: int,
) -> None:  # fmt: skip
    rc, doc = _measure(capsys, _capture(tmp_path, width_ns, period_ns))
    fw = doc["axes"][0]["firmware"]
    assert {c["what"] for c in fw["comparisons"] if c["verdict"] == "fail"} == failing
    assert rc == code and fw["findings"] == len(failing)
    pulse = next(c for c in fw["comparisons"] if c["what"] == "pulse")
    assert (pulse["configured"], pulse["measured"]) == (9437.5, width_ns)  # $0 - 562.5 ns


def test_same_comparisons_as_check(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """One comparison, two sources: measure's minima and check's report give the same
    comparisons where the drive measures the interval (leadshine-dm542 states pulse and setup)."""
    vcd = _capture(tmp_path, 2500)
    _, measured = _measure(capsys, vcd)
    main(["check", str(vcd), "--map", "step=STEP,dir=DIR", "--drive", "leadshine-dm542",
          "--firmware", str(GRBL), "--format", "json", "-q"])  # fmt: skip
    checked = json.loads(capsys.readouterr().out)["firmware"]
    by_what = {c["what"]: c for c in measured["axes"][0]["firmware"]["comparisons"]}
    for c in checked["comparisons"]:
        m = by_what[c["what"]]
        assert (m["configured"], m["measured"], m["verdict"]) == (
            c["configured"], c["measured"], c["verdict"]
        ), c["what"]  # fmt: skip


def test_text_report_and_no_firmware(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    vcd = _capture(tmp_path, 2500)
    assert (
        main(["measure", str(vcd), "--map", "step=STEP,dir=DIR", "--firmware", str(GRBL), "-q"])
        == 1
    )
    out = capsys.readouterr().out
    assert "firmware: grbl" in out and "configured 9.438 us pulses" in out
    assert main(["measure", str(vcd), "--map", "step=STEP,dir=DIR", "-q"]) == 0
    assert "firmware" not in capsys.readouterr().out
