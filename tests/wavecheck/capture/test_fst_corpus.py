"""The hypothesis corpus written as FST reads back to the same edges as its VCD (issue 16: "VCD =
FST = GHW … on the hypothesis corpus written in each format where a writer exists"). GTKWave's
vcd2fst is the FST writer; GHW has no writer outside GHDL (the simulator tests cover it)."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings

from tests.reliability.test_reference_agreement import _vcd, waveforms
from wavecheck.capture.open import open_capture

pytestmark = pytest.mark.skipif(shutil.which("vcd2fst") is None, reason="needs GTKWave's vcd2fst")


@settings(
    max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(w=waveforms())
def test_fst_reads_as_its_vcd(tmp_path: Path, w: dict) -> None:
    vcd = _vcd(tmp_path / "w.vcd", {"STEP": w["step"], "DIR": w["dir"]}, w["end"])
    fst = tmp_path / "w.fst"
    subprocess.run(["vcd2fst", str(vcd), str(fst)], check=True, capture_output=True, timeout=60)
    a, b = open_capture(vcd), open_capture(fst)
    assert b.format == "fst" and a.timebase == b.timebase
    for name in ("STEP", "DIR"):
        ca, cb = a.channel(name), b.channel(name)
        assert (ca.initial, ca.edges.tolist()) == (cb.initial, cb.edges.tolist()), name
