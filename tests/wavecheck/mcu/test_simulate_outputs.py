"""``wavecheck simulate grbl``'s inputs and outputs beside the VCD: the user's own ELF, the
``$$`` dump read back (``--settings-out``, ``--check-settings``), check's report formats."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from tests.wavecheck.mcu.helpers import GRBL_SRC, SIMAVR_SRC
from wavecheck.cli import main

#: grbl simulated end to end (make test-all and CI run it; make test leaves it out)
pytestmark = pytest.mark.slow

SETTINGS = "$0=3\n$100=250\n$110=500\n$120=10\n"
JOB = "G1 X2 F500\nG1 X0\n"


def _simulate(tmp: Path, *extra: str, name: str = "out") -> tuple[int, Path]:
    s, g = tmp / "s.txt", tmp / "job.nc"
    s.write_text(SETTINGS)
    g.write_text(JOB)
    vcd = tmp / f"{name}.vcd"
    code = main(
        ["simulate", "grbl", "--settings", str(s), "--gcode", str(g), "--vcd", str(vcd)]
        + ["--drive", "drv8825", "--grbl-src", str(GRBL_SRC), "--simavr-src", str(SIMAVR_SRC)]
        + list(extra)
    )
    return code, vcd


def test_the_users_elf_gives_the_same_waveform_as_the_source_build(grbl, tmp_path):
    built = _simulate(tmp_path, name="built")
    given = _simulate(tmp_path, "--elf", str(grbl), name="given")
    assert built[0] == given[0] == 0
    assert built[1].read_bytes() == given[1].read_bytes()


def test_the_settings_grbl_printed_back(grbl, tmp_path, capsys):
    dump = tmp_path / "dump.txt"
    code, _ = _simulate(tmp_path, "--settings-out", str(dump), "--check-settings")
    lines = dump.read_text().splitlines()
    assert {"$0=3", "$100=250.000", "$110=500.000", "$120=10.000"} <= set(lines)
    assert len(lines) == 34  # grbl 1.1h's $$ (report.c:181-226)
    out = capsys.readouterr().out
    # the firmware section: $0=3 configured is 2.4375 us at the pin (39 cycles: $0 less grbl's
    # 562.5 ns, stepper.c:241, 344-345), and the shortest pulse simavr made is exactly that
    assert f"firmware: grbl {dump}" in out
    assert "pulse      PASS          configured 2.438 us pulses; shortest measured 2.438 us" in out
    assert code == 0  # the pin does what grbl 1.1h makes of $0=3: no finding (issue 32)


def test_junit_report(grbl, tmp_path):
    report = tmp_path / "r.xml"
    code, _ = _simulate(tmp_path, "--format", "junit", "-o", str(report))
    assert code == 0
    suite = ET.parse(report).getroot()
    assert suite.iter("testcase") and "failures" in (suite.attrib or next(iter(suite)).attrib)
