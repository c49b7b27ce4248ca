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
