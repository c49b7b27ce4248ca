"""A parallel-port pin between a stepgen output and the wire (:mod:`wavecheck.linuxcnc.parport`;
LinuxCNC ``hal_parport.c`` and ``sim_parport.comp`` at git f1270d6ed7)."""

from __future__ import annotations

from fractions import Fraction as F

import pytest

from tools.firmware_corpus import CORPUS
from wavecheck.firmware import read_firmware
from wavecheck.linuxcnc.configuration import scan
from wavecheck.linuxcnc.parport import pin_out

pytestmark = pytest.mark.skipif(not CORPUS.is_dir(), reason="shared firmware corpus not present")
LCNC = CORPUS / "linuxcnc/configs"


@pytest.mark.parametrize(
    ("ini", "period", "pin", "reset", "simulated"),
    [
        # Gecko_540B3.hal:7 reset-time 1000, :26 pin-02 reset: hal_parport lowers it 1000 ns on
        ("by_interface/parport/gecko/Gecko_540B3/Gecko_540B3.ini", 23000, "parport.0.pin-02-out",
         F(1000), False),
        # the clamp: reset-time at most P/4 (hal_parport.c:371): 1000 ns at P = 2000 -> 500
        ("by_interface/parport/gecko/Gecko_540B3/Gecko_540B3.ini", 2000, "parport.0.pin-02-out",
         F(500), False),
        # spartan.hal:3 sim_parport, :51 pin-02 reset: sim_parport's reset is a no-op (:28)
        ("sim/gscreen/spartan/spartan.ini", 100000, "parport.0.pin-02-out", None, True),
        # stepper_mm: standard_pinout.hal:14 Xstep on pin-03, no reset
        ("by_interface/parport/stepper/stepper_mm.ini", 50000, "parport.0.pin-03-out", None, False),
    ],
)  # fmt: skip
def test_pin_out(ini: str, period: int, pin: str, reset: F | None, simulated: bool) -> None:
    out = pin_out(scan(LCNC / ini), "stepgen.0.step", period)
    assert (out.pin, out.reset_ns, out.simulated) == (pin, reset, simulated)


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
