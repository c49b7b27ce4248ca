"""The vectorised checker agrees with the plain-loop reference checker on generated waveforms.

Each waveform is written to disk (VCD and ``.sr``) and read back with tiny read chunks and
``.sr`` members, so edges fall on chunk boundaries; the engine's report must give the same
intervals checked, violations (count and where), indeterminate counts, verdicts, minimum
margins (value and where), steps and overall verdict as :mod:`tests.reliability.refcheck`.
"""

from __future__ import annotations

from fractions import Fraction
from pathlib import Path

import pytest
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from tests.conftest import write_vcd
from tests.engine_probe import run_check
from tests.reliability.corpus import samples_from_edges, sr_bytes, sr_metadata
from tests.reliability.refcheck import min_margin, reference_check
from tests.wavecheck.waves import drive as make_drive
from wavecheck.capture.sr import read_sr
from wavecheck.capture.vcd import read_vcd

TICK_NS = Fraction(100)  # VCD "$timescale 100 ns", .sr at 10 MHz


def _vcd(path: Path, signals: dict[str, tuple[int, list[int]]], end: int) -> Path:
    return write_vcd(path, signals, timescale="100 ns", end=end)


@st.composite
def waveforms(draw: st.DrawFn) -> dict:
    gaps = draw(st.lists(st.integers(1, 12), min_size=2, max_size=40))
    start = draw(st.integers(1, 5))
    step_edges = []
    t = start
    for g in gaps:
        step_edges.append(t)
        t += g
    horizon = t + 5
    near = (
        st.sampled_from(step_edges).flatmap(lambda e: st.integers(max(1, e - 3), e + 3))
        if step_edges
        else st.integers(1, horizon)
    )
    dir_edges = sorted(set(draw(st.lists(st.one_of(near, st.integers(1, horizon)), max_size=8))))
    limits = {}
    for rule in ("step_high", "step_low", "dir_setup", "dir_hold"):
        if draw(st.integers(0, 4)):  # stated 4 times in 5
            limits[rule] = Fraction(25 * draw(st.integers(0, 40)))
    period_k = draw(st.integers(1, 30)) if draw(st.integers(0, 2)) else None
    return {
        "step": (draw(st.integers(0, 1)), step_edges),
        "dir": (draw(st.integers(0, 1)), dir_edges),
        "end": max([horizon, *dir_edges]) + 1,
        "limits": limits,
        "max_rate": Fraction(10**9, 50 * period_k) if period_k else None,
        "resolution_ns": Fraction(draw(st.sampled_from([0, 50, 100, 250]))),
        "active_edge": draw(st.sampled_from(["rising", "falling", "both"])),
        "forward_level": draw(st.integers(0, 1)),
        "vcd_chunk": draw(st.integers(4, 64)),
        "sr_member": draw(st.integers(1, 16)),
        "sr_read": draw(st.integers(1, 9)),
    }


def _compare(report, ref, w) -> None:  # type: ignore[no-untyped-def]
    for rule in ("step_high", "step_low", "step_period", "dir_setup", "dir_hold"):
        got = report.rule(rule)
        want = ref.rules.get(rule)
        if want is None:
            assert got is None, f"{rule}: not stated by the drive but evaluated"
            continue
        assert got is not None, f"{rule}: stated by the drive but missing from the report"
        assert got.checked == want.checked, (rule, got.checked, want.checked)
        assert got.violation_ticks.tolist() == want.violation_ticks, rule
        assert got.violations == len(want.violation_ticks), rule
        assert got.indeterminate == want.indeterminate, rule
        assert got.verdict == want.verdict, (rule, got.verdict, want.verdict)
        mm = min_margin(want, TICK_NS)
        if mm is None:
            assert got.min_margin_ns is None, rule
        else:
            assert got.min_margin_ns == mm[0], (rule, got.min_margin_ns, mm[0])
            assert got.min_margin_at_tick == mm[1], rule
    assert report.steps.ticks.tolist() == ref.step_ticks
    assert report.steps.direction.tolist() == ref.directions
    assert report.steps.ambiguous.tolist() == ref.ambiguous
    assert report.verdict == ref.verdict, (report.verdict, ref.verdict)


@settings(
    max_examples=200,
    deadline=None,
    derandomize=True,
    suppress_health_check=[HealthCheck.too_slow],
)
@given(w=waveforms())
def test_engine_agrees_with_reference(tmp_path_factory: pytest.TempPathFactory, w: dict) -> None:
    verdict = agree(w, tmp_path_factory.mktemp("agree"))
    event(f"verdict {verdict}")


def agree(w: dict, folder: Path) -> str:
    """Check one waveform both ways; returns the reference verdict."""
    folder.mkdir(parents=True, exist_ok=True)
    ref = reference_check(
        w["step"],
        w["dir"],
        tick_ns=TICK_NS,
        resolution_ns=w["resolution_ns"],
        limits_ns=w["limits"],
        max_rate_hz=w["max_rate"],
        active_edge=w["active_edge"],
        forward_level=w["forward_level"],
    )
    drv = make_drive(active_edge=w["active_edge"], max_rate_hz=w["max_rate"], **w["limits"])
    signals = {"STEP": w["step"], "DIR": w["dir"]}
    vcd_cap = read_vcd(_vcd(folder / "w.vcd", signals, w["end"]), chunk_bytes=w["vcd_chunk"])
    raw = samples_from_edges(w["end"] + 1, [w["step"], w["dir"]]).tobytes()
    sr_path = folder / "w.sr"
    sr_path.write_bytes(
        sr_bytes(raw, metadata=sr_metadata(samplerate="10 MHz"), chunk=w["sr_member"])
    )
    sr_cap = read_sr(sr_path, chunk_bytes=w["sr_read"])
    for cap in (vcd_cap, sr_cap):
        report = run_check(
            cap,
            drv,
            {"step": "STEP", "dir": "DIR"},
            (),
            0,
            w["resolution_ns"] / 10**9,
            forward_level=w["forward_level"],
            active_edge=w["active_edge"],
        )
        _compare(report, ref, w)
    return ref.verdict


def test_the_comparison_has_teeth(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A DIR change in the same tick as an active edge must be a 0-length dir_setup interval;
    an engine that looked only strictly after the change (an off-by-one) is caught."""
    import numpy as np

    import wavecheck.engine.intervals as compiled
    from wavecheck.steps.primitives import Intervals

    w = {
        "step": (0, [10, 12, 20, 22]), "dir": (0, [20]), "end": 30,
        "limits": {"dir_setup": Fraction(100)}, "max_rate": None,
        "resolution_ns": Fraction(0), "active_edge": "rising", "forward_level": 0,
        "vcd_chunk": 16, "sr_member": 4, "sr_read": 3,
    }  # fmt: skip
    agree(w, tmp_path / "ok")

    def strictly_after(data, ref):  # type: ignore[no-untyped-def]
        k = np.searchsorted(ref, data, side="right")
        ok = k < len(ref)
        return Intervals(data[ok], ref[k[ok]])

    monkeypatch.setattr(compiled, "setups", strictly_after)
    with pytest.raises(AssertionError):
        agree(w, tmp_path / "broken")
