"""Step-generator settings of motion firmware: what each configuration guarantees on the wire.

:func:`read_firmware` detects the format by content (or takes ``fmt``) and returns one
:class:`~wavecheck.firmware.model.FirmwareConfig` with a
:class:`~wavecheck.firmware.model.GeneratorGuarantee` per axis. :mod:`.evaluate` compares a
guarantee with a drive (``wavecheck config``); :mod:`.capture` compares it with a checked capture
(``wavecheck check --firmware``).
"""

from __future__ import annotations

import os
from fractions import Fraction
from pathlib import Path

from wavecheck.errors import ConfigError
from wavecheck.firmware._text import read_text
from wavecheck.firmware.model import FIRMWARES, FirmwareConfig, GeneratorGuarantee, Guaranteed

__all__ = [
    "FIRMWARES",
    "FirmwareConfig",
    "GeneratorGuarantee",
    "Guaranteed",
    "detect",
    "read_firmware",
]


def detect(path: str | os.PathLike[str]) -> str:
    """The firmware of ``path`` by its content (a Marlin folder counts as Marlin).

    Raises:
        ConfigError: no format recognised (the hint names ``--firmware-format``).
    """
    # the readers are imported when a configuration is read, not at start-up
    from wavecheck.firmware import grbl, hm2, klipper, linuxcnc, marlin, rrf, smoothie

    detectors = (
        ("grbl", grbl.looks_like),
        ("marlin", marlin.looks_like),
        ("klipper", klipper.looks_like),
        ("reprapfirmware", rrf.looks_like),
        ("smoothieware", smoothie.looks_like),
        ("hm2", hm2.looks_like),
        ("linuxcnc", linuxcnc.looks_like),
    )
    p = Path(path)
    if p.is_dir():
        if (p / "Configuration.h").is_file():
            return "marlin"
        raise ConfigError(f"{path}: a folder without Configuration.h; give a configuration file")
    text = read_text(p)
    if p.suffix.lower() == ".ini" and hm2.looks_like(text):
        return "hm2" if "[HOSTMOT2]" in text else "linuxcnc"
    for name, looks in detectors:
        if looks(text):
            if name == "hm2" and p.suffix.lower() == ".ini" and "[HOSTMOT2]" not in text:
                continue
            return name
    raise ConfigError(
        f"{path}: not a configuration wavecheck recognises ({', '.join(FIRMWARES)}); "
        "give --firmware-format NAME if it is one of them"
    )


def read_firmware(
    path: str | os.PathLike[str],
    fmt: str | None = None,
    *,
    latency_ns: Fraction | None = None,
    clock_hz: Fraction | None = None,
) -> FirmwareConfig:
    """Read ``path`` as ``fmt`` (default: detected). ``latency_ns`` is LinuxCNC's J,
    ``clock_hz`` the hm2 stepgen clock."""
    from wavecheck.firmware import grbl, hm2, klipper, linuxcnc, marlin, rrf, smoothie

    name = fmt or detect(path)
    if name not in FIRMWARES:
        raise ConfigError(f"unknown firmware format {name!r} (one of {', '.join(FIRMWARES)})")
    if name == "grbl":
        return grbl.read(path)
    if name == "klipper":
        return klipper.read(path)
    if name == "marlin":
        return marlin.read(path)
    if name == "reprapfirmware":
        return rrf.read(path)
    if name == "smoothieware":
        return smoothie.read(path)
    if name == "hm2":
        return hm2.read(path, clock_hz)
    return linuxcnc.read(path, latency_ns)
