"""A report draws from small windows of the signals what every edge would draw.

The oracle is the one-block report drawn from every edge of the capture (its windows replaced by
the whole signals). On the corpus captures of the engine's tests and at block sizes from one event
up, the report drawn from its windows gives the same ``--plot`` places, the same traces in each
timing diagram, the same titles (diagrams and histograms), the same GTKWave save file (markers,
view; the dump path and the windows note aside) and the same neighbouring edges of each marked
place. The windows stay bounded when every interval fails, and a window cut by its edge cap says
so.
"""

from __future__ import annotations

import re
import subprocess
import sys
from dataclasses import replace
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest

from tests.conftest import shared_capture
from tests.wavecheck.engine.corpus import GOLDEN, GOLDEN_CASES, ROOT, engine_check
from wavecheck.capture.blocks import WHOLE, MemorySource
from wavecheck.capture.edges import Capture, Channel
from wavecheck.capture.open import open_capture
from wavecheck.drives.datasheet import Drive, Figure
from wavecheck.drives.library import load_drive
from wavecheck.engine.outcome import Report
from wavecheck.engine.windows import PLACES_PER_RULE, SIDE_EDGES, WindowKeeper
from wavecheck.report.gtkw import MAX_MARKERS, _neighbours, write_gtkw
from wavecheck.report.plot import (
    MAX_PLACES,
    choose_places,
    hist_title,
    place_title,
    place_traces,
)
from wavecheck.steps.interface import build_interface
from wavecheck.steps.mapping import AxisMap
from wavecheck.timebase import Timebase

SMOOTHIE = "sigrok-dumps/stepper_motor/smoothieware/smoothieware_snippet.sr"
GRBL = "sigrok-dumps/stepper_motor/grbl_cnc/grbl_cnc_1.sr"


def _drive(limits: dict[str, int], interface: str = "step-dir") -> Drive:
    fig = {k: Figure(Fraction(v), "test", "datasheet") for k, v in limits.items()}
    return Drive("t", "test drive", Path("t.toml"), "user", interface, "rising", fig, None)  # type: ignore[arg-type]


def _gtkw(report: Report, folder: Path) -> str:
    """The save file written for ``report`` in ``folder``, its paths and the streamed note out."""
    folder.mkdir(parents=True, exist_ok=True)
    write_gtkw(report, folder / "w.gtkw")
    text = (folder / "w.gtkw").read_text()
    return "\n".join(
        line
        for line in text.splitlines()
        if not line.startswith(("[dumpfile]", "[savefile]", "[*] only "))
    )


def _same_drawings(whole: Report, streamed: Report, tmp_path: Path) -> None:
    assert streamed.windows is not None and whole.windows is None
    for n in (MAX_PLACES, 4 * MAX_MARKERS):
        assert choose_places(streamed, n) == choose_places(whole, n)
    for k, place in enumerate(choose_places(whole, MAX_PLACES), 1):
        assert place_title(streamed, place, k) == place_title(whole, place, k)
        a, b = place_traces(whole, place), place_traces(streamed, place)
        assert a.keys() == b.keys()
        for role in a:
            ts = a[role][0][1:-1]
            if max(np.sum(ts < place.start_tick), np.sum(ts >= place.start_tick)) > SIDE_EDGES:
                assert streamed.windows.cut  # more edges than a window keeps: cut, and said
                continue
            assert np.array_equal(a[role][0], b[role][0]), (place, role)
            assert np.array_equal(a[role][1], b[role][1]), (place, role)
    for place in choose_places(whole, 4 * MAX_MARKERS)[:MAX_MARKERS]:
        assert _neighbours(streamed, place.start_tick) == _neighbours(whole, place.start_tick)
    titles = [hist_title(r) for r in whole.rules if r.limit_ns is not None and r.checked]
    assert titles == [hist_title(r) for r in streamed.rules if r.limit_ns is not None and r.checked]
    # GTKWave: the capture's own VCD, and a capture of another format (a VCD written beside)
    assert _gtkw(streamed, tmp_path / "s") == _gtkw(whole, tmp_path / "w")
    sr = {"capture": replace(whole.capture, format="sr")}
    w2, s2 = replace(whole, **sr), replace(streamed, capture=replace(streamed.capture, format="sr"))
    assert _gtkw(s2, tmp_path / "s2") == _gtkw(w2, tmp_path / "w2")


def _both(
    cap: Capture, axes: list[AxisMap], drives: dict, block: int, **kw: object
) -> list[tuple[Report, Report]]:
    """(the one-block report drawing every edge, the report of ``block``-edge blocks) per axis."""
    one = engine_check(MemorySource(cap), axes, drives, WHOLE, **kw)
    streamed = engine_check(MemorySource(cap, block), axes, drives, block, **kw)
    every = [
        replace(r, windows=None, interface=build_interface(cap, r.mapping, r.inverted))
        for r in one.axes
    ]
    return list(zip(every, streamed.axes, strict=True))


@pytest.mark.parametrize("block", [1, 2, 7, 64, 10**9])
@pytest.mark.parametrize(("name", "drive", "typ"), GOLDEN_CASES)
def test_golden_traces_draw_the_same(
    name: str, drive: str, typ: int | None, block: int, tmp_path: Path
) -> None:
    cap = open_capture(GOLDEN / name)
    types = {None: typ} if typ is not None else None
    for whole, streamed in _both(cap, [AxisMap(None, {})], {None: load_drive(drive)}, block,
                                 step_types=types):  # fmt: skip
        _same_drawings(whole, streamed, tmp_path)


def test_every_phase_rule_draws_the_same(tmp_path: Path) -> None:
    cap = open_capture(GOLDEN / "user-type15-velocity.vcd")
    drive = _drive({"state_hold": 120_000}, "phases")
    for block in (1, 3, 50):
        for whole, streamed in _both(cap, [AxisMap(None, {})], {None: drive}, block,
                                     step_types={None: 15}, user_table=(1, 3, 2, 6, 4, 5)):  # fmt: skip
            _same_drawings(whole, streamed, tmp_path / str(block))


@pytest.mark.parametrize("block", [1, 97, 4096])
def test_real_sr_with_hundreds_of_violations(block: int, tmp_path: Path) -> None:
    cap = open_capture(shared_capture(SMOOTHIE))
    axes = [AxisMap(None, {"step": "5", "dir": "6"})]
    for whole, streamed in _both(cap, axes, {None: load_drive("gecko-g202")}, block):
        assert whole.total_violations > 4 * MAX_MARKERS  # more than the markers can show
        _same_drawings(whole, streamed, tmp_path)


def test_real_grbl_capture_two_axes(tmp_path: Path) -> None:
    cap = open_capture(shared_capture(GRBL))
    names = [c.name for c in cap.channels]
    axes = [
        AxisMap("x", {"step": names[0], "dir": names[1]}),
        AxisMap("y", {"step": names[2], "dir": names[3]}),
    ]
    drive = load_drive("gecko-g202")
    for block in (997, 1 << 16):
        for k, (whole, streamed) in enumerate(_both(cap, axes, {"x": drive, "y": drive}, block)):
            _same_drawings(whole, streamed, tmp_path / f"{block}-{k}")


# -- the command line ----------------------------------------------------------------------------
def _cli(tmp_path: Path, capture: Path, *args: str) -> tuple[str, str, str]:
    tmp_path.mkdir(parents=True, exist_ok=True)
    out = [f"--gtkw={tmp_path / 'w.gtkw'}", f"--plot={tmp_path / 'p.png'}",
           f"--html={tmp_path / 'r.html'}"]  # fmt: skip
    p = subprocess.run(
        [sys.executable, "-m", "wavecheck", "check", str(capture), *args, *out, "-q"],
        capture_output=True, text=True, cwd=ROOT,
    )  # fmt: skip
    assert p.returncode == 1 and not p.stderr, p.stderr
    html = re.sub(r'src="data:image/png;base64,[^"]*"', "", (tmp_path / "r.html").read_text())
    return (tmp_path / "w.gtkw").read_text(), html, (tmp_path / "p.png").read_bytes()[:8].hex()


def test_cli_streams_plot_gtkw_and_html(tmp_path: Path) -> None:
    sr = shared_capture(SMOOTHIE)
    args = ["--drive", "gecko-g202", "--map", "step=5,dir=6"]
    gw, hw, pw = _cli(tmp_path / "w", sr, *args, "--no-stream")  # one window
    whole_vcd = (tmp_path / "w" / "w.vcd").read_text()
    assert "window(s) around the worst places hold edges" in whole_vcd.splitlines()[0]
    for block in ("1", "262144"):
        gs, hs, ps = _cli(tmp_path / block, sr, *args, "--block-edges", block)
        strip = re.compile(r"^\[(dumpfile|savefile)\].*$", re.M)
        assert strip.sub("", gs) == strip.sub("", gw)
        assert hs == hw and ps == pw == "89504e470d0a1a0a"  # the same page; a PNG each
        vcd = (tmp_path / block / "w.vcd").read_text()
        assert vcd.splitlines()[1:] == whole_vcd.splitlines()[1:]


# -- bounded memory -------------------------------------------------------------------------------
def _pulses(steps: int, dir_at: int | None = None) -> Capture:
    """1-tick STEP pulses every 10 ticks (100 ns ticks), DIR changing at ``dir_at``."""
    rise = np.arange(steps, dtype=np.int64) * 10 + 5
    step = np.stack([rise, rise + 1], axis=1).ravel()
    d = np.array([] if dir_at is None else [dir_at], dtype=np.int64)
    chans = [Channel("step", 0, 0, step), Channel("dir", 1, 0, d)]
    return Capture("p", "vcd", Timebase(Fraction(1, 10**7)), 0, None, 0, steps * 10 + 20, chans)


def _held(k: WindowKeeper) -> tuple[int, int]:
    """(windows, edges) a keeper holds."""
    edges = sum(len(e) for e in k.back.values())
    for w in k.windows.values():
        edges += sum(len(p) for s in w.sides.values() for p in s.pieces)
    return len(k.windows), edges


def _peak(
    monkeypatch: pytest.MonkeyPatch, cap: Capture, drive: Drive, block: int
) -> tuple[int, int]:
    peak = [0, 0]
    update = WindowKeeper.update

    def watched(self: WindowKeeper, *a: object) -> None:
        update(self, *a)  # type: ignore[arg-type]
        peak[:] = [max(x, y) for x, y in zip(peak, _held(self), strict=True)]

    monkeypatch.setattr(WindowKeeper, "update", watched)
    report = engine_check(MemorySource(cap, block), [AxisMap(None, {})], {None: drive},
                          block).axes[0]  # fmt: skip
    assert report.rule("step_high").violations == len(cap.channels[0].edges) // 2  # type: ignore[union-attr]
    return peak[0], peak[1]


@pytest.mark.parametrize("block", [1, 64, 5000])
def test_windows_stay_bounded_when_every_interval_fails(
    monkeypatch: pytest.MonkeyPatch, block: int
) -> None:
    drive = _drive({"step_high": 500, "step_low": 2000, "step_period": 3000})  # all fail
    short = _peak(monkeypatch, _pulses(5_000), drive, block)
    long = _peak(monkeypatch, _pulses(20_000), drive, block)
    assert short == long  # four times the capture, the same windows and edges held
    windows, edges = long
    assert windows <= 3 * (PLACES_PER_RULE + 1)
    assert edges <= 3 * (PLACES_PER_RULE + 1) * 2 * 12 + 2 * (SIDE_EDGES + 2)


def test_a_window_with_too_many_edges_is_cut_and_says_so(tmp_path: Path) -> None:
    # DIR changes 1 tick before a step: dir_setup of 10 ms keeps 2 × 10 ms each side, 20k edges
    cap = _pulses(3_000, dir_at=15_004)
    drive = _drive({"dir_setup": 10_000_000})
    (whole, streamed), = _both(cap, [AxisMap(None, {})], {None: drive}, 256)  # fmt: skip
    assert streamed.windows is not None and streamed.windows.cut == 1
    assert f"cut to {SIDE_EDGES} edges a side" in streamed.windows.note
    step = streamed.traces["step"].edges
    assert len(step) <= 2 * SIDE_EDGES + 2
    near = whole.traces["step"].edges
    near = near[(near > 15_004 - 1000) & (near < 15_004 + 1000)]  # around the place: every edge
    assert np.isin(near, step).all()
    save = tmp_path / "cut.gtkw"
    write_gtkw(replace(streamed, capture=replace(streamed.capture, format="sr")), save)
    assert f"cut to {SIDE_EDGES} edges a side" in save.read_text()
