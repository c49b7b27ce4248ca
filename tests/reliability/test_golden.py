"""stepgen's golden VCDs: the decode round trip and injected faults (issue 8)."""

from __future__ import annotations

import bisect
import io
import re
import tomllib
from pathlib import Path

import pytest
from vcd.reader import TokenKind, tokenize

from tests.reliability.vcdedit import VcdText
from wavecheck.api import check
from wavecheck.capture.vcd import read_vcd
from wavecheck.steps.decode import decode
from wavecheck.steps.interface import build_interface

GOLDEN = Path(__file__).resolve().parents[2] / "captures" / "golden"
VCDS = sorted(GOLDEN.glob("*.vcd"))
_ROLES = {0: ("step", "dir"), 1: ("up", "down")}


def _counts_by_pyvcd(path: Path) -> list[tuple[int, int]]:
    """(time, signed 32-bit value) of every ``counts`` change, read with pyvcd's tokenizer."""
    code = None
    t = 0
    out = []
    for tok in tokenize(io.BytesIO(path.read_bytes())):
        if tok.kind is TokenKind.VAR and tok.data.reference == "counts":
            code = tok.data.id_code
        elif tok.kind is TokenKind.CHANGE_TIME:
            t = int(tok.data)
        elif tok.kind is TokenKind.CHANGE_VECTOR and tok.data.id_code == code:
            v = int(tok.data.value)
            out.append((t, v - (1 << 32) if v >> 31 else v))
    assert code is not None, f"{path.name}: no counts vector"
    return out


def test_golden_set_present() -> None:
    assert len(VCDS) >= 5, f"golden VCDs missing in {GOLDEN}"


@pytest.mark.parametrize("path", VCDS, ids=[p.stem for p in VCDS])
def test_round_trip_counts(path: Path) -> None:
    """Every step wavecheck decodes lands on the position stepgen's ``counts`` shows at that
    instant, and the totals match the expected file."""
    comment = re.search(r"type (\d+);(?: user table ([\d,]+);)?", path.read_text()[:2000])
    assert comment, "no step type in the $comment"
    number = int(comment.group(1))
    table = tuple(int(x) for x in comment.group(2).split(",")) if comment.group(2) else None
    cap = read_vcd(path)
    if number in _ROLES:
        roles = _ROLES[number]
    else:
        roles = tuple(c.name for c in cap.channels if c.name.startswith("phase-"))
    iface = build_interface(cap, {r: r for r in roles})
    steps = decode(iface, number, active_edge="rising", user_table=table)
    counts = _counts_by_pyvcd(path)
    times = [t for t, _ in counts]

    def shown(t: int, *, before: bool = False) -> int:
        k = (bisect.bisect_left if before else bisect.bisect_right)(times, t) - 1
        return counts[k][1] if k >= 0 else 0

    mismatches = []
    ambiguous = set(steps.ambiguous.tolist())
    for tick, direction in zip(steps.ticks.tolist(), steps.direction.tolist(), strict=True):
        delta = shown(tick) - shown(tick, before=True)
        if tick in ambiguous:
            # DIR changed at the step's instant: wavecheck leaves the direction open (0);
            # stepgen counted one step either way
            ok = direction == 0 and abs(delta) == 1
        else:
            ok = delta == direction
        if not ok:
            mismatches.append((tick, direction, delta))
    assert not mismatches, f"{len(mismatches)} steps disagree with counts, first {mismatches[:3]}"
    # nothing moves counts between steps
    stray = sorted(set(times[1:]) - set(steps.ticks.tolist()))
    assert not stray, f"counts changes where no step was decoded: {stray[:5]}"
    expect = tomllib.loads(path.with_suffix(".toml").read_text())["expect"]
    assert steps.count == expect["steps"]
    assert counts[-1][1] == expect["final_counts"]
    if not ambiguous:
        assert steps.final_position == expect["final_counts"]


def _only_violation(report, rule: str, time_ns: int) -> None:  # type: ignore[no-untyped-def]
    assert report.verdict == "fail"
    failed = {r.rule: r.violations for r in report.rules if r.violations}
    assert failed == {rule: 1}, failed
    (v,) = report.violations()
    assert v.rule == rule
    assert v.time_s * 10**9 == time_ns


def test_injected_dir_edge_in_setup_window(tmp_path: Path) -> None:
    """G202 at 16 us, dirhold 2 (passes): move the second DIR change to 0.5 us before the next
    active (falling) STEP edge. Exactly one dir_setup violation, at the moved edge."""
    src = GOLDEN / "g202-p16-dirhold2-worst.vcd"
    assert check(src, "gecko-g202").verdict == "pass"
    vt = VcdText(src)
    (t_dir, v_dir) = vt.changes("dir")[-1]
    falls = [t for t, v in vt.changes("step") if v == "0" and t > t_dir]
    new_t = falls[0] - 500
    vt.move("dir", v_dir, t_dir, new_t)
    report = check(vt.write(tmp_path / "moved.vcd"), "gecko-g202")
    _only_violation(report, "dir_setup", new_t)
    assert report.rule("dir_setup").min_margin_ns == -500


def test_injected_dir_edge_in_hold_window(tmp_path: Path) -> None:
    """The same file's dir_hold margin is +1 us: move the DIR change 1 us + 1 ns earlier and the
    hold from the active edge before it fails by exactly 1 ns."""
    src = GOLDEN / "g202-p16-dirhold2-worst.vcd"
    vt = VcdText(src)
    report0 = check(src, "gecko-g202")
    hold = report0.rule("dir_hold")
    assert hold.min_margin_ns == 1000
    t_active = hold.min_margin_at_tick
    t_dir = t_active + 21000
    value = dict(vt.changes("dir"))[t_dir]
    vt.move("dir", value, t_dir, t_dir - 1001)
    report = check(vt.write(tmp_path / "moved.vcd"), "gecko-g202")
    _only_violation(report, "dir_hold", t_active)
    assert report.rule("dir_hold").min_margin_ns == -1


def test_injected_short_pulse(tmp_path: Path) -> None:
    """stepgen.0 (1280 pulses of 100 us) against a drive whose step_high minimum is exactly
    100 us (every pulse passes at the boundary); end pulse #700 one tick early: exactly one
    step_high violation, at that pulse's start, 1 ns short."""
    from dataclasses import replace
    from fractions import Fraction

    from wavecheck.drives.datasheet import Figure
    from wavecheck.drives.library import load_drive

    src = GOLDEN / "stepgen0.vcd"
    g202 = load_drive("gecko-g202")
    limits = dict(g202.limits)
    limits["step_high"] = Figure(Fraction(100_000), "test", "datasheet")
    drive = replace(g202, limits=limits, active_edge="rising")
    report0 = check(src, drive)
    assert report0.verdict == "pass" and report0.rule("step_high").min_margin_ns == 0
    vt = VcdText(src)
    step = vt.changes("step")
    rises = [t for t, v in step if v == "1" and t > 0]
    falls = [t for t, v in step if v == "0" and t > 0]
    start, end = rises[700], min(t for t in falls if t > rises[700])
    vt.move("step", "0", end, end - 1)
    report = check(vt.write(tmp_path / "short.vcd"), drive)
    _only_violation(report, "step_high", start)
    assert report.rule("step_high").min_margin_ns == -1
    assert report.steps.count == report0.steps.count
