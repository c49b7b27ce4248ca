"""A LinuxCNC configuration (an INI and its HAL files, or one HAL file): which step generator it
has is decided by what the HAL files load, never by a ``BASE_PERIOD`` alone.

- ``loadrt stepgen``: LinuxCNC's software stepgen (:mod:`.linuxcnc_stepgen`).
- ``loadrt hostmot2`` (or an ``hm2_…`` board driver) with ``hm2_….stepgen.NN`` parameters: Mesa
  hostmot2 stepgens (:mod:`.hm2`).
- Step generators of other cards (:data:`UNMODELLED`: GM6-PCI, Pico PPMC, Pluto-P) are named as
  such and not modelled.
- Nothing of these (a simulator, a servo configuration): no step generator — refused with one
  line naming the file, the line and what was loaded instead, never an invented stepgen.

HALFILEs that could not be found are named in the refusal when they might hold the generator.
"""

from __future__ import annotations

import os
import re
from collections.abc import Callable
from fractions import Fraction

from wavecheck.errors import ConfigError
from wavecheck.firmware import hm2, linuxcnc_stepgen
from wavecheck.firmware.guarantee import FirmwareConfig, FixRole, GeneratorGuarantee
from wavecheck.linuxcnc.configuration import LinuxCNCFiles, is_ini, scan

__all__ = ["UNMODELLED", "looks_like", "read"]

#: HAL modules with step generators wavecheck does not model, and what they drive.
UNMODELLED: dict[str, str] = {
    "hal_gm": "the General Mechatronics GM6-PCI card's step generators",
    "hal_ppmc": "the Pico Systems PPMC/USC/UPC boards' step generators",
    "pluto_step": "the Pluto-P FPGA's step generators",
    "hal_motenc": "the Vital Systems MOTENC card's outputs",
    "hal_ax5214h": "the Axiom AX5214H card's outputs",
}
_HM2 = re.compile(r"^(hostmot2|hm2_\w+)$")


def looks_like(text: str) -> bool:
    """A LinuxCNC INI (an ``[EMCMOT]``, ``[HAL]`` or ``[KINS]`` section) or a HAL file
    (``loadrt``/``setp``/``net`` commands)."""
    if is_ini(text):
        return bool(
            re.search(
                r"^[ \t]*(\[(EMCMOT|HAL|KINS|TRAJ|EMCIO|EMC|DISPLAY|RS274NGC)\]|#INCLUDE[ \t])",
                text,
                re.M,
            )
        )
    return len(re.findall(r"^[ \t]*(loadrt|setp|net|addf)[ \t]", text, re.M)) >= 2


def read(
    path: str | os.PathLike[str],
    *,
    latency_ns: Fraction | None = None,
    clock_hz: Fraction | None = None,
    want: str | None = None,
    ini: str | os.PathLike[str] | None = None,
) -> FirmwareConfig:
    """Read the step generators of the configuration at ``path`` (see the module doc);
    ``want`` ``"hm2"`` or ``"linuxcnc"`` is what ``--firmware-format`` asked for; ``ini`` the
    INI given beside a HAL file."""
    files = scan(path, ini)
    modules = {m for m, _ in files.loads}
    soft = linuxcnc_stepgen.axes(files, latency_ns) if "stepgen" in modules else []
    hw = hm2.axes(files, clock_hz) if any(_HM2.match(m) for m in modules) else []
    if want == "hm2" and not hw:
        raise ConfigError(_none(files, "hostmot2 stepgen"))
    if not soft and not hw:
        raise ConfigError(_none(files, "stepgen or hostmot2 stepgen"))
    notes = list(files.not_read)
    if files.ini_note:
        notes.insert(0, files.ini_note)
    unsupported = []
    for module, at in files.loads:
        if module in UNMODELLED:
            unsupported.append(f"{at}: loadrt {module}: {UNMODELLED[module]} are not modelled")
    if files.computed:
        unsupported.append(
            f"{len(files.computed)} Tcl command(s) with computed words are not evaluated "
            f"(first: {files.computed[0]})"
        )
    if files.ini is not None:
        unsupported += files.ini.ignored[:5]
    j = latency_ns if latency_ns is not None else Fraction(0)
    if soft:
        notes.insert(
            0,
            f"every interval is n x BASE_PERIOD - J with J = {float(j):g} ns"
            if latency_ns is not None
            else "J = 0 assumed (give --latency for the latency-aware figures, as stepgen plan "
            "does)",
        )
    if hw:
        clock = "unknown (give --hm2-clock for the exact rounding)" if clock_hz is None else (
            f"{float(clock_hz):g} Hz"
        )  # fmt: skip
        notes.insert(0, f"hm2 stepgen clock {clock}; registers are truncated to whole clocks")
    return FirmwareConfig(
        firmware="hm2" if hw and not soft else "linuxcnc",
        path=str(path),
        axes=tuple(soft + hw),
        files=tuple(dict.fromkeys((str(path), *filter(None, [files.found_ini]), *files.hal_files))),
        unsupported=tuple(dict.fromkeys(unsupported)),
        notes=tuple(notes),
        fixer=_fixer({id(a) for a in hw}, hm2.fixer(clock_hz), linuxcnc_stepgen.fixer(j)),
    )


def _none(files: LinuxCNCFiles, what: str) -> str:
    """The one-line refusal of a configuration without a modelled step generator."""
    unmodelled = [(m, at) for m, at in files.loads if m in UNMODELLED]
    if unmodelled:
        module, at = unmodelled[0]
        return f"{at}: loadrt {module}: {UNMODELLED[module]} are not modelled (no {what})"
    loaded = sorted({m for m, _ in files.loads if not m.startswith("[")})
    hals = ", ".join(os.path.basename(h) for h in files.hal_files) or "none"
    place = files.path
    if files.ini is not None and files.ini.get("HAL", "HALFILE") is not None:
        place = files.ini.place("HAL", "HALFILE")
    missing = f"; not found: {files.not_read[0].split(': ', 1)[1].split(' is not')[0]}" if (
        files.not_read
    ) else ""  # fmt: skip
    tcl_files = [os.path.basename(h) for h in files.hal_files if h.lower().endswith(".tcl")]
    tcl = (
        f"; Tcl HAL files ({', '.join(tcl_files)}) are read for their literal commands only"
        if tcl_files
        else ""
    )
    return (
        f"{place}: no step generator: the HAL files ({hals}) load no {what}"
        f" (they load: {', '.join(loaded) or 'nothing'}){missing}{tcl}"
    )


_Fix = Callable[[GeneratorGuarantee, FixRole, Fraction], str]


def _fixer(hw: set[int], hard: _Fix, soft: _Fix) -> _Fix:
    def fix(axis: GeneratorGuarantee, role: FixRole, need: Fraction) -> str:
        return hard(axis, role, need) if id(axis) in hw else soft(axis, role, need)

    return fix
