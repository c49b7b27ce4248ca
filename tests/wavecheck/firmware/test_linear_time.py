"""Every firmware reader runs in linear time (issue 32, class 8).

Format detection and the FluidNC rewrite searched ``^\\s*…`` with ``re.M``: at every line start
``\\s*`` ran over all the blank lines that follow before failing, so n blank lines cost n²/2
steps (a 104 KB FluidNC file took more than 120 s, 20 KB of newlines 35 s to be refused). The fix
is structural: no line-anchored pattern can leave its line. The first test checks that of every
``re.M`` pattern in the readers' source; the second reads 1 MB of blank lines per format (between the
first setting and the rest), which finishes only when the work is linear (the guard turns a
hang into a failure; it asserts no speed)."""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

from tests.wavecheck.firmware.bounded import bounded
from wavecheck.errors import ConfigError
from wavecheck.firmware import read_firmware

ROOT = Path(__file__).resolve().parents[3]
READERS = [*sorted((ROOT / "wavecheck/firmware").glob("*.py")), ROOT / "wavecheck/linuxcnc"]
_FLAG = {"M", "MULTILINE"}


def _multiline_patterns(path: Path) -> list[tuple[int, str]]:
    """(line, pattern) of every ``re.*(PATTERN, …, re.M)`` call in ``path``."""
    out = []
    for node in ast.walk(ast.parse(path.read_text())):
        if not (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute)):
            continue
        if not (isinstance(node.func.value, ast.Name) and node.func.value.id == "re"):
            continue
        flags = [*node.args[1:], *(k.value for k in node.keywords)]
        multiline = any(
            isinstance(sub, ast.Attribute) and sub.attr in _FLAG
            for f in flags
            for sub in ast.walk(f)
        )
        first = node.args[0] if node.args else None
        if multiline and isinstance(first, ast.Constant) and isinstance(first.value, str):
            out.append((node.lineno, first.value))
    return out


def _leaves_its_line(pattern: str) -> bool:
    """True when a part of ``pattern`` can match a newline: ``\\s`` outside ``[^\\s…]``, or a
    negated class that does not exclude the newline."""
    for cls in re.findall(r"\[\^((?:\\.|[^\]])*)\]", pattern):
        if "\\n" not in cls and "\\s" not in cls:
            return True
    return "\\s" in re.sub(r"\[\^(?:\\.|[^\]])*\]", "", pattern)


def _files() -> list[Path]:
    return [p for entry in READERS for p in ([entry] if entry.is_file() else entry.rglob("*.py"))]


@pytest.mark.parametrize("path", _files(), ids=lambda p: p.name)
def test_no_line_anchored_pattern_crosses_lines(path: Path) -> None:
    bad = [(no, pat) for no, pat in _multiline_patterns(path) if _leaves_its_line(pat)]
    assert bad == [], f"{path.name}: re.M patterns that can run over blank lines: {bad}"


def test_the_check_sees_the_old_patterns() -> None:
    """The structural check catches the patterns that were quadratic."""
    assert _leaves_its_line(r"^\s*alpha_(steps_per_mm|step_pin)\s")
    assert _leaves_its_line(r"^(\s*[A-Za-z0-9_]+)\s*:(?=[^\s])")
    assert not _leaves_its_line(r"^([ \t]*[A-Za-z0-9_]+)[ \t]*:(?=[^\s])")


BLANK = "\n" * (1 << 20)
#: (format, file name, the settings; a LinuxCNC INI also gets its HAL file).
FORMATS = [
    ("grbl", "dump.txt", "$0=10\n$100=80\n$110=500\n"),
    ("klipper", "printer.cfg",
     "[printer]\nkinematics: cartesian\nmax_velocity: 300\n[stepper_x]\nstep_pin: PA9\n"
     "dir_pin: PA10\n"),
    ("marlin", "Configuration.h",
     "#define CONFIGURATION_H_VERSION 02010300\n#define X_DRIVER_TYPE A4988\n"),
    ("smoothieware", "config", "alpha_steps_per_mm 80\nalpha_step_pin 2.0\n"),
    ("reprapfirmware", "config.g", "M584 X0 Y1 Z2\nM92 X80 Y80 Z400\nM203 X6000\n"),
    ("fluidnc", "config.yaml",
     "name: m\nstepping:\n  engine: RMT\n  pulse_us: 4\naxes:\n  x:\n    steps_per_mm: 80\n"
     "    motor0:\n      stepstick:\n        step_pin: gpio.12\n        direction_pin: gpio.14\n"),
    ("linuxcnc", "m.ini", "[EMCMOT]\nBASE_PERIOD = 50000\n[HAL]\nHALFILE = m.hal\n"),
]  # fmt: skip


@pytest.mark.parametrize(("fmt", "name", "text"), FORMATS, ids=[f[0] for f in FORMATS])
def test_a_megabyte_of_blank_lines_is_read(tmp_path: Path, fmt: str, name: str, text: str) -> None:
    first, _, rest = text.partition("\n")
    (tmp_path / name).write_text(first + "\n" + BLANK + rest)  # between the first line and the rest
    if fmt == "linuxcnc":
        (tmp_path / "m.hal").write_text(
            "loadrt stepgen step_type=0\n" + BLANK + "addf stepgen.make-pulses base-thread\n"
        )
    cfg = bounded(lambda: read_firmware(tmp_path / name))
    assert cfg.firmware == fmt and len(cfg.axes) >= 1


def test_a_megabyte_of_newlines_is_refused(tmp_path: Path) -> None:
    (tmp_path / "blank.txt").write_text(BLANK)
    with pytest.raises(ConfigError, match="not a configuration"):
        bounded(lambda: read_firmware(tmp_path / "blank.txt"))


@pytest.mark.parametrize(("fmt", "name", "text"), FORMATS, ids=[f[0] for f in FORMATS])
def test_crlf_files_are_still_recognised(tmp_path: Path, fmt: str, name: str, text: str) -> None:
    """The line-bound patterns end lines at \\r too (6x_X_Carve.yaml is a CRLF file)."""
    (tmp_path / name).write_bytes(text.replace("\n", "\r\n").encode())
    if fmt == "linuxcnc":
        (tmp_path / "m.hal").write_bytes(
            b"loadrt stepgen step_type=0\r\naddf stepgen.make-pulses base-thread\r\n"
        )
    assert read_firmware(tmp_path / name).firmware == fmt
