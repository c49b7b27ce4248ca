"""The files of a LinuxCNC configuration, read as the ``linuxcnc`` script reads them: the INI
(continuations and ``#INCLUDE`` followed, :func:`~wavecheck.linuxcnc.files.read_ini`), every
``[HAL] HALFILE`` and ``POSTGUI_HALFILE`` (beside the INI, else in LinuxCNC's HAL library;
``LIB:name`` only there; ``.tcl`` files read for their literal HAL commands) and every
``HALCMD``; or one HAL file, read with the INI given beside it (``wavecheck config HAL INI``) or
else the INI beside it whose ``HALFILE`` names it (LinuxCNC runs a HAL file only from its INI), or
alone when no INI names it. An INI given whose ``HALFILE`` does not name the HAL file only
supplies its ``[SECTION]KEY`` values, as ``halcmd -i INI -f HAL`` does.

LinuxCNC's HAL library is looked for in ``$HALLIB_DIR``, in the ``lib/hallib`` folder of a
LinuxCNC tree the INI sits in (``…/configs/…`` beside ``…/lib/hallib``, as a run-in-place build
has it) and in the installed ``/usr/share/linuxcnc/hallib``. A HALFILE found nowhere is named,
with the consequence, in :attr:`LinuxCNCFiles.not_read`.

:class:`LinuxCNCFiles` also answers what the HAL commands say: which modules are loaded, the
``setp`` values, which pins share a signal, which function runs in which thread and which joint
(and axis letter) commands a step generator. The software-stepgen and hm2 readers of
:mod:`wavecheck.firmware` decide from it.
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path

from wavecheck.config_text import is_file, read_text
from wavecheck.errors import ConfigError
from wavecheck.linuxcnc.files import (
    HalLine,
    IniFile,
    hal_lines,
    hal_words,
    ini_value,
    read_ini,
)

__all__ = ["LinuxCNCFiles", "expand_refs", "hallib_dirs", "is_ini", "scan"]

_INLINE = re.compile(r"\[([^\]]+)\]\(([^)]+)\)")
_INSTALLED_HALLIB = Path("/usr/share/linuxcnc/hallib")
_MAX_HAL_FILES = 64
_MAX_INIS = 64  # INIs beside a HAL file given alone that are read to find the one naming it


def is_ini(text: str) -> bool:
    """True for an INI file (section headers and ``KEY = VALUE`` lines, no HAL commands)."""
    return bool(
        re.search(r"^[ \t]*(\[[A-Za-z_0-9]+\]|#INCLUDE[ \t])", text, re.M)
    ) and not re.search(r"^[ \t]*(loadrt|setp|net|addf)[ \t]", text, re.M)


def expand_refs(text: str, ini: IniFile | None) -> str:
    """``hm2_[HOSTMOT2](BOARD).0`` → ``hm2_5i20.0`` (LinuxCNC's inline INI substitution);
    references the INI does not hold are left as written."""
    if ini is None:
        return text

    def sub(m: re.Match[str]) -> str:
        found = ini.get(m.group(1), m.group(2))
        return found[0].strip('"') if found else m.group(0)

    return _INLINE.sub(sub, text)


def hallib_dirs(ini_path: Path) -> list[Path]:
    """LinuxCNC's HAL library folders for a configuration at ``ini_path``, existing ones only."""
    found: list[Path] = []
    env = os.environ.get("HALLIB_DIR")
    if env:
        found.append(Path(env))
    for parent in ini_path.resolve().parents:
        if parent.name == "configs" and (parent.parent / "lib" / "hallib").is_dir():
            found.append(parent.parent / "lib" / "hallib")
            break
    found.append(_INSTALLED_HALLIB)
    return [d for d in dict.fromkeys(found) if d.is_dir()]


@dataclass
class LinuxCNCFiles:
    """A LinuxCNC configuration read (see the module doc).

    Attributes:
        path: the file given (an INI or a HAL file).
        ini: the INI, None for a HAL file given alone.
        hal_files: the HAL and Tcl files read, in order.
        lines: every HAL command, INI references not yet substituted.
        not_read: HALFILEs not found, one line each with the consequence.
        computed: Tcl commands whose words are computed (not evaluated).
    """

    path: str
    ini: IniFile | None
    hal_files: list[str] = field(default_factory=list)
    lines: list[HalLine] = field(default_factory=list)
    not_read: list[str] = field(default_factory=list)
    computed: list[str] = field(default_factory=list)
    found_ini: str = ""
    """The INI a HAL file is read with (found beside it, or given)."""
    ini_note: str = ""
    """How the HAL file was read with :attr:`found_ini` (a note for the report)."""

    def words(self, line: HalLine) -> list[str]:
        """A command's words, inline ``[SECTION](KEY)`` references substituted."""
        return hal_words(expand_refs(line.text, self.ini))

    @cached_property
    def loads(self) -> list[tuple[str, str]]:
        """(module, ``file:line``) of every ``loadrt``, INI references resolved."""
        out = []
        for line in self.lines:
            w = self.words(line)
            if len(w) > 1 and w[0] == "loadrt":
                module = ini_value(w[1], self.ini).split()
                out.append((module[0] if module else w[1], line.where))
        return out

    @cached_property
    def setp(self) -> dict[str, tuple[str, str]]:
        """Parameter or pin → (its last ``setp`` value as written, ``file:line``)."""
        out: dict[str, tuple[str, str]] = {}
        for line in self.lines:
            w = self.words(line)
            if len(w) >= 3 and w[0] == "setp":
                out[w[1]] = (w[2], line.where)
            elif len(w) >= 3 and w[1] == "=":
                out[w[0]] = (w[2], line.where)
        return out

    @cached_property
    def signal_of(self) -> dict[str, str]:
        """Pin → the signal it is on (``net``, ``linksp``, ``linkps``)."""
        out: dict[str, str] = {}
        for line in self.lines:
            w = self.words(line)
            if len(w) >= 3 and w[0] == "net":
                for pin in w[2:]:
                    if pin not in ("=>", "<=", "<=>"):
                        out[pin] = w[1]
            elif len(w) >= 3 and w[0] == "linksp":
                out[w[2]] = w[1]
            elif len(w) >= 3 and w[0] == "linkps":
                out[w[1]] = w[2]
        return out

    def on_signal(self, pin: str) -> list[str]:
        """The other pins on ``pin``'s signal."""
        sig = self.signal_of.get(pin)
        return [p for p, s in self.signal_of.items() if s == sig and p != pin] if sig else []

    @cached_property
    def thread_of(self) -> dict[str, str]:
        """HAL function → the thread it is added to (``addf``)."""
        out: dict[str, str] = {}
        for line in self.lines:
            w = self.words(line)
            if len(w) >= 3 and w[0] == "addf":
                out[w[1]] = w[2]
        return out

    def ini_setting(self, section: str, key: str) -> tuple[str, str] | None:
        """(value, ``file:line``) of an INI setting, None without it."""
        if self.ini is None or self.ini.get(section, key) is None:
            return None
        value = self.ini.get(section, key)
        assert value is not None
        return value[0], self.ini.place(section, key)

    def joint_of(self, gen: str) -> tuple[int | None, str]:
        """(the joint whose command drives ``gen``, that joint's axis letter or "")."""
        joint = None
        for pin in (f"{gen}.position-cmd", f"{gen}.velocity-cmd"):
            for other in self.on_signal(pin):
                m = re.fullmatch(
                    r"joint\.(\d{1,3})\.motor-pos-cmd|axis\.(\d{1,3})\.motor-pos-cmd", other
                )
                if m:
                    joint = int(m.group(1) or m.group(2))
        if joint is None:
            return None, ""
        return joint, self._letter(joint)

    def _letter(self, joint: int) -> str:
        kins = self.ini_setting("KINS", "KINEMATICS")
        coords = ""
        if kins:
            m = re.search(r"coordinates=(\w+)", kins[0])
            coords = m.group(1) if m else ""
        if not coords:
            traj = self.ini_setting("TRAJ", "COORDINATES")
            coords = "".join(traj[0].split()) if traj else ""
        return coords[joint].lower() if joint < len(coords) else ""


def scan(
    path: str | os.PathLike[str], given: str | os.PathLike[str] | None = None
) -> LinuxCNCFiles:
    """Read the configuration at ``path`` (an INI, or one HAL/Tcl file; with ``given``, a HAL
    file and its INI in either order)."""
    p = Path(path)
    text = read_text(p)
    if given is not None:
        return _with_ini(p, text, Path(given))
    if not is_ini(text):
        ini_path = _ini_naming(p)
        if ini_path is not None:
            files = scan(ini_path)
            files.path = str(p)
            files.found_ini = str(ini_path)
            files.ini_note = (f"a HAL file given alone: read with {ini_path}, whose [HAL] "
                              "HALFILE names it")  # fmt: skip
            return files
        files = LinuxCNCFiles(str(p), None)
        _add(files, p)
        return files
    ini = read_ini(p)
    files = LinuxCNCFiles(str(p), ini)
    libs = hallib_dirs(p)
    for key in ("HALFILE", "POSTGUI_HALFILE"):
        for index, (value, _) in enumerate(ini.sections.get("HAL", {}).get(key, [])):
            name = value.split()[0] if value.split() else ""
            if not name:
                continue
            at = ini.place("HAL", key, index)
            found = _find(p.parent, name, libs)
            if found is None:
                where_looked = "LinuxCNC's HAL library" if name.startswith("LIB:") else (
                    "beside the INI or in LinuxCNC's HAL library"
                )  # fmt: skip
                files.not_read.append(
                    f"{at}: {key} {name} is not {where_looked} "
                    f"({', '.join(map(str, libs)) or 'no HAL library found'}); its commands are "
                    "not read"
                )
                continue
            _add(files, found)
    for index, (value, _) in enumerate(ini.sections.get("HAL", {}).get("HALCMD", [])):
        files.lines.append(HalLine(value, ini.place("HAL", "HALCMD", index)))
    return files


def _with_ini(first: Path, first_text: str, second: Path) -> LinuxCNCFiles:
    """A HAL file and the INI given with it (either order): the whole configuration when the
    INI's ``HALFILE`` runs the HAL file, else the HAL file alone with the INI's values."""
    second_is_ini = is_ini(read_text(second))
    if is_ini(first_text) == second_is_ini:
        kind = "INIs" if second_is_ini else "HAL files"
        raise ConfigError(
            f"{first} and {second}: two {kind}; give one HAL file and the INI that runs it "
            "(wavecheck config HAL INI)"
        )
    hal, ini_path = (first, second) if second_is_ini else (second, first)
    ini = read_ini(ini_path)
    if _resolved(hal) in _named_hal_files(ini, ini_path):
        files = scan(ini_path)
        files.path = str(hal)
        files.found_ini = str(ini_path)
        files.ini_note = f"{hal.name} read with the INI given, {ini_path}, whose HALFILE runs it"
        return files
    files = LinuxCNCFiles(str(hal), ini)
    files.found_ini = str(ini_path)
    files.ini_note = (
        f"{hal.name} read alone with the INI given, {ini_path}, for its [SECTION]KEY values "
        "(as halcmd -i INI -f HAL): that INI's HALFILEs do not name it, so they are not read"
    )
    _add(files, hal)
    return files


def _named_hal_files(ini: IniFile, ini_path: Path) -> set[Path]:
    """The files the INI's ``HALFILE``/``POSTGUI_HALFILE`` name beside it, resolved."""
    out = set()
    for key in ("HALFILE", "POSTGUI_HALFILE"):
        for value, _ in ini.sections.get("HAL", {}).get(key, []):
            named = _resolved(ini_path.parent / value.split()[0]) if value.split() else None
            if named is not None:
                out.add(named)
    return out


def _ini_naming(hal: Path) -> Path | None:
    """The INI beside ``hal`` whose ``[HAL] HALFILE`` names it (LinuxCNC runs a HAL file from
    its INI), None when no INI names it.

    Raises:
        ConfigError: several INIs name it (each may set other values: the user chooses).
    """
    found = []
    for ini_path in sorted(hal.parent.glob("*.ini"))[:_MAX_INIS]:
        try:
            if not is_file(ini_path) or not is_ini(read_text(ini_path)):
                continue
            ini = read_ini(ini_path)
        except ConfigError:
            continue
        if _resolved(hal) in _named_hal_files(ini, ini_path):
            found.append(ini_path)
    if len(found) > 1:
        raise ConfigError(
            f"{hal}: a HAL file given alone, and {len(found)} INIs beside it name it as a "
            f"HALFILE ({', '.join(f.name for f in found[:5])}): give the INI to read as a "
            f"second file (wavecheck config {hal.name} {found[0].name} …)"
        )
    return found[0] if found else None


def _resolved(path: Path) -> Path | None:
    try:
        return path.resolve()
    except OSError:
        return None


def _find(folder: Path, name: str, libs: list[Path]) -> Path | None:
    if name.startswith("LIB:"):
        candidates = [d / name[4:] for d in libs]
    elif Path(name).is_absolute():
        candidates = [Path(name)]
    else:
        candidates = [folder / name, *(d / name for d in libs)]
    return next((c for c in candidates if is_file(c)), None)


def _add(files: LinuxCNCFiles, hal: Path) -> None:
    if len(files.hal_files) >= _MAX_HAL_FILES:
        raise ConfigError(f"{files.path}: more than {_MAX_HAL_FILES} HAL files")
    lines, computed = hal_lines(hal)
    files.hal_files.append(str(hal))
    files.lines += lines
    files.computed += computed
