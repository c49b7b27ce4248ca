"""LinuxCNC's own file syntax: INI files, HAL command words and halcmd's ``[SECTION]KEY``
substitutions. Every value keeps the file and line it came from; errors name them."""

from __future__ import annotations

import os
import re
import shlex
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

from wavecheck.config_text import is_file, read_text
from wavecheck.errors import ConfigError, UnitError
from wavecheck.units import exact_number, shown

__all__ = [
    "HAL_COMMANDS",
    "INI_REF",
    "HalLine",
    "IniFile",
    "hal_lines",
    "hal_words",
    "ini_value",
    "int_ns",
    "loadrt_args",
    "logical_lines",
    "read_ini",
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
    ignored: list[str] = field(default_factory=list)
    """Lines LinuxCNC ignores (neither a section, a comment nor ``KEY = VALUE``)."""
    section: str | None = None
    """The section being read (while reading)."""
    origins: dict[tuple[str, str], list[str]] = field(default_factory=dict)
    """(section, key) → the file of each value (an ``#INCLUDE``d file or the INI)."""

    def get(self, section: str, key: str) -> tuple[str, int] | None:
        """The first value of ``[section] key`` and its line, or None."""
        values = self.sections.get(section, {}).get(key)
        return values[0] if values else None

    def place(self, section: str, key: str, index: int = 0) -> str:
        """``file:line`` of a value (the included file's own name and line)."""
        value = self.sections[section][key][index]
        files = self.origins.get((section, key), [])
        return f"{files[index] if index < len(files) else self.path}:{value[1]}"


def logical_lines(text: str) -> Iterator[tuple[int, str]]:
    """(first line number, text) of each line with its ``\\`` continuations joined by one space
    (LinuxCNC's INI and HAL files continue a line so), stripped; linear in the text."""
    parts: list[str] = []
    first = 1
    for no, raw in enumerate(text.splitlines(), 1):
        if not parts:
            first = no
        line = raw.strip()
        if line.endswith("\\"):
            parts.append(line[:-1].strip())
            continue
        parts.append(line)
        yield first, " ".join(p for p in parts if p)
        parts = []
    if parts:
        yield first, " ".join(p for p in parts if p)


#: ``#INCLUDE`` nesting LinuxCNC's INI files may use (a loop is refused).
_MAX_INCLUDE_DEPTH = 8


def read_ini(path: str | os.PathLike[str]) -> IniFile:
    """Read a LinuxCNC INI file as the ``linuxcnc`` script does: ``#``/``;`` comment lines,
    ``[SECTION]`` headers, ``KEY = VALUE`` lines, values continued on the next line with a
    trailing ``\\``, and ``#INCLUDE file`` lines (relative to the including file; nested up to
    8 deep). A line that is none of these is ignored, as LinuxCNC's INI reader ignores it, and
    listed in :attr:`IniFile.ignored`.

    Raises:
        ConfigError: a file cannot be read, an ``#INCLUDE`` is missing or loops, or a
            ``KEY = VALUE`` line comes before any ``[SECTION]``.
    """
    ini = IniFile(str(path))
    _read_ini_into(Path(path), ini, [])
    return ini


def _read_ini_into(path: Path, ini: IniFile, stack: list[Path]) -> None:
    if len(stack) >= _MAX_INCLUDE_DEPTH or path.resolve() in stack:
        raise ConfigError(f"{stack[-1] if stack else path}: #INCLUDE {path.name} loops or nests "
                          f"more than {_MAX_INCLUDE_DEPTH} deep")  # fmt: skip
    text = read_text(path)
    stack = [*stack, path.resolve()]
    for first, line in logical_lines(text):
        if line.startswith("#INCLUDE"):
            name = line[len("#INCLUDE") :].strip()
            target = path.parent / name
            if not name or not is_file(target):
                raise ConfigError(f"{path}:{first}: #INCLUDE {name}: no such file beside it")
            _read_ini_into(target, ini, stack)
            continue
        if not line or line[0] in "#;":
            continue
        if line.startswith("[") and "]" in line:
            ini.section = line[1 : line.index("]")].strip()
            ini.sections.setdefault(ini.section, {})
            continue
        if "=" not in line:
            ini.ignored.append(f"{path}:{first}: {line[:60]!r} is not KEY = VALUE (ignored)")
            continue
        if ini.section is None:
            raise ConfigError(f"{path}: line {first}: {line[:60]!r} comes before any [SECTION]")
        key, value = (x.strip() for x in line.split("=", 1))
        ini.sections[ini.section].setdefault(key, []).append((value, first))
        ini.origins.setdefault((ini.section, key), []).append(str(path))


def int_ns(value: str, where: str, what: str) -> int:
    """A whole u32 number of ns written as LinuxCNC writes it (bare ns)."""
    try:
        number = exact_number(value)
    except UnitError as err:
        raise ConfigError(f"{where}: {what} {err}") from None
    if number.denominator != 1 or number < 0 or number > 2**32 - 1:
        raise ConfigError(f"{where}: {what} {shown(value)} is not a whole u32 number of ns")
    return int(number)


def resolve_ref(value: str, ini: IniFile | None, where: str) -> str:
    """``value``, or the INI value it names (``[SECTION]KEY``, ``[SECTION](KEY)``)."""
    m = INI_REF.match(value)
    if not m:
        return value
    if ini is None:
        raise ConfigError(
            f"{where}: {value} refers to an INI file and none was read: give the INI whose "
            "[HAL] HALFILE runs this file"
        )
    found = ini.get(m.group(1), m.group(2) or m.group(3))
    if found is None:
        raise ConfigError(f"{where}: {value} is not in {ini.path}")
    return found[0]


def ini_value(word: str, ini: IniFile | None) -> str:
    """``word``, or the INI value it names when the INI has it (lenient: a word that only looks
    like a reference stays as written)."""
    m = INI_REF.match(word)
    found = ini.get(m.group(1), m.group(2) or m.group(3)) if m and ini is not None else None
    return found[0] if found else word


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


@dataclass(frozen=True)
class HalLine:
    """One HAL command as halcmd reads it: comments removed, ``\\`` continuations joined.

    Attributes:
        text: the command (``setp stepgen.0.steplen 5000``).
        where: ``file:line`` of its first line.
    """

    text: str
    where: str


#: The commands of HAL files (halcmd's, which haltcl also has).
HAL_COMMANDS = frozenset(
    "loadrt loadusr setp sets net addf linksp linkps linkpp newsig unlinkp alias".split()
)
_TCL_INI = re.compile(r"\$::(\w+)\((\w+)\)")


def hal_lines(path: str | os.PathLike[str]) -> tuple[list[HalLine], list[str]]:
    """The HAL commands of a ``.hal`` file, or the literal ones of a Tcl HAL file (``.tcl``,
    run by haltcl), and the places of Tcl commands whose words are computed (``loadrt $name``,
    ``[…]``): those are not evaluated.

    In a Tcl file ``$::SECTION(KEY)`` is the INI value, read as halcmd's ``[SECTION](KEY)``.
    """
    text = read_text(path)
    tcl = str(path).lower().endswith(".tcl")
    out: list[HalLine] = []
    computed: list[str] = []
    for first, raw in logical_lines(text):
        line = (raw.split(";#", 1)[0] if tcl else raw).split("#", 1)[0].strip()
        if not line:
            continue
        where = f"{path}:{first}"
        if tcl:
            head = line.split(None, 1)[0]
            if head not in HAL_COMMANDS:
                continue
            if "[" in line or "{" in line or "$" in _TCL_INI.sub("", line):
                computed.append(f"{where}: {line[:60]}")
                continue
            line = _TCL_INI.sub(r"[\1](\2)", line)
        out.append(HalLine(line, where))
    return out, computed
