"""Start-up stays light (issue 18): the heavy or rarely needed layers are imported only by the
command that uses them, so ``wavecheck --help``, ``wavecheck drives`` and a check of a small VCD
load none of them. (Timings are in ``make bench``, not here: this checks what is imported.)"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
TINY = ROOT / "captures/golden/g202-p16-dirhold2-worst.vcd"

#: Imported only where used: plotting, HTML/XML, pyvcd (the writer's header, the reference
#: reader), the sigrok-cli layer, firmware readers, latency analysis, cross-checks, reports
#: other than text/JSON, the live watch, cocotb.
LAZY = (
    "matplotlib",
    "lxml",
    "vcd",
    "wavecheck.capture.sigrokcli",
    "wavecheck.crosscheck",
    "wavecheck.firmware.grbl",
    "wavecheck.firmware.marlin",
    "wavecheck.firmware.capture",
    "wavecheck.lattice",
    "wavecheck.live.watch",
    "wavecheck.live.sigrok",
    "wavecheck.live.record",
    "cocotb",
    "wavecheck.report.html",
    "wavecheck.report.plot",
    "wavecheck.report.junit",
    "wavecheck.report.gtkw",
)


def _loaded_after(argv: list[str]) -> set[str]:
    code = (
        "import sys\n"
        "from wavecheck.cli import main\n"
        "try:\n"
        f"    main({argv!r})\n"
        "except SystemExit:\n"
        "    pass\n"
        "print('\\n'.join(sys.modules))\n"
    )
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
    assert run.returncode == 0, run.stderr
    return set(run.stdout.split())


@pytest.mark.parametrize(
    "argv",
    [[], ["--help"], ["drives"], ["check", str(TINY), "--drive", "gecko-g202"]],
    ids=["import", "help", "drives", "check-tiny-vcd"],
)
def test_start_up_does_not_import_heavy_layers(argv: list[str]) -> None:
    if not argv:  # just the import of the command's module
        code = "import sys, wavecheck.cli; print('\\n'.join(sys.modules))"
        loaded = set(subprocess.run([sys.executable, "-c", code], capture_output=True,
                                    text=True, check=True).stdout.split())  # fmt: skip
    else:
        loaded = _loaded_after(argv)
    assert "wavecheck.cli" in loaded  # the probe sees what it should
    assert sorted(m for m in LAZY if m in loaded) == []


def test_the_probe_sees_a_lazy_import_when_it_happens() -> None:
    loaded = _loaded_after(["check", str(TINY), "--drive", "gecko-g202", "--format", "junit"])
    assert "wavecheck.report.junit" in loaded
