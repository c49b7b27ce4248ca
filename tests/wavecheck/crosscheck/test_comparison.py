"""The cross-check's parsing and comparison without sigrok-cli: sigrok's output is written by
hand as its decoders print it (``../shared/reference/sigrok.md`` §3.1)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from tests.conftest import write_vcd
from wavecheck.capture.vcd import read_vcd
from wavecheck.crosscheck.comparison import CrosscheckResult, compare
from wavecheck.crosscheck.sigrok import (
    DecoderOutput,
    SigrokInput,
    parse_annotations,
    pick_downsample,
)
from wavecheck.errors import CaptureError
from wavecheck.steps.decode import decode
from wavecheck.steps.interface import build_interface


def test_parse_annotations() -> None:
    out = (
        "10-20 stepper_motor-1: 1 steps\n"
        "7-7 counter-1: 1\n"
        "some other line\n"
        "20-30 stepper_motor-1: -1 steps\n"
        "21-21 counter-1: 2\n"
    )
    got = parse_annotations(out, "x.sr")
    assert got.counts.tolist() == [1, 2]
    assert got.positions.tolist() == [[10, 20, 1], [20, 30, -1]]
    with pytest.raises(CaptureError, match="unexpected stepper_motor line"):
        parse_annotations("1-2 stepper_motor-1: fast\n", "x.sr")


def test_pick_downsample() -> None:
    a = np.array([100, 200, 230], dtype=np.int64)
    assert pick_downsample([a, np.array([200, 260], dtype=np.int64)]) == 30
    assert pick_downsample([np.array([5], dtype=np.int64)]) == 1


def _result(
    tmp_path: Path, positions: list[tuple[int, int, int]], counts: list[int]
) -> CrosscheckResult:
    # 3 rising STEP edges at 10, 30, 50; DIR high (sigrok: +) from 20 on, low (−) before
    vcd = write_vcd(tmp_path / "s.vcd", {"step": (0, [10, 15, 30, 35, 50, 55]), "dir": (0, [20])})
    iface = build_interface(read_vcd(vcd), {"step": "step", "dir": "dir"})
    steps = decode(iface, 0, active_edge="rising", forward_level=0)
    return compare(
        str(vcd),
        iface.require("step"),
        iface.get("dir"),
        active_edge="rising",
        forward_level=0,
        steps=steps,
        rising=steps,
        sigrok_input=SigrokInput(str(vcd), ["step", "dir"], 5, converted=True),
        sigrok=DecoderOutput.of(counts, positions),
    )


def test_sigroks_known_differences_agree(tmp_path: Path) -> None:
    # samples at downsample 5: steps at 2, 6, 10; positions −1, then 0 (the last step not printed)
    res = _result(tmp_path, [(2, 6, -1), (6, 10, 0)], [1, 2, 3])
    assert res.agree, res.disagreements
    assert res.sigrok_input == "converted .sr (downsample 5)"
    assert (res.expected_last_position, res.final_sigrok_polarity) == (0, 1)
    assert res.wavecheck_final_position == -1  # forward = DIR low: the sign is flipped


def test_a_wrong_position_and_count_disagree(tmp_path: Path) -> None:
    res = _result(tmp_path, [(2, 6, -1), (6, 10, -2)], [1, 2])
    assert not res.agree
    assert any(d.startswith("step count: sigrok counter 2, wavecheck 3") for d in res.disagreements)
    assert any("1 position(s) differ, first after step 2" in d for d in res.disagreements)
