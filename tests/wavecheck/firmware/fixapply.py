"""Apply a fix that ``wavecheck config`` prints, mechanically, to a copy of the configuration
(issue 32, class 5): each firmware's fix sentences name one setting and its value; this module
reads them back and writes that value where the firmware reads it. A sentence it cannot read is
an advice that is no edit (grbl cannot delay DIR from ``$$``): :data:`ADVICE` lists them."""

from __future__ import annotations

import re
import shutil
from pathlib import Path

from wavecheck.firmware.guarantee import FirmwareConfig

#: Fix sentences that advise rather than edit (a build option, not a setting of the file).
ADVICE = re.compile(
    r"grbl cannot delay DIR|Grbl_ESP32's direction delay|Smoothieware has no DIR|tops out"
    r"|FluidNC may change DIR|raise BASE_PERIOD"
)


class NotAnEdit(ValueError):
    """The fix sentence names no setting this module can write."""


def copy_case(cfg: FirmwareConfig, corpus: Path, dest: Path) -> Path:
    """The folder of ``cfg``'s main file copied under ``dest`` at its place in ``corpus`` (a
    LinuxCNC case keeps LinuxCNC's ``lib/hallib`` beside its ``configs``); the main file's copy."""
    main = Path(cfg.path).resolve()
    rel = main.parent.relative_to(corpus.resolve())
    shutil.copytree(main.parent, dest / rel, dirs_exist_ok=True)
    for f in cfg.files:  # files read from elsewhere in the corpus (LinuxCNC's HAL library)
        p = Path(f).resolve()
        if p.is_relative_to(corpus.resolve()) and p.parent != main.parent:
            target = dest / p.relative_to(corpus.resolve())
            target.parent.mkdir(parents=True, exist_ok=True)
            shutil.copy(p, target)
    return dest / rel / main.name


def apply(firmware: str, path: Path, fix: str, cfg: FirmwareConfig) -> None:
    """Write ``fix`` into the copy at ``path`` (raises :class:`NotAnEdit`)."""
    handler = {
        "klipper": _klipper,
        "grbl": _grbl,
        "smoothieware": _smoothie,
        "fluidnc": _fluidnc,
        "marlin": _marlin,
        "reprapfirmware": _rrf,
        "linuxcnc": _hal,
        "hm2": _hal,
    }[firmware]
    handler(path, fix, cfg)


def _klipper(path: Path, fix: str, cfg: FirmwareConfig) -> None:
    sets = re.findall(r"`(\w+): (\S+)` in \[(.+?)\]", fix)
    for key, value, section in sets:
        _ini_set(path, section, key, value)
    m = re.search(r"invert step_pin in \[(.+?)\]", fix)
    if m:
        lines = path.read_text().splitlines()
        section = False
        for i, line in enumerate(lines):
            if line.startswith("["):
                section = line.strip() == f"[{m.group(1)}]"
            elif section and re.match(r"step_pin\s*[:=]", line):
                key, _, value = line.partition(":")
                v = value.strip()
                v = v[1:] if v.startswith("!") else "!" + v
                lines[i] = f"{key}: {v}"
        path.write_text("\n".join(lines) + "\n")
    elif not sets:
        raise NotAnEdit(fix)


def _ini_set(path: Path, section: str, key: str, value: str) -> None:
    """Set ``key: value`` in ``[section]`` of a Klipper file (added after the header)."""
    lines = path.read_text().splitlines()
    out: list[str] = []
    inside = done = False
    for line in lines:
        if line.startswith("["):
            inside = " ".join(line.strip()[1:].split("]")[0].split()) == section
            out.append(line)
            if inside and not done:
                out.append(f"{key}: {value}")
                done = True
            continue
        if inside and re.match(rf"{key}\s*[:=]", line):
            continue
        out.append(line)
    if not done:
        raise NotAnEdit(f"no [{section}] in {path}")
    path.write_text("\n".join(out) + "\n")


def _grbl(path: Path, fix: str, cfg: FirmwareConfig) -> None:
    found = re.findall(r"`\$(\d+)=([\d.]+)`", fix)
    if not found:
        raise NotAnEdit(fix)
    text = path.read_text()
    for n, value in found:
        text, count = re.subn(
            rf"(?m)^([ \t]*\${n}[ \t]*=[ \t]*)[^\s(]+", rf"\g<1>{value}", text, count=1
        )
        if not count:
            text = f"${n}={value}\n" + text
    path.write_text(text)


def _smoothie(path: Path, fix: str, cfg: FirmwareConfig) -> None:
    m = re.search(r"set `(\S+) (\S+)`", fix)
    if not m:
        raise NotAnEdit(fix)
    with path.open("a") as fh:  # a key given again replaces the earlier value
        fh.write(f"\n{m.group(1)} {m.group(2)}\n")


def _fluidnc(path: Path, fix: str, cfg: FirmwareConfig) -> None:
    m = re.search(r"`(\w+): (\w+): (\S+)`", fix)
    if not m:
        raise NotAnEdit(fix)
    section, key, value = m.groups()
    lines = path.read_text().splitlines()
    indent_of = None
    for i, line in enumerate(lines):
        stripped = line.strip()
        if indent_of is None and stripped.rstrip(":") == section and stripped.endswith(":"):
            indent_of = len(line) - len(line.lstrip())
            lines.insert(i + 1, " " * (indent_of + 2) + f"{key}: {value}")
            break
    if indent_of is None:
        raise NotAnEdit(f"no section {section}: in {path}")
    # drop later copies of the key in that section (a repeated key keeps the last)
    out, inside = [], False
    for j, line in enumerate(lines):
        if j == i:
            inside = True
        elif inside and line.strip() and len(line) - len(line.lstrip()) <= indent_of:
            inside = False
        if (
            inside
            and j > i + 1
            and line.strip().startswith(f"{key}:")
            and (len(line) - len(line.lstrip()) == indent_of + 2)
        ):
            continue
        out.append(line)
    path.write_text("\n".join(out) + "\n")


def _marlin(path: Path, fix: str, cfg: FirmwareConfig) -> None:
    found = re.findall(r"define (\w+) (\w+)", fix)
    if not found:
        raise NotAnEdit(fix)
    adv = path.parent / "Configuration_adv.h"
    target = adv if adv.is_file() else path
    with target.open("a") as fh:
        for name, value in found:
            fh.write(f"\n#undef {name}\n#define {name} {value}\n")


def _rrf(path: Path, fix: str, cfg: FirmwareConfig) -> None:
    lines = re.findall(r"`(M\d+ [^`]+)`", fix)
    if not lines:
        raise NotAnEdit(fix)
    with path.open("a") as fh:
        fh.write("\n" + "\n".join(lines) + "\n")


def _hal(path: Path, fix: str, cfg: FirmwareConfig) -> None:
    found = re.findall(r"`(setp \S+ \S+)`", fix)
    if not found:
        raise NotAnEdit(fix)
    hal = [Path(f).resolve() for f in cfg.files if f.endswith(".hal")]
    if not hal:
        raise NotAnEdit(f"no HAL file in {cfg.files}")
    # the copy of the last HAL file read (a later setp wins)
    main = Path(cfg.path).resolve()
    copied = (
        path.parent / hal[-1].relative_to(main.parent)
        if hal[-1].is_relative_to(main.parent)
        else None
    )
    if copied is None or not copied.is_file():
        raise NotAnEdit(f"{hal[-1]} is not beside the configuration")
    with copied.open("a") as fh:
        fh.write("\n" + "\n".join(found) + "\n")
