"""Every firmware file input is bounded (issue 27): devices, FIFOs and huge files are refused
before they are read, parsing is linear in the file, and a number no machine can have (NaN,
infinities, ``1e999999999``, ``1e400``, 20 or 5,000 digits) is one line naming the file, the line
and the value, exit 2 — never OverflowError, ValueError, a hang or a traceback. Each case would
hang, crash or read gigabytes on the code before this change."""

from __future__ import annotations

import os
import re
from pathlib import Path

import pytest

from tests.bounds import lines_run
from tests.wavecheck.firmware.bounded import bounded
from wavecheck.cli import main
from wavecheck.config_text import MAX_CONFIG_BYTES
from wavecheck.errors import ConfigError
from wavecheck.firmware import read_firmware

#: Numbers no configuration can hold, each as a firmware file writes numbers.
BAD_NUMBERS = ["1e999999999", "1e400", "12345678901234567890", "9" * 5000, "nan", "inf", "-inf"]

#: (format, file name, text with {N} where the number goes, the line of {N}).
TEMPLATES = [
    ("grbl", "dump.txt", "$0={N}\n$1=25\n$100=80\n$110=500\n", 1),
    ("grbl-rate", "dump.txt", "$0=10\n$100=80\n$110={N}\n", 3),
    ("klipper", "printer.cfg",
     "[printer]\nkinematics: cartesian\nmax_velocity: 300\n[stepper_x]\nstep_pin: PA1\n"
     "dir_pin: PA2\nmicrosteps: 16\nrotation_distance: {N}\n", 8),
    ("klipper-pulse", "printer.cfg",
     "[printer]\nmax_velocity: 300\n[stepper_x]\nstep_pin: PA9\ndir_pin: PA10\n"
     "step_pulse_duration: {N}\n", 6),
    ("marlin", "Configuration.h",
     "#define CONFIGURATION_H_VERSION 02010300\n#define X_DRIVER_TYPE A4988\n"
     "#define MINIMUM_STEPPER_PULSE_NS {N}\n", 3),
    ("smoothie", "config", "alpha_steps_per_mm {N}\nalpha_step_pin 2.0\n", 1),
    ("smoothie-pulse", "config", "microseconds_per_step_pulse {N}\nalpha_steps_per_mm 80\n", 1),
    ("rrf", "config.g", "M584 X0 Y1 Z2\nM92 X{N} Y80 Z400\nM203 X6000\n", 2),
    ("rrf-timing", "config.g", "M569 P0 S1 T{N}\nM92 X80\n", 1),
    ("fluidnc", "config.yaml",
     "board: test\nstepping:\n  engine: RMT\n  pulse_us: {N}\naxes:\n  x:\n    steps_per_mm: 80\n"
     "    motor0:\n      standard_stepper:\n        step_pin: gpio.2\n", 4),
    ("linuxcnc-ini", "machine.ini", "[EMCMOT]\nBASE_PERIOD = {N}\n[HAL]\nHALFILE = m.hal\n", 2),
    ("linuxcnc-hal", "m.hal", "loadrt stepgen step_type=0\nsetp stepgen.0.steplen {N}\n", 2),
]  # fmt: skip


@pytest.mark.parametrize("value", BAD_NUMBERS, ids=lambda v: v[:12])
@pytest.mark.parametrize("fmt,name,template,line", TEMPLATES, ids=[t[0] for t in TEMPLATES])
def test_numbers_no_machine_has(
    tmp_path: Path, fmt: str, name: str, template: str, line: int, value: str
) -> None:
    path = tmp_path / name
    path.write_text(template.replace("{N}", value))
    if fmt == "linuxcnc-ini":
        (tmp_path / "m.hal").write_text("loadrt stepgen step_type=0\n")
    if fmt == "linuxcnc-hal":
        (tmp_path / "machine.ini").write_text(
            "[EMCMOT]\nBASE_PERIOD = 20000\n[HAL]\nHALFILE = m.hal\n"
        )
        path = tmp_path / "machine.ini"
    with pytest.raises(ConfigError) as err:
        bounded(lambda: read_firmware(path))
    text = str(err.value)
    assert "\n" not in text and len(text) < 300, text
    assert f"{name}:{line}:" in text, text  # the file and the line
    assert value[:8] in text or "…" in text, text  # the value, shortened when long


def test_a_character_device_is_refused_unread(capsys: pytest.CaptureFixture[str]) -> None:
    """``config /dev/zero`` read 2.7 GB then raised MemoryError."""
    code = bounded(lambda: main(["config", "/dev/zero", "--drive", "tb6600"]))
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1
    assert "/dev/zero" in err and "character device" in err


def test_a_fifo_without_writer_is_refused_not_waited_for(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    fifo = tmp_path / "settings.txt"
    os.mkfifo(fifo)
    code = bounded(lambda: main(["config", str(fifo), "--drive", "tb6600"]))
    err = capsys.readouterr().err
    assert code == 2 and "FIFO" in err and str(fifo) in err


def test_a_huge_file_is_refused_before_it_is_read(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    big = tmp_path / "printer.cfg"
    with big.open("wb") as fh:
        fh.truncate(MAX_CONFIG_BYTES + 1)  # sparse: no disk used
    code = bounded(lambda: main(["config", str(big), "--drive", "tb6600"]))
    err = capsys.readouterr().err
    assert code == 2 and "MiB" in err and str(big) in err


def test_a_huge_hal_file_named_by_an_ini_is_refused(tmp_path: Path) -> None:
    (tmp_path / "m.ini").write_text("[EMCMOT]\nBASE_PERIOD = 20000\n[HAL]\nHALFILE = m.hal\n")
    with (tmp_path / "m.hal").open("wb") as fh:
        fh.truncate(MAX_CONFIG_BYTES + 1)
    with pytest.raises(ConfigError, match=r"m\.hal: more than"):
        read_firmware(tmp_path / "m.ini")


def _klipper(n: int) -> str:
    body = [f"[stepper_{i}]\nstep_pin: PA{i % 16}\ndir_pin: PB1\n" for i in range(n)]
    return "[printer]\nkinematics: cartesian\nmax_velocity: 300\n" + "".join(body)


def test_parsing_is_linear_and_axes_are_bounded(tmp_path: Path) -> None:
    """A Klipper file with 20,000 stepper sections took over 60 s (quadratic lookups): now it is
    refused at once, and 200 sections (a legal count) cost about what 20 do, times ten: work
    counted as lines of Python run (tests/bounds.py), after a first run has imported what the
    command needs."""
    big = tmp_path / "big.cfg"
    big.write_text(_klipper(20_000))
    with pytest.raises(ConfigError, match=r"20000 stepper sections \(at most 256"):
        bounded(lambda: read_firmware(big))
    costs = []
    for n in (20, 20, 200):
        path = tmp_path / f"k{n}.cfg"
        path.write_text(_klipper(n))
        argv = ["config", str(path), "--drive", "tb6600", "-o", str(tmp_path / f"r{n}.txt")]
        code, lines = lines_run(lambda a=argv: bounded(lambda: main(a)))  # type: ignore[misc]
        costs.append(lines)
        assert code in (0, 1, 3)
    assert costs[2] < 20 * costs[1]  # linear: ~10x; quadratic would be ~100x


@pytest.mark.parametrize(
    "text",
    [
        "#define X_DRIVER_TYPE A4988\n#define A "
        + "(" * 5000
        + "1"
        + ")" * 5000
        + "\n#if A\n#endif\n",
        "#define X_DRIVER_TYPE A4988\n"
        + "".join(f"#define M{i} M{i + 1}\n" for i in range(5000))
        + "#if M0\n#endif\n",
        "#define X_DRIVER_TYPE A4988\n#define S 1 << 100000000\n#define MAXIMUM_STEPPER_RATE S\n",
        "#define X_DRIVER_TYPE A4988\n" + "#if 1\n" * 3000 + "#endif\n" * 3000,
    ],
    ids=["deep-parentheses", "macro-chain", "huge-shift", "deep-ifs"],
)
def test_marlin_preprocessor_is_bounded(tmp_path: Path, text: str) -> None:
    path = tmp_path / "Configuration.h"
    path.write_text(text)
    try:
        bounded(lambda: read_firmware(path))
    except ConfigError as err:
        assert "\n" not in str(err) and str(path) in str(err)


def test_yaml_bombs_and_nesting_are_bounded(tmp_path: Path) -> None:
    path = tmp_path / "config.yaml"
    lol = "".join(f"l{i}: &l{i} [*l{i - 1}, *l{i - 1}, *l{i - 1}]\n" for i in range(1, 30))
    path.write_text("board: x\nl0: &l0 [a]\n" + lol + "axes:\n  x:\n    steps_per_mm: 80\n"
                    + "deep: " + "[" * 100_000 + "]" * 100_000 + "\n")  # fmt: skip
    with pytest.raises(ConfigError) as err:
        bounded(lambda: read_firmware(path, "fluidnc"))
    assert re.match(rf"{re.escape(str(path))}(:\d+)?: ", str(err.value))
