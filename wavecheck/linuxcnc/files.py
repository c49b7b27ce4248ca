"""LinuxCNC's own file syntax: INI files, HAL command words and halcmd's ``[SECTION]KEY``
substitutions. Every value keeps the file and line it came from; errors name them."""

from __future__ import annotations

import os
import re
import shlex
from dataclasses import dataclass, field
from fractions import Fraction
from pathlib import Path

from wavecheck.errors import ConfigError

__all__ = [
    "INI_REF",
    "IniFile",
    "hal_words",
    "int_ns",
    "loadrt_args",
    "read_ini",
    "read_text",
    "resolve_ref",
]

#: halcmd's INI substitutions: ``[SECTION]KEY`` and ``[SECTION](KEY)`` (the form that can sit
#: inside a longer word).
INI_REF = re.compile(r"^\[([^\]]+)\](?:\(([^()\s]+)\)|([^()\s]+))$")


@dataclass
class IniFile:
    """A LinuxCNC INI file: section → key → every (value, line) in file order.

    LinuxCNC allows a key more than once (``HALFILE``); :meth:`get` returns the first, as
    LinuxCNC's ``ini.find`` does.
    """

    path: str
    sections: dict[str, dict[str, list[tuple[str, int]]]] = field(default_factory=dict)

    def get(self, section: str, key: str) -> tuple[str, int] | None:
        """The first value of ``[section] key`` and its line, or None."""
        values = self.sections.get(section, {}).get(key)
        return values[0] if values else None


def read_ini(path: str | os.PathLike[str]) -> IniFile:
    """Read a LinuxCNC INI file (``#``/``;`` comment lines, ``KEY = VALUE`` lines).

    Raises:
        ConfigError: the file cannot be read or a line is neither a section nor ``KEY = VALUE``.
    """
    text = read_text(path)
    ini = IniFile(str(path))
    section: str | None = None
    for no, raw in enumerate(text.splitlines(), 1):
        line = raw.strip()
        if not line or line[0] in "#;":
            continue
        if line.startswith("["):
            if not line.endswith("]"):
                raise ConfigError(
                    f"{path}: line {no}: bad section header {line!r} (expected [NAME])"
                )
            section = line[1:-1].strip()
            ini.sections.setdefault(section, {})
            continue
        if "=" not in line:
            raise ConfigError(f"{path}: line {no}: {line!r} is not KEY = VALUE")
        if section is None:
            raise ConfigError(f"{path}: line {no}: {line!r} comes before any [SECTION]")
        key, value = (s.strip() for s in line.split("=", 1))
        ini.sections[section].setdefault(key, []).append((value, no))
    return ini


def read_text(path: str | os.PathLike[str]) -> str:
    try:
        return Path(path).read_text(encoding="utf-8", errors="replace")
    except OSError as err:
        raise ConfigError(f"{path}: cannot read: {err.strerror or err}") from None


def int_ns(value: str, where: str, what: str) -> int:
    """A whole u32 number of ns written as LinuxCNC writes it (bare ns)."""
    try:
        number = Fraction(value)
    except (ValueError, ZeroDivisionError):
        raise ConfigError(f"{where}: {what} {value!r} is not a number of ns") from None
    if number.denominator != 1 or number < 0 or number > 2**32 - 1:
        raise ConfigError(f"{where}: {what} {value!r} is not a whole u32 number of ns")
    return int(number)


def resolve_ref(value: str, ini: IniFile | None, where: str) -> str:
    """``value``, or the INI value it names (``[SECTION]KEY``, ``[SECTION](KEY)``)."""
    m = INI_REF.match(value)
    if not m:
        return value
    if ini is None:
        raise ConfigError(f"{where}: {value} refers to the INI file (give --ini FILE)")
    found = ini.get(m.group(1), m.group(2) or m.group(3))
    if found is None:
        raise ConfigError(f"{where}: {value} is not in {ini.path}")
    return found[0]


def hal_words(line: str) -> list[str]:
    """A HAL command's words (``"quoted words"`` kept together)."""
    try:
        return shlex.split(line, posix=True)
    except ValueError:
        return line.split()


def loadrt_args(words: list[str], ini: IniFile | None, where: str) -> dict[str, str]:
    """``key=value`` arguments of a ``loadrt`` line, INI references resolved."""
    out: dict[str, str] = {}
    for arg in words:
        if "=" in arg:
            key, value = arg.split("=", 1)
            out[key] = resolve_ref(value, ini, where)
    return out
