"""A parallel-port pin between a LinuxCNC stepgen output and the wire.

When ``stepgen.N.step`` drives a parallel-port pin (``net … parport.P.pin-NN-out``)
its ``-invert`` makes pulses low, and with ``-reset 1`` and ``parport.P.reset`` in the base thread
the pin is written high each period and reset ``parport.P.reset-time`` ns later, at most P/4
(``src/hal/drivers/hal_parport.c`` 368-385, the clamp at 371): the pulse on the pin is the reset
time and the rest of the period is idle, whatever ``stepspace`` is (StepConf's "doublestep":
``steplen 1``, ``stepspace 0``, one step per period). ``sim_parport``'s reset does nothing
(``sim_parport.comp``:28): there the pulse is steplen. (LinuxCNC sources at git f1270d6ed7.)
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction

from wavecheck.linuxcnc.configuration import LinuxCNCFiles
from wavecheck.linuxcnc.files import ini_value, int_ns

__all__ = ["PinOut", "pin_out"]


@dataclass(frozen=True)
class PinOut:
    """What stands between a stepgen output and the wire: a parallel-port pin, if any.

    Attributes:
        pin: the port pin (``parport.0.pin-02-out``), "" when the output drives no port pin.
        inverted: the pin's ``-invert`` is set.
        reset_ns: the pulse the ``reset`` function makes (ns, after hal_parport's P/4 clamp),
            None when the pin is not reset.
        reset_where: where the reset time (or its absence) comes from.
    """

    pin: str = ""
    inverted: bool = False
    reset_ns: Fraction | None = None
    reset_where: str = ""
    reset_unknown: str = ""
    simulated: bool = False
    """The port is ``sim_parport``, whose ``reset`` function does nothing (sim_parport.comp:28)."""


def _true(value: str) -> bool:
    return value.strip().lower() in ("1", "true")


def pin_out(files: LinuxCNCFiles, output: str, period_ns: int) -> PinOut:
    """The parallel-port pin ``output`` (``stepgen.0.step``) drives, its inversion and reset."""
    pins = [p for p in files.on_signal(output) if p.startswith("parport.") and p.endswith("-out")]
    if not pins:
        return PinOut()
    pin = pins[0]
    port = pin.split(".")[1]
    inverted = _true(files.setp.get(f"{pin}-invert", ("0", ""))[0])
    if not _true(files.setp.get(f"{pin}-reset", ("0", ""))[0]):
        return PinOut(pin, inverted)
    modules = {m for m, _ in files.loads}
    if "sim_parport" in modules and "hal_parport" not in modules:
        return PinOut(pin, inverted, simulated=True)
    funct = f"parport.{port}.reset"
    if funct not in files.thread_of:
        return PinOut(
            pin, inverted, reset_unknown=f"{pin}-reset is set but {funct} runs in no thread"
        )
    found = files.setp.get(f"parport.{port}.reset-time")
    if found is None:
        return PinOut(pin, inverted, reset_unknown=f"parport.{port}.reset-time is not set")
    ns = int_ns(ini_value(found[0], files.ini), found[1], f"parport.{port}.reset-time")
    clamp = Fraction(period_ns // 4)
    return PinOut(pin, inverted, min(Fraction(ns), clamp), found[1])
