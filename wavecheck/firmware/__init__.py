"""Step-generator settings of motion firmware: what each configuration guarantees on the wire.

:func:`read_firmware` detects the format by content (or takes ``fmt``) and returns one
:class:`~wavecheck.firmware.guarantee.FirmwareConfig` with a
:class:`~wavecheck.firmware.guarantee.GeneratorGuarantee` per axis. :mod:`.evaluate` compares a
guarantee with a drive (``wavecheck config``); :mod:`.capture` compares it with a checked capture
(``wavecheck check --firmware``); :mod:`.pairing` pairs capture axes with firmware axes.

Every file is read with a bound (:func:`~wavecheck.config_text.read_text`: devices, FIFOs
and files over 4 MiB are refused) and every number with one (:func:`._text.number`).
"""

from __future__ import annotations

import importlib
import os
from pathlib import Path
from typing import TYPE_CHECKING, Any

from wavecheck.errors import ConfigError

if TYPE_CHECKING:
    from fractions import Fraction

    from wavecheck.firmware.guarantee import FirmwareConfig, GeneratorGuarantee, Guaranteed

__all__ = [
    "FIRMWARES",
    "FirmwareConfig",
    "GeneratorGuarantee",
    "Guaranteed",
    "detect",
    "read_firmware",
]

#: Firmware names (``--firmware-format`` choices), in detection order.
FIRMWARES: tuple[str, ...] = (
    "grbl",
    "klipper",
    "marlin",
    "reprapfirmware",
    "smoothieware",
    "fluidnc",
    "hm2",
    "linuxcnc",
)

#: Reader module of each format, in detection order (LinuxCNC INIs are decided by what their
#: HAL files load, in :mod:`.linuxcnc`, so ``hm2`` and ``linuxcnc`` share one reader).
_DETECT = ("grbl", "fluidnc", "marlin", "klipper", "rrf", "smoothie", "linuxcnc")
_MODULE = {
    "grbl": "grbl",
    "klipper": "klipper",
    "marlin": "marlin",
    "reprapfirmware": "rrf",
    "smoothieware": "smoothie",
    "fluidnc": "fluidnc",
    "hm2": "linuxcnc",
    "linuxcnc": "linuxcnc",
}
_NAME = {"rrf": "reprapfirmware", "smoothie": "smoothieware"}


#: The record types, loaded with the first configuration read (``check`` without ``--firmware``
#: builds its ``--firmware-format`` choices from :data:`FIRMWARES` alone).
_RECORDS = ("FirmwareConfig", "GeneratorGuarantee", "Guaranteed")


def __getattr__(name: str) -> Any:
    if name in _RECORDS:
        return getattr(importlib.import_module("wavecheck.firmware.guarantee"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def _reader(module: str):  # type: ignore[no-untyped-def]
    # the readers are imported when a configuration is read, not at start-up
    return importlib.import_module(f"wavecheck.firmware.{module}")


def detect(path: str | os.PathLike[str]) -> str:
    """The firmware of ``path`` by its content (a Marlin folder counts as Marlin; a LinuxCNC
    INI or HAL file is ``linuxcnc``, whatever step generator it loads).

    Raises:
        ConfigError: no format recognised (the hint names ``--firmware-format``).
    """
    p = Path(path)
    if p.is_dir():
        if (p / "Configuration.h").is_file():
            return "marlin"
        raise ConfigError(f"{path}: a folder without Configuration.h; give a configuration file")
    from wavecheck.firmware._text import read_text

    text = read_text(p)
    for module in _DETECT:
        if _reader(module).looks_like(text):
            return _NAME.get(module, module)
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
    ini: str | os.PathLike[str] | None = None,
) -> FirmwareConfig:
    """Read ``path`` as ``fmt`` (default: detected). ``latency_ns`` is LinuxCNC's J,
    ``clock_hz`` the hm2 stepgen clock, ``ini`` a LinuxCNC INI given beside a HAL file."""
    name = fmt or detect(path)
    if name not in FIRMWARES:
        raise ConfigError(f"unknown firmware format {name!r} (one of {', '.join(FIRMWARES)})")
    reader = _reader(_MODULE[name])
    if _MODULE[name] == "linuxcnc":
        cfg: FirmwareConfig = reader.read(
            path, latency_ns=latency_ns, clock_hz=clock_hz, want=fmt, ini=ini
        )
    elif ini is not None:
        raise ConfigError(
            f"{ini}: a second file is read only with a LinuxCNC HAL file (its INI); "
            f"{path} is a {name} configuration"
        )
    else:
        cfg = reader.read(path)
    return cfg
