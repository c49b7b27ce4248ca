"""The files of a LinuxCNC configuration: an INI and the HAL files its ``[HAL] HALFILE`` names
(or one HAL file given alone). Shared by the hm2 and software-stepgen readers."""

from __future__ import annotations

import os
import re
from pathlib import Path

from wavecheck.linuxcnc.files import IniFile, read_ini

__all__ = ["expand_refs", "files_of", "is_ini"]

_INLINE = re.compile(r"\[([^\]]+)\]\(([^)]+)\)")


def is_ini(text: str) -> bool:
    """True for an INI file (section headers and ``KEY = VALUE`` lines, no HAL commands)."""
    return bool(re.search(r"^\s*\[[A-Z_0-9]+\]\s*$", text, re.M)) and not re.search(
        r"^\s*(loadrt|setp|net|addf)\s", text, re.M
    )


def files_of(
    path: str | os.PathLike[str], text: str
) -> tuple[IniFile | None, list[Path], list[str]]:
    """(INI or None, HAL files, notes) for ``path`` (an INI or a HAL file)."""
    if not is_ini(text):
        return None, [Path(path)], []
    ini = read_ini(path)
    hals: list[Path] = []
    notes: list[str] = []
    for value, line in ini.sections.get("HAL", {}).get("HALFILE", []):
        hal = Path(path).parent / value
        if hal.is_file():
            hals.append(hal)
        else:
            notes.append(f"{path}:{line}: HALFILE {value} not found beside the INI; not read")
    return ini, hals, notes


def expand_refs(text: str, ini: IniFile | None) -> str:
    """``hm2_[HOSTMOT2](BOARD).0`` → ``hm2_5i20.0`` (LinuxCNC's inline INI substitution);
    references the INI does not hold are left as written."""
    if ini is None:
        return text

    def sub(m: re.Match[str]) -> str:
        found = ini.get(m.group(1), m.group(2))
        return found[0].strip('"') if found else m.group(0)

    return _INLINE.sub(sub, text)
