"""Issue 23: what only a picture draws (the thinned step trace, the signal windows around the
worst places, each rule's histogram) is built when a picture is asked for, and only then."""

from __future__ import annotations

from pathlib import Path

import pytest

import wavecheck

GOLDEN = Path(__file__).resolve().parents[3] / "captures" / "golden"
CAPTURE = GOLDEN / "g202-p20-worst-dirhold.vcd"


@pytest.mark.parametrize("pictures", [False, True])
def test_pictures_only_when_asked(pictures: bool) -> None:
    report = wavecheck.check(CAPTURE, "gecko-g202", pictures=pictures)
    assert report.rules and report.steps.count  # a real check ran either way
    assert (report.trace is not None) is pictures
    assert (report.windows is not None) is pictures
    measured = [r for r in report.rules if r.limit_ns is not None and r.checked]
    assert measured
    for r in measured:
        hist = r.histogram()
        assert (hist is not None) is pictures
        if hist is not None:  # every measured interval is in one bin
            assert sum(c for _, c in hist.counts) == r.checked
