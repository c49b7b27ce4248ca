"""GTKWave save files: markers at the violations, signals by their VCD names, a VCD for .sr."""

from __future__ import annotations

import re
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest

from tests.conftest import write_vcd
from tests.engine_probe import run_check
from tests.wavecheck.report.traces import stepgen_trace, write_stepgen_vcd
from tests.wavecheck.waves import capture, g202
from wavecheck.capture.open import open_capture
from wavecheck.report import gtkw
from wavecheck.report.gtkw import WAVE_PIXELS, WINDOW_SIZE, vcd_timescale, view_of, write_gtkw
from wavecheck.report.plot import Place


def _markers(text: str) -> list[int]:
    line = next(ln for ln in text.splitlines() if ln.startswith("*"))
    return [int(v) for v in line.split()[1:] if v != "-1"]


def test_vcd_capture_is_opened_as_is(tmp_path: Path) -> None:
    vcd = write_stepgen_vcd(tmp_path / "run.vcd")
    report = run_check(open_capture(vcd), g202(), pictures=True)
    out = tmp_path / "run.gtkw"
    assert write_gtkw(report, out) is None
    text = out.read_text()
    assert f'[dumpfile] "{vcd}"' in text
    assert "+{STEP} top.STEP" in text and "+{DIR} top.DIR" in text
    # primary marker + A + B at the three dir_hold violations (1 ns timescale: ns)
    starts = [v.start_tick for v in report.violations()]
    assert _markers(text) == starts
    assert text.count("dir_hold FAIL") == 3


def test_markers_follow_the_vcd_time_unit(tmp_path: Path) -> None:
    trace = stepgen_trace()
    ten_ns = {k: (init, [t // 10 for t in edges]) for k, (init, edges) in trace.items()}
    vcd = write_vcd(tmp_path / "run.vcd", ten_ns, timescale="10 ns")
    report = run_check(open_capture(vcd), g202(), pictures=True)
    out = tmp_path / "run.gtkw"
    write_gtkw(report, out)
    # GTKWave counts in the unit (ns), not in timescale steps
    assert _markers(out.read_text()) == [10 * v.start_tick for v in report.violations()]


def test_non_vcd_capture_gets_a_vcd_beside_the_save_file(tmp_path: Path) -> None:
    vcd = write_stepgen_vcd(tmp_path / "src.vcd")
    cap = open_capture(vcd)
    cap.format = "sr"  # as if read from a .sr: the save file cannot open it directly
    report = run_check(cap, g202(), {"step": "STEP", "dir": "DIR"}, invert=["step"], pictures=True)
    out = tmp_path / "out" / "run.gtkw"
    out.parent.mkdir()
    written = write_gtkw(report, out)
    assert written == out.with_suffix(".vcd")
    text = out.read_text()
    assert f'[dumpfile] "{written}"' in text
    assert re.search(r"^@68\n\+\{STEP\} wavecheck\.step$", text, re.M)  # 0x40 = invert
    # the VCD written holds the raw channels of the windows kept around the worst places:
    # reading it back gives their edges (inside a window, the capture's own)
    back = open_capture(written)
    assert [c.name for c in back.channels] == ["step", "dir"]
    assert report.windows is not None
    for ch, role in zip(back.channels, ("step", "dir"), strict=True):
        kept = report.windows.signals[role]
        assert ch.initial == kept.initial ^ int(kept.inverted)
        assert list(ch.edges) == list(kept.edges)
        whole = set(cap.channel(kept.channel).edges.tolist())
        # an edge that is not the capture's joins two windows: one tick before the next one's
        joins = set(kept.edges.tolist()) - whole
        assert len(kept.edges) > len(joins) and all(t + 1 in whole for t in joins)
    assert sorted(p.name for p in out.parent.iterdir()) == ["run.gtkw", "run.vcd"]


def test_sr_like_capture_at_2mhz(tmp_path: Path) -> None:
    # 500 ns ticks: the VCD beside is on a 100 ns timescale (5 steps a tick), markers in ns
    trace = stepgen_trace()
    cap = capture(
        {k: (init, [t // 500 for t in edges]) for k, (init, edges) in trace.items()},
        tick_ns=500,
        resolution_ticks=1,
    )
    cap.format = "sr"
    report = run_check(cap, g202(), pictures=True)
    out = tmp_path / "run.gtkw"
    vcd = write_gtkw(report, out)
    assert vcd is not None and "$timescale 100 ns $end" in vcd.read_text()
    assert _markers(out.read_text()) == [500 * v.start_tick for v in report.violations()]
    back = open_capture(vcd)
    assert report.windows is not None
    kept = report.windows.signals["step"].edges
    assert list(back.channel("step").edges) == [5 * t for t in kept]


def test_vcd_timescale() -> None:
    assert vcd_timescale(Fraction(1, 2_000_000)) == (100, "ns", 5)  # 2 MHz: 500 ns
    assert vcd_timescale(Fraction(1, 10**9)) == (1, "ns", 1)
    assert vcd_timescale(Fraction(1, 24_000_000)) == (1, "ps", Fraction(125_000, 3))  # rounded


def _view(text: str) -> tuple[int, float]:
    """``[timestart]`` and the time GTKWave shows across the planned wave area (dump units)."""
    zoom = float(next(ln for ln in text.splitlines() if ln.startswith("*")).split()[0][1:])
    start = int(next(ln for ln in text.splitlines() if ln.startswith("[timestart]")).split()[1])
    return start, WAVE_PIXELS * 2**-zoom / 200


def test_markers_go_to_distinct_times(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    # places that share a time (repeated identical violations) get one marker; the next
    # distinct place takes the next letter
    vcd = write_stepgen_vcd(tmp_path / "run.vcd")
    report = run_check(open_capture(vcd), g202(), pictures=True)
    v = report.violations()
    place = [Place(x.rule, x.start_tick, x.end_tick, x.measured_ns, x.limit_ns, True) for x in v]
    repeated = [place[0], place[0], place[1], place[0], place[1], place[2]]
    monkeypatch.setattr(gtkw, "choose_places", lambda report, n: repeated)
    out = tmp_path / "run.gtkw"
    write_gtkw(report, out)
    text = out.read_text()
    assert _markers(text) == [v[0].start_tick, v[1].start_tick, v[2].start_tick]
    assert text.count("dir_hold FAIL") == 3


def test_save_file_sets_the_window_and_shows_the_worst_interval(tmp_path: Path) -> None:
    vcd = write_stepgen_vcd(tmp_path / "run.vcd")
    report = run_check(open_capture(vcd), g202(), pictures=True)
    out = tmp_path / "run.gtkw"
    write_gtkw(report, out)
    text = out.read_text()
    assert "[size] 1200 600" in text and "[sst_expanded] 0" in text
    worst = report.violations(1)[0]
    start, window = _view(text)
    # the interval (9 us) is the middle third of the window
    assert start == worst.start_tick - 9_000
    assert window == pytest.approx(27_000, rel=1e-5)


def test_view_stays_inside_the_dump() -> None:
    widest = Fraction(WINDOW_SIZE[0], WAVE_PIXELS)
    middle = view_of(1_000, 1_900, 0, 10_000)
    assert (middle.start, middle.window) == (100, 2_700)
    assert view_of(50, 950, 0, 10_000).start == 0  # no time before the dump's first
    near = view_of(1_000, 1_900, 0, 3_000)  # the widest window still ends inside the dump
    assert near.start == 100 and near.start + widest * near.window <= 3_000
    assert near.start + near.window >= 1_900 + 900 // 4
    at_end = view_of(1_000, 1_900, 0, 1_900)  # ends on the dump's last time: an exact fit
    assert (at_end.start, at_end.window) == (100, 1_800)
    assert view_of(5, 5, 0, 10).window == 3  # a zero-length interval counts as 1 unit


def test_a_state_change_is_shown_with_its_neighbouring_edges(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    vcd = write_stepgen_vcd(tmp_path / "run.vcd")
    cap = open_capture(vcd)
    report = run_check(cap, g202(), pictures=True)
    step = list(cap.channel(report.mapping["step"]).edges)
    tick = step[10]
    place = Place("state_sequence", tick, tick, None, None, True, "state 1 → 3")
    monkeypatch.setattr(gtkw, "choose_places", lambda report, n: [place])
    out = tmp_path / "run.gtkw"
    write_gtkw(report, out)
    start, window = _view(out.read_text())
    assert _markers(out.read_text()) == [tick]
    assert start < step[9] and step[11] < start + window


def test_header_names_come_from_the_shared_vcd_header(tmp_path: Path) -> None:
    vcd = tmp_path / "two.vcd"
    vcd.write_text(
        "$timescale 100 ps $end\n$scope module top $end\n$scope module x $end\n"
        "$var wire 1 ! step $end\n$upscope $end\n$scope module y $end\n"
        '$var wire 1 " step $end\n$var wire 1 # dir $end\n$upscope $end\n$upscope $end\n'
        '$enddefinitions $end\n#0\n0!\n0"\n0#\n#10\n'
    )
    names, magnitude = gtkw._vcd_header_names(str(vcd))
    assert magnitude == 100
    assert names["dir"] == "top.y.dir" and names["top.x.step"] == "top.x.step"
    assert "step" not in names  # two leaves named step: only their full names


def test_the_companion_vcd_never_replaces_a_file_wavecheck_did_not_write(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Issue 27: ``check X.sr --gtkw X.gtkw`` beside an existing capture ``X.vcd`` replaced it
    with a small window. The capture is kept byte for byte, the companion takes the first free
    name and the run says which; a second run replaces its own companion, not the capture; a
    symbolic link named X.vcd is not followed into its target."""
    from wavecheck.capture.srzip import write_sr_edges
    from wavecheck.cli import main

    sr = tmp_path / "X.sr"
    steps = [10 * k for k in range(1, 40)]
    edges = sorted(steps + [t + 3 for t in steps])
    write_sr_edges(sr, ["STEP", "DIR"], [np.asarray(edges), np.asarray([5])], [0, 0], 500,
                   samplerate=1_000_000)  # fmt: skip
    capture = tmp_path / "X.vcd"
    capture.write_bytes(b"$comment a 1.5 MB capture of someone else's $end\n" * 3)
    before = capture.read_bytes()
    argv = ["check", str(sr), "--drive", "gecko-g202", "--map", "step=STEP,dir=DIR",
            "--gtkw", str(tmp_path / "X.gtkw")]  # fmt: skip
    for _ in range(2):
        main(argv)
        err = capsys.readouterr().err
        assert f"its signals are in {tmp_path / 'X-2.vcd'}" in err
        assert capture.read_bytes() == before
        assert f'[dumpfile] "{tmp_path / "X-2.vcd"}"' in (tmp_path / "X.gtkw").read_text()
        assert sorted(p.name for p in tmp_path.iterdir()) == ["X-2.vcd", "X.gtkw", "X.sr", "X.vcd"]
    target = tmp_path / "elsewhere.vcd"
    target.write_bytes(before)
    (tmp_path / "X-2.vcd").unlink()
    (tmp_path / "X-2.vcd").symlink_to(target)
    main(argv)
    assert f"its signals are in {tmp_path / 'X-3.vcd'}" in capsys.readouterr().err
    assert target.read_bytes() == before and capture.read_bytes() == before


@pytest.mark.parametrize("name", ["view.vcd", "view.FST", "view.ghw"])
def test_gtkw_named_like_a_dump_is_refused_before_any_work(
    tmp_path: Path, name: str, capsys: pytest.CaptureFixture[str]
) -> None:
    """Issue 34: ``--gtkw FILE.vcd`` gave the save file and its companion one name: the save
    file replaced the VCD and named itself as the dump (and GTKWave opens a .vcd as a dump)."""
    from wavecheck.cli import main

    vcd = Path(__file__).resolve().parents[3] / "captures" / "golden" / "stepgen0.vcd"
    with pytest.raises(SystemExit) as done:  # argparse's usage error, before any work
        main(["check", str(vcd), "--drive", "gecko-g202", "--gtkw", str(tmp_path / name)])
    assert done.value.code == 2
    err = capsys.readouterr().err
    assert "opens a" in err and "name it view.gtkw" in err and err.count("\n") == 1
    assert list(tmp_path.iterdir()) == []


def test_the_api_never_makes_a_save_file_its_own_companion(tmp_path: Path) -> None:
    """write_gtkw given a FILE.vcd save path: the companion is FILE-2.vcd, and a second write
    reuses it, replacing nothing else."""
    vcd = write_stepgen_vcd(tmp_path / "src.vcd")
    cap = open_capture(vcd)
    cap.format = "sr"  # as if read from a .sr: a VCD is written beside the save file
    report = run_check(cap, g202(), {"step": "STEP", "dir": "DIR"}, invert=["step"], pictures=True)
    save = tmp_path / "view.vcd"
    for _ in range(2):
        assert write_gtkw(report, save) == tmp_path / "view-2.vcd"
    assert sorted(p.name for p in tmp_path.glob("view*")) == ["view-2.vcd", "view.vcd"]
    assert f'[dumpfile] "{tmp_path / "view-2.vcd"}"' in save.read_text()
    assert [c.name for c in open_capture(tmp_path / "view-2.vcd").channels] == ["step", "dir"]
