"""``check --firmware`` / ``measure --firmware`` compare each capture axis with its own firmware
axis (issue 24): by name or alias, ``--firmware-axis y=beta`` where the names differ, and the
pairing is stated in the report. Before, every axis was compared with the first axis's settings
(a Y axis checked against grbl's X limit $110)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from tests.conftest import SHARED, write_vcd
from wavecheck.cli import main

FW = SHARED / "firmware"
#: GRBL-config.md, first dump: $100=$101=800 steps/mm (lines 28-29), $110=1000 (line 31),
#: $111=800 mm/min (line 32): X may step at 13333 Hz, Y only at 10667 Hz.
GRBL = FW / "grbl/GRBL-config.md"
SMOOTHIE_DELTA = SHARED / "firmware-corpus/smoothie/AzteegX5Mini.delta/Version3/config"
pytestmark = pytest.mark.skipif(not GRBL.is_file(), reason="shared firmware files not present")


def _two_axes(tmp_path: Path, y_period_ns: int) -> Path:
    """x steps at 1 kHz, y at 1e9 / ``y_period_ns``; 20 us pulses, DIR still."""

    def steps(period: int) -> list[int]:
        return [t for k in range(6) for t in (1000 + k * period, 1000 + k * period + 20_000)]

    return write_vcd(tmp_path / "two.vcd", {"X_STEP": (0, steps(1_000_000)), "X_DIR": (0, []),
                     "Y_STEP": (0, steps(y_period_ns)), "Y_DIR": (0, [])}, end=7_000_000)  # fmt: skip


_MAP = ["--map", "x.step=X_STEP,x.dir=X_DIR", "--map", "y.step=Y_STEP,y.dir=Y_DIR"]


def _firmware(doc: dict, axis: str) -> dict:  # type: ignore[type-arg]
    return next(a["firmware"] for a in doc["axes"] if a["name"] == axis)


def test_check_pairs_axes_by_name(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    vcd = _two_axes(tmp_path, 80_000)  # y at 12.5 kHz: within X's 13333 Hz, over Y's 10667 Hz
    code = main(["check", str(vcd), "--drive", "leadshine-dm542", *_MAP, "--firmware", str(GRBL),
                 "--format", "json", "-q"])  # fmt: skip
    doc = json.loads(capsys.readouterr().out)
    y = _firmware(doc, "y")
    assert y["axis"] == "Y" and "capture axis y ↔ firmware axis Y (same name)" == y["pairing"]
    rate = next(c for c in y["comparisons"] if c["what"] == "rate")
    assert rate["configured"] == pytest.approx(800 * 800 / 60) and rate["verdict"] == "fail"
    assert _firmware(doc, "x")["axis"] == "X" and code == 1


def test_measure_pairs_axes_by_name(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    vcd = _two_axes(tmp_path, 80_000)
    main(["measure", str(vcd), *_MAP, "--firmware", str(GRBL), "--format", "json", "-q"])
    doc = json.loads(capsys.readouterr().out)
    y = next(a for a in doc["axes"] if a["name"] == "y")["firmware"]
    assert y["axis"] == "Y" and "firmware axis Y" in y["pairing"]


def test_firmware_axis_pairs_other_names(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A delta's alpha/beta have no x/y alias: a named capture axis without a match is refused
    (one line naming the option); --firmware-axis pairs them and the report says so."""
    if not SMOOTHIE_DELTA.is_file():
        pytest.skip("shared firmware corpus not present")
    vcd = _two_axes(tmp_path, 1_000_000)
    argv = ["check", str(vcd), "--drive", "leadshine-dm542", *_MAP, "--firmware",
            str(SMOOTHIE_DELTA), "--format", "json", "-q"]  # fmt: skip
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "capture axis 'x'" in err and "--firmware-axis x=NAME" in err and err.count("\n") == 1
    main([*argv, "--firmware-axis", "x=alpha", "--firmware-axis", "y=beta"])
    doc = json.loads(capsys.readouterr().out)
    assert _firmware(doc, "y")["axis"] == "beta"
    assert "--firmware-axis y=beta" in _firmware(doc, "y")["pairing"]


def test_one_unnamed_axis_states_its_pairing(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    vcd = write_vcd(tmp_path / "one.vcd", {"STEP": (0, [1000, 21000]), "DIR": (0, [])})
    main(["check", str(vcd), "--drive", "leadshine-dm542", "--map", "step=STEP,dir=DIR",
          "--firmware", str(GRBL), "-q"])  # fmt: skip
    out = capsys.readouterr().out
    assert "paired: the capture ↔ firmware axis X (the first of X, Y, Z" in out
    main(["check", str(vcd), "--drive", "leadshine-dm542", "--map", "step=STEP,dir=DIR",
          "--firmware", str(GRBL), "--axis", "Z", "-q"])  # fmt: skip
    assert "firmware axis Z (--axis Z)" in capsys.readouterr().out
