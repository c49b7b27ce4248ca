"""Reports say each thing once (issue 26: "measure it; measure it", "not measured (it was not
measured (…))"): every firmware example of the README against a few drives, and the golden and
example captures with ``--firmware``, in every format; no line repeats a phrase back to back."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from wavecheck.cli import main

REPO = Path(__file__).resolve().parents[3]
FIRMWARE = REPO / "captures" / "firmware"
CONFIGS = sorted(
    p
    for p in FIRMWARE.rglob("*")
    if p.is_file()
    and p.suffix not in (".hal", ".md")
    or p.name in ("settings.md", "GRBL-config.md")
)
CONFIGS = [p for p in CONFIGS if p.name not in ("README.md", "custom.hal")]
#: A phrase of two words or more said twice in a row ("measure it; measure it"); table columns
#: of figures ("37 us  37 us") are not phrases.
REPEATED = re.compile(r"\b([A-Za-z]{2,}(?: [A-Za-z]{2,})+)[;,:(\s]+\1\b")
NESTED = re.compile(r"not measured \([^)]*not measured")


def _said(capsys: pytest.CaptureFixture[str], *argv: object) -> str:
    main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return out + err


def _lines_repeating(text: str) -> list[str]:
    return [line for line in text.splitlines() if REPEATED.search(line) or NESTED.search(line)]


@pytest.mark.parametrize("config", CONFIGS, ids=lambda p: str(p.relative_to(FIRMWARE)))
def test_config_reports_say_each_thing_once(config: Path, capsys) -> None:
    for drive in ("a4988", "leadshine-dm542", "tb6600"):
        for fmt in ("text", "json", "junit"):
            text = _said(capsys, "config", config, "--drive", drive, "--format", fmt)
            assert not _lines_repeating(text), (drive, fmt, _lines_repeating(text)[:3])


def test_the_two_known_repetitions_are_gone(capsys) -> None:
    smoothie = FIRMWARE / "smoothieware" / "Smoothieboard" / "config"
    text = _said(capsys, "config", smoothie, "--drive", "a4988")
    assert "dir_hold: DIR may change while STEP is still high: measure it\n" in text
    two = REPO / "captures" / "examples" / "two-axis.vcd"
    grbl = FIRMWARE / "grbl" / "settings.md"
    text = _said(capsys, "measure", two, "--map", "x.step=x_step", "--map", "y.step=y_step",
                 "--firmware", grbl)  # fmt: skip
    # grbl's DIR setup is no setting (stepper.c:323-333): said once per axis, not per interval
    assert "dir_setup  UNCHECKED     the firmware does not enforce a DIR setup: measure it" in text


@pytest.mark.parametrize("capture", sorted((REPO / "captures" / "golden").glob("*.vcd")),
                         ids=lambda p: p.name)  # fmt: skip
def test_capture_reports_say_each_thing_once(capture: Path, capsys) -> None:
    grbl = FIRMWARE / "grbl" / "settings.md"
    for argv in (
        ["check", capture, "--drive", "drv8825", "--firmware", grbl],
        ["check", capture, "--drive", "tb6600", "--format", "json", "--require", "all"],
        ["measure", capture, "--firmware", grbl],
    ):
        text = _said(capsys, *argv)
        assert not _lines_repeating(text), (argv, _lines_repeating(text)[:3])
