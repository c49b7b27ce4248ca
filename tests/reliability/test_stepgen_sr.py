"""A .sr written by ``stepgen simulate`` is checked as exactly as its VCD (issue 12).

At a 40 kHz base thread every edge is on the 25 µs grid, so the .sr is written at 40 kHz; read as
sampled, each 25 µs pulse was 25 µs ± 25 µs against a 4.5 µs limit: indeterminate unless the
user gave ``--resolution 0``. The file now says its edges are exact.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from tests.reliability.helpers import cli


@pytest.mark.parametrize("base", ["25us", "50us"])
def test_stepgen_sr_checks_like_its_vcd(tmp_path: Path, base: str) -> None:
    verdicts = {}
    for suffix in (".sr", ".vcd"):
        out = tmp_path / f"run{suffix}"
        rc, _, err = cli(
            "stepgen",
            ["simulate", "--base-period", base, "--mode", "velocity", "--position-scale", "1000",
             "--velocity", "10", "--duration", "20ms", "-q", "-o", str(out)],
        )  # fmt: skip
        assert rc == 0, err
        report = tmp_path / f"report{suffix}.json"
        rc, _, err = cli(
            "wavecheck",
            ["check", str(out), "--drive", "gecko-g202", "--format", "json", "-o", str(report)],
        )
        data = json.loads(report.read_text())
        verdicts[suffix] = (rc, data["verdict"])
    assert verdicts[".sr"] == verdicts[".vcd"] == (0, "pass"), verdicts
