"""One block or many, through every option of ``check`` and ``measure`` (issue 23).

The matrix is built from the commands' own parsers: every option (but ``--help`` and the block
options themselves) has a sample below, run on a capture at ``--block-edges`` 1, 7 and 1000 and
as one window (``--no-stream``); the report, the exit code and every file written must be the
same at each size. An option added to either command fails :func:`test_every_option_has_a_sample`
until it is given one here.
"""

from __future__ import annotations

import argparse
import importlib
import re
from pathlib import Path

import numpy as np
import pytest

from wavecheck.cli import main

ROOT = Path(__file__).resolve().parents[3]
GOLDEN = ROOT / "captures" / "golden"
FIRMWARE = ROOT / "captures" / "firmware"
G202 = str(GOLDEN / "g202-p20-worst-dirhold.vcd")
QUAD = str(GOLDEN / "stepgen1-quadrature.vcd")
UPDOWN = str(GOLDEN / "updown-uniform.vcd")
LINUXCNC = FIRMWARE / "linuxcnc" / "Gecko_540B3"
BLOCKS = (["--block-edges", "1"], ["--block-edges", "7"], ["--block-edges", "1000"],
          ["--no-stream"])  # fmt: skip
#: Options the matrix itself sets.
OWN = {"-h", "--help", "--block-edges", "--no-stream"}

#: option → (capture, arguments) samples; "{tmp}" is a folder of the run. Arguments for
#: ``check`` (``--drive`` is added); measure takes those of its options.
SAMPLES: dict[str, list[tuple[str, list[str]]]] = {
    "--drive": [(G202, ["--drive", "xylotex"])],
    "--map": [(G202, ["--map", "step=step,dir=dir"])],
    "--invert": [(G202, ["--invert", "step"]),
                 (UPDOWN, ["--type", "1", "--invert", "up", "--invert", "down"])],
    "--type": [(QUAD, ["--type", "2"]), (UPDOWN, ["--type", "1"])],
    "--user-step-type": [(QUAD, ["--type", "15", "--user-step-type", "1,3,2,0"])],
    "--dir-forward": [(G202, ["--dir-forward", "high"])],
    "--pulse-level": [(G202, ["--pulse-level", "low"])],
    "--active-edge": [(G202, ["--active-edge", "both"]), (G202, ["--active-edge", "rising"])],
    "--limit": [(G202, ["--limit", "dir_hold=5us"])],
    "--margin": [(G202, ["--margin", "2x"])],
    "--require": [(G202, ["--require", "all"]),
                  (UPDOWN, ["--type", "1", "--require", "enable_setup"])],
    "--firmware": [(G202, ["--firmware", str(LINUXCNC / "Gecko_540B3.ini")])],
    "--axis": [(G202, ["--firmware", str(LINUXCNC / "Gecko_540B3.ini"), "--axis", "y"])],
    "--firmware-axis": [
        (G202, ["--firmware", str(LINUXCNC / "Gecko_540B3.ini"), "--firmware-axis", "x=x"])
    ],
    "--firmware-format": [
        (G202, ["--firmware", str(LINUXCNC / "Gecko_540B3.ini"), "--firmware-format", "linuxcnc"])
    ],
    "--hm2-clock": [
        (G202, ["--firmware", str(FIRMWARE / "linuxcnc/hm2-stepper/5i20.ini"),
                "--hm2-clock", "33MHz"])
    ],  # fmt: skip
    "--samplerate": [(G202, ["--samplerate", "1MHz"])],
    "--resolution": [(G202, ["--resolution", "500ns"])],
    "--input-format": [(G202, ["--input-format", "vcd"])],
    "--channels": [("{tmp}/raw.bin", ["--input-format", "binary:numchannels=2",
                                      "--samplerate", "1MHz", "--channels", "step,dir"])],
    "--format": [(G202, ["--format", "json"]), (G202, ["--format", "junit"])],
    "-o": [(G202, ["-o", "{tmp}/report.txt"])],
    "--max-violations": [(G202, ["--max-violations", "2"])],
    "--plot": [(G202, ["--plot", "{tmp}/p.png"])],
    "--html": [(G202, ["--html", "{tmp}/p.html"])],
    "--gtkw": [(G202, ["--gtkw", "{tmp}/p.gtkw"])],
    "-j": [(G202, ["-j", "1"])],
    "-q": [(G202, ["-q"])],
    "--ini": [(G202, ["--ini", str(LINUXCNC / "Gecko_540B3.ini")])],
    "--hal": [(G202, ["--ini", str(LINUXCNC / "Gecko_540B3.ini"),
                      "--hal", str(LINUXCNC / "Gecko_540B3.hal")])],
    "--channel": [(G202, ["--base-period", "20us", "--channel", "0"])],
    "--base-period": [(G202, ["--base-period", "20us", "--latency", "11us"])],
    "--steplen": [(G202, ["--base-period", "20us", "--steplen", "20us"])],
    "--stepspace": [(G202, ["--base-period", "20us", "--stepspace", "20us"])],
    "--dirsetup": [(G202, ["--base-period", "20us", "--dirsetup", "20us"])],
    "--dirhold": [(G202, ["--base-period", "20us", "--dirhold", "40us"])],
    "--latency": [(G202, ["--base-period", "20us", "--latency", "9us"])],
    "--pulseview": [(G202, ["--pulseview", "{tmp}/s.pvs"])],
    "--steps-csv": [(G202, ["--steps-csv", "{tmp}/s.csv"]),
                    (UPDOWN, ["--type", "1", "--steps-csv", "{tmp}/s.csv"])],
    "--steps-per-unit": [(G202, ["--steps-csv", "{tmp}/s.csv", "--steps-per-unit", "80"])],
}  # fmt: skip
#: check-only options (measure has no drive, no stepgen configuration, no several captures).
CHECK_ONLY = {"--drive", "--limit", "--margin", "--require", "--format", "--max-violations",
              "--gtkw", "-j", "--ini", "--hal", "--channel", "--base-period", "--steplen",
              "--stepspace", "--dirsetup", "--dirhold", "--latency", "--pulseview"}  # fmt: skip


def _options(command: str) -> set[str]:
    sub = argparse.ArgumentParser().add_subparsers()
    importlib.import_module(f"wavecheck.cli.{command}").register(sub)
    return {a.option_strings[0] for a in sub.choices[command]._actions if a.option_strings}


@pytest.mark.parametrize("command", ["check", "measure"])
def test_every_option_has_a_sample(command: str) -> None:
    missing = _options(command) - OWN - set(SAMPLES)
    assert not missing, f"give {command}'s {sorted(missing)} a sample in SAMPLES"


def _raw(tmp: Path) -> None:
    """The golden G202 trace as raw samples (1 us a sample: sigrok-cli's -O binary layout)."""
    from wavecheck.capture.open import open_capture

    cap = open_capture(G202)
    n = int(cap.end // 1000) + 2
    samples = np.zeros(n, dtype=np.uint8)
    for bit, ch in enumerate(cap.channels[:2]):
        level = np.full(n, ch.initial, dtype=np.uint8)
        for t in (ch.edges // 1000).tolist():
            level[t:] ^= 1
        samples |= level << bit
    (tmp / "raw.bin").write_bytes(samples.tobytes())


def _run(command: str, capture: str, args: list[str], block: list[str], tmp: Path, capsys: pytest.CaptureFixture[str]) -> tuple[int, dict[str, str]]:  # fmt: skip
    for f in tmp.iterdir():
        if f.name != "raw.bin":
            f.unlink()
    drive = ["--drive", "gecko-g202"] if command == "check" else []
    argv = [command, capture.format(tmp=tmp), *drive, *(a.format(tmp=tmp) for a in args), *block]
    code = main(argv)
    out = capsys.readouterr().out
    files = {"stdout": out}
    for f in sorted(tmp.iterdir()):
        if f.name in ("raw.bin",) or f.suffix == ".png":
            files[f.name] = "(png)" if f.suffix == ".png" else ""
            continue
        text = f.read_text(errors="replace")
        files[f.name] = re.sub(r"data:image/png;base64,[^\"']*", "", text)
    return code, files


CASES = [
    (command, option, k)
    for command in ("check", "measure")
    for option, samples in SAMPLES.items()
    if command == "check" or option not in CHECK_ONLY
    for k in range(len(samples))
]


@pytest.mark.parametrize(("command", "option", "k"), CASES, ids=lambda v: str(v))
def test_one_block_or_many(
    command: str, option: str, k: int, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    capture, args = SAMPLES[option][k]
    if "{tmp}" in capture:
        _raw(tmp_path)
    results = [_run(command, capture, args, b, tmp_path, capsys) for b in BLOCKS]
    first = results[0]
    assert first[0] in (0, 1, 3, 4), first  # a usable sample: not a usage error (2)
    for block, got in zip(BLOCKS[1:], results[1:], strict=True):
        assert got == first, f"{command} {option} differs at {block}"
