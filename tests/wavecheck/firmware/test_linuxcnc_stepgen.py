"""LinuxCNC's software stepgen as its source makes it (:mod:`wavecheck.firmware.linuxcnc_stepgen`;
line numbers are LinuxCNC ``src/hal/components/stepgen.c`` at git f1270d6ed7)."""

from __future__ import annotations

import pytest

from tools.firmware_corpus import CORPUS
from wavecheck.firmware import read_firmware

pytestmark = pytest.mark.skipif(not CORPUS.is_dir(), reason="shared firmware corpus not present")
LCNC = CORPUS / "linuxcnc/configs"


def test_software_stepgen_maxvel_clamps_the_rate() -> None:
    """stepgen.c clamps the velocity to maxvel: Sherline4Axis_inch.ini [JOINT_0] STEPGEN_MAXVEL
    .4 (line 150) x INPUT_SCALE 16000 (153) = 6400 steps/s, under the 10 kHz of
    (steplen + stepspace) x BASE_PERIOD."""
    cfg = read_firmware(LCNC / "by_machine/sherline/Sherline4Axis/Sherline4Axis_inch.ini")
    assert cfg.axis("stepgen.0").max_rate.value == 6400


def test_sim_parport_reset_does_nothing() -> None:
    """spartan.hal:3 loads sim_parport and :51 sets pin-02-out-reset, but sim_parport's reset
    function is a no-op (sim_parport.comp:28): the pulse is steplen (1 period of 100 us), not
    the 5 us reset-time hal_parport would make (hal_parport.c:368-385), and stepspace 0 leaves
    no low time at the top rate."""
    s = read_firmware(LCNC / "sim/gscreen/spartan/spartan.ini").axis("stepgen.0")
    assert s.pulse.value == 100_000 and s.idle.value == 0
    assert any("sim_parport" in n for n in s.notes)
    real = read_firmware(LCNC / "by_interface/parport/gecko/Gecko_540B3/Gecko_540B3.ini")
    assert real.axis("stepgen.0").pulse.value == 1000  # hal_parport: reset-time 1000 ns
