"""Grouped violations state their true count and span over the whole capture (issue 34): a
group read "20 × step_high … first at …, last at 0.0074 s … and 30961 more" when only 20 were
listed, while the violations ran through the whole capture."""

from __future__ import annotations

import json
import re
from collections import defaultdict
from fractions import Fraction

import numpy as np
import pytest

from tests.conftest import shared_capture
from wavecheck.cli import main
from wavecheck.engine import results
from wavecheck.engine.judge import FAIL, Judged
from wavecheck.engine.results import RuleResult
from wavecheck.steps.primitives import Intervals
from wavecheck.timebase import Timebase

GRBL = "sigrok-dumps/stepper_motor/grbl_cnc/grbl_cnc_1.sr"
#: grbl's 9.5 us step pulses against a 10 us limit: 5054 fail, each 500 ns short
ARGS = ["--drive", "drv8825", "--map", "step=1", "--limit", "step_high=10us"]


def _every_violation(capsys: pytest.CaptureFixture[str]) -> list[dict[str, object]]:
    path = str(shared_capture(GRBL))
    assert main(["check", path, *ARGS, "--format", "json", "--max-violations", "100000"]) == 1
    return json.loads(capsys.readouterr().out)["violations"]


@pytest.mark.parametrize("blocks", [None, "20000"])
def test_a_group_counts_the_whole_capture(
    capsys: pytest.CaptureFixture[str], blocks: str | None
) -> None:
    every = _every_violation(capsys)
    by: dict[tuple[str, str], list[Fraction]] = defaultdict(list)
    for v in every:
        by[(str(v["rule"]), str(v["measured_ns"]))].append(Fraction(str(v["time_s"])))
    path = str(shared_capture(GRBL))
    extra = ["--block-edges", blocks] if blocks else []
    assert main(["check", path, *ARGS, "--max-violations", "20", *extra]) == 1
    text = capsys.readouterr().out
    lines = [ln for ln in text.splitlines() if " × " in ln]
    assert len(lines) == len(by) == 1
    ((_, times),) = by.items()
    count = int(lines[0].split(" × ")[0])
    first, last = re.findall(r"at (\d+\.\d+) s", lines[0])
    assert count == len(every) == 5054
    assert (first, last) == (f"{float(min(times)):.9f}", f"{float(max(times)):.9f}")
    assert float(last) > 40  # through the whole 48 s capture, not the first few listed
    # every violation is in the group shown (the text names the capture: a checkout whose path
    # holds "more" must not fail this)
    assert not re.search(r"\d+ more\b", text.replace(path, "CAPTURE"))


def _judged(starts: list[int], lengths: list[int]) -> Judged:
    s = np.asarray(starts, dtype=np.int64)
    iv = Intervals(s, s + np.asarray(lengths, dtype=np.int64))
    return Judged("step_high", iv, np.full(len(s), FAIL, dtype=np.int8), len(s))


def test_the_tally_keeps_the_shortest_lengths(monkeypatch: pytest.MonkeyPatch) -> None:
    """Bounded: beyond TALLY_KEPT distinct lengths the longest are dropped (never the short ones
    the report lists), and a dropped length is never tallied again (its count would be short)."""
    monkeypatch.setattr(results, "TALLY_KEPT", 3)
    r = RuleResult("step_high", Fraction(100), None, Timebase(Fraction(1, 10**9)), Fraction(1))
    empty = np.zeros(0, dtype=np.int64)
    r.add(_judged([0, 10, 20, 30], [50, 60, 70, 80]), empty)
    r.add(_judged([40, 50, 60], [80, 40, 50]), empty)
    assert r.tally(40) == (1, 50, 50)
    assert r.tally(50) == (2, 0, 60)
    assert r.tally(60) == (1, 10, 10)
    assert r.tally(70) is None and r.tally(80) is None
    r.add(_judged([90], [70]), empty)
    assert r.tally(70) is None
