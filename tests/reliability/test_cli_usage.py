"""Bad options on a good capture: exit 2, one line, no traceback, no output file."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.reliability.corpus import vcd_text
from tests.reliability.helpers import assert_no_output, cli

BAD = {
    "unknown-drive": ["--drive", "gecko-g2O2"],
    "unknown-role": ["--map", "stpe=STEP"],
    "map-no-equals": ["--map", "STEP"],
    "map-empty-channel": ["--map", "step="],
    "unknown-channel": ["--map", "step=NOPE"],
    "channel-index-out-of-range": ["--map", "step=7"],
    "invert-unmapped": ["--invert", "enable"],
    "invert-unknown-role": ["--invert", "wobble"],
    "type-99": ["--type", "99"],
    "type-negative": ["--type", "-1"],
    "type-junk": ["--type", "two"],
    "type-15-no-table": ["--type", "15"],
    "user-table-junk": ["--type", "15", "--user-step-type", "1,x"],
    "resolution-negative": ["--resolution", "-1ns"],
    "resolution-junk": ["--resolution", "fine"],
    "resolution-frequency": ["--resolution", "1MHz"],
    "samplerate-zero": ["--samplerate", "0"],
    "samplerate-negative": ["--samplerate", "-1MHz"],
    "max-violations-negative": ["--max-violations", "-1"],
    "format-unknown": ["--format", "xml"],
    "output-folder-missing": ["-o", "{tmp}/no/such/folder/r.json"],
    "input-format-unknown": ["--input-format", "nosuch"],
    "phase-type-needs-phases": ["--type", "2"],
}


@pytest.mark.parametrize("name", sorted(BAD))
def test_check_usage_errors(tmp_path: Path, name: str) -> None:
    cap = tmp_path / "c.vcd"
    cap.write_text(vcd_text())
    out = tmp_path / "out"
    out.mkdir()
    extra = [a.replace("{tmp}", str(tmp_path)) for a in BAD[name]]
    argv = ["check", str(cap), "--drive", "gecko-g202", "--map", "step=STEP,dir=DIR", *extra]
    if "-o" not in extra:
        argv += ["-o", str(out / "r.json")]
    rc, stdout, err = cli("wavecheck", argv)
    assert rc == 2, f"exit {rc}: {err or stdout[:200]}"
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1 and "Traceback" not in err, err
    assert_no_output(out)
