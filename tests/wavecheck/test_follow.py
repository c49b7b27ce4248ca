"""wavecheck follow: commanded motion against the position decoded from a capture (issues 17, 19).

Documented facts checked:
- LinuxCNC's position-mode stepgen aims 1.5 servo periods behind its command (its follower's
  ``est_cmd = pos_cmd + vel_cmd·(match_time − 1.5·dt)``, reference §4.2): the least-squares lag
  of a simulated run is 1.5 ms at a 1 ms servo period, and with the command delayed by that the
  following error is what the model implies (bound below);
- latency moves every edge of the same invocations at most J later, so it adds at most v·J;
- a step removed from (added to) a capture is one step lost (extra) at the end, exit 1;
- motion's ferror = pos_cmd(previous cycle) − pos_fb(now) (pid reference §4.4): following the
  servo plant's encoder with the command delayed one servo period gives, at the command's
  samples, exactly the max following error stepgen's own loop reports.
"""

from __future__ import annotations

import json
import re
import shlex
from pathlib import Path

import numpy as np
import pytest

from stepgen.cli import main as stepgen_main
from stepgen.plant import quadrature_edges
from wavecheck.capture.open import open_capture
from wavecheck.capture.vcd.writer import VcdWire, write_vcd
from wavecheck.cli import main as wavecheck_main
from wavecheck.errors import UsageError
from wavecheck.follow import read_command

REPO = Path(__file__).resolve().parents[2]

# a move within stepgen's limits (LinuxCNC's advice: stepgen's maxvel/maxaccel above the joint's)
SCALE = 1000  # steps per unit
VEL, ACCEL = 12, 160  # units/s, units/s² of the move
P_S, SERVO_S = 25e-6, 1e-3
MOVE = [
    "--move", "1, pause 10ms, 0.2", "--move-vel", str(VEL), "--move-accel", str(ACCEL),
    "--position-scale", str(SCALE), "--maxvel", "15", "--maxaccel", "200", "--seed", "3",
]  # fmt: skip


def _simulate(tmp: Path, latency: str, name: str = "run") -> tuple[Path, Path]:
    vcd, cmd = tmp / f"{name}.vcd", tmp / f"{name}.csv"
    argv = ["simulate", *MOVE, "--latency", latency, "-o", str(vcd), "--command-out", str(cmd)]
    assert stepgen_main([*argv, "-q"]) == 0
    return vcd, cmd


def _follow(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, dict]:
    capsys.readouterr()
    code = wavecheck_main(["follow", *argv, "--format", "json"])
    return code, json.loads(capsys.readouterr().out)


@pytest.fixture(scope="module")
def runs(tmp_path_factory: pytest.TempPathFactory) -> dict[str, tuple[Path, Path]]:
    tmp = tmp_path_factory.mktemp("follow")
    return {lat: _simulate(tmp, lat, lat.replace(":", "-")) for lat in ("none", "uniform:11us")}


def test_command_out_is_the_motion(runs: dict[str, tuple[Path, Path]]) -> None:
    _, cmd = runs["none"]
    rows = cmd.read_text().splitlines()
    assert rows[0] == "time_s,position,steps"
    t, pos, steps = (
        np.array(c, float) for c in zip(*(r.split(",") for r in rows[1:]), strict=True)
    )
    assert np.all(np.diff(t) > 0) and t[1] == pytest.approx(SERVO_S)
    assert pos.max() == pytest.approx(1.0) and pos[-1] == pytest.approx(0.2)
    assert steps == pytest.approx(pos * SCALE)


@pytest.mark.parametrize("latency", ["none", "uniform:11us"])
def test_stepgen_run_follows_within_what_the_model_implies(
    runs: dict[str, tuple[Path, Path]], latency: str, capsys: pytest.CaptureFixture[str]
) -> None:
    vcd, cmd = runs[latency]
    j_s = 11e-6 if latency != "none" else 0.0
    code, raw = _follow(capsys, str(vcd), "--command", str(cmd), "--scale", str(SCALE))
    assert code == 0
    # the follower's design lag: 1.5 servo periods (measured 1.512 ms)
    assert raw["following_error"]["lag_s"] == pytest.approx(1.5 * SERVO_S, abs=0.05e-3)
    assert raw["following_error"]["max_abs"] > 10  # v·1.5 ms = 18 steps at cruise
    code, doc = _follow(
        capsys, str(vcd), "--command", str(cmd), "--column", "steps", "--delay", "1.5ms"
    )
    assert code == 0 and doc["end"]["lost_steps"] == 0
    fe = doc["following_error"]["max_abs"]
    # the bound: the wire position is a whole step (1), a step leaves at the make-pulses after
    # the accumulator reaches it (≤ one base period: v·P) and up to J late on the wire (v·J),
    # and the command is linear between servo samples while the follower's velocity changes
    # once per servo period (a·dt²/8). v = 12000 steps/s, a = 160000 steps/s².
    v, a = VEL * SCALE, ACCEL * SCALE
    bound = 1 + v * (P_S + j_s) + a * SERVO_S**2 / 8
    assert 0.5 <= fe <= bound, (fe, bound)  # a whole-step feedback shows at least half a step


def test_latency_adds_at_most_v_times_j(
    runs: dict[str, tuple[Path, Path]], capsys: pytest.CaptureFixture[str]
) -> None:
    # the same invocations make the same edges, each at most J later: the feedback is the
    # no-latency one delayed by 0 … J, so the error grows by at most v·J (0.132 steps)
    got = {}
    for lat, (vcd, cmd) in runs.items():
        _, doc = _follow(
            capsys, str(vcd), "--command", str(cmd), "--column", "steps", "--delay", "1.5ms"
        )
        got[lat] = doc["following_error"]["max_abs"]
    assert got["uniform:11us"] <= got["none"] + VEL * SCALE * 11e-6 + 1e-9


def _rewrite(src: Path, dst: Path, step: np.ndarray) -> None:
    cap = open_capture(src)
    wires = [
        VcdWire(c.name, c.initial, step if c.name == "step" else c.edges) for c in cap.channels
    ]
    write_vcd(dst, wires, timescale="1 ns", end=int(cap.end), scope="stepgen")


@pytest.mark.parametrize(("change", "lost"), [("remove", 1), ("add", -1)])
def test_a_step_removed_or_added_is_found(
    runs: dict[str, tuple[Path, Path]],
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    change: str,
    lost: int,
) -> None:
    vcd, cmd = runs["none"]
    edges = open_capture(vcd).channel("step").edges
    if change == "remove":  # the 300th pulse (forward, cruising): its rising and falling edge
        edited = np.delete(edges, [600, 601])
    else:  # a 1 µs pulse in the middle of the gap after it
        mid = (edges[601] + edges[602]) // 2
        edited = np.sort(np.concatenate([edges, [mid, mid + 1000]]))
    out = tmp_path / f"{change}.vcd"
    _rewrite(vcd, out, edited)
    argv = [str(out), "--command", str(cmd), "--column", "steps", "--delay", "1.5ms"]
    code, doc = _follow(capsys, *argv)
    assert code == 1 and doc["end"]["lost_steps"] == lost and doc["verdict"] == "fail"
    assert doc["following_error"]["max_abs"] > 1.2  # the error carries the step from then on
    capsys.readouterr()
    assert wavecheck_main(["follow", *argv]) == 1
    word = "LOST" if lost > 0 else "EXTRA"
    assert f"1 {word}" in capsys.readouterr().out.replace("step(s) ", "")


def test_servo_encoder_feedback_matches_the_loops_ferror(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    vcd, cmd = tmp_path / "servo.vcd", tmp_path / "servo.csv"
    argv = [
        "simulate", "--pid", "--plant", "servo", "--inertia", "2e-4", "--viscous", "0.02",
        "--load", "0.05", "--pgain", "19.76", "--igain", "188.6", "--dgain", "0.0485",
        "--move", "0.5, pause 100ms, 0", "--move-vel", "5", "--move-accel", "50",
        "--encoder-counts", "2000", "-o", str(vcd), "--command-out", str(cmd),
    ]  # fmt: skip
    assert stepgen_main(argv) == 0
    m = re.search(r"following error: max (\S+) units at (\S+) s", capsys.readouterr().out)
    assert m
    loop_max, loop_at = float(m.group(1)), float(m.group(2))
    code, doc = _follow(
        capsys, str(vcd), "--command", str(cmd), "--map", "phase-A=phase-A,phase-B=phase-B",
        "--scale", "2000", "--delay", "1ms",
    )  # fmt: skip
    assert code == 0 and "encoder" in doc["feedback"]
    s = doc["following_error"]["at_command_samples"]
    assert s["max_abs"] / 2000 == pytest.approx(loop_max, abs=1e-9)
    assert s["at_s"] == pytest.approx(loop_at)
    # between samples the command moves on while the encoder lags: larger, by at most v·dt
    assert s["max_abs"] <= doc["following_error"]["max_abs"] <= s["max_abs"] + 5 * 2000 * 1e-3
    assert doc["end"]["lost_steps"] is None  # a servo's residual is not lost steps


def test_step_dir_command_with_an_encoder(
    runs: dict[str, tuple[Path, Path]], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # a servo drive's STEP/DIR input as the command, its encoder (here: the steps 2 ms later,
    # 2 counts per step) as the feedback, both in one capture
    vcd, _ = runs["none"]
    cap = open_capture(vcd)
    from wavecheck.steps.decode import decode
    from wavecheck.steps.interface import build_interface

    ev = decode(build_interface(cap, {"step": "step", "dir": "dir"}), 0)
    t = np.repeat(ev.ticks + 2_000_000, 2) + np.tile([0, 500], len(ev.ticks))
    counts = np.repeat(ev.position * 2, 2) - np.tile([1, 0], len(ev.ticks)) * np.repeat(
        ev.direction, 2
    )
    edges, init = quadrature_edges(t, counts)
    wires = [VcdWire(c.name, c.initial, c.edges) for c in cap.channels]
    wires += [VcdWire(p, init[p], edges[p]) for p in ("phase-A", "phase-B")]
    out = tmp_path / "both.vcd"
    write_vcd(out, wires, timescale="1 ns", end=int(cap.end) + 3_000_000, scope="drive")
    code, doc = _follow(
        capsys, str(out), "--map", "step=step,dir=dir,phase-A=phase-A,phase-B=phase-B",
        "--command-scale", "1000", "--scale", "2000",
    )  # fmt: skip
    assert code == 0 and "step=step, dir=dir" in doc["command"]
    assert doc["following_error"]["lag_s"] == pytest.approx(2e-3, rel=0.02)
    assert doc["end"]["difference"] == 0


@pytest.mark.parametrize(
    ("text", "kwargs", "times_ns", "values", "unit"),
    [
        ("time_s,position\n0,0\n0.001,0.5\n", {}, [0, 1_000_000], [0, 0.5], "units"),
        ("# c\ntime_ms,steps\n0,0\n1.5,3\n", {}, [0, 1_500_000], [0, 3], "counts"),
        ("t_us,x,y_counts\n0,9,1\n2,9,2\n", {"column": "y_counts"}, [0, 2000], [1, 2], "counts"),
        ("0 12 0.5\n1 13 0.25\n3 15 0\n", {"tagged": True}, [0, 1, 3], [12, 13, 15], "counts"),
        ("0.5 1\n0.75 2\n", {"column": "2"}, [0, 1], [1, 2], "counts"),
        ("0.5 1\n0.75 2\n", {}, [0, 1], [0.5, 0.75], "units"),
    ],
)
def test_command_files(
    tmp_path: Path, text: str, kwargs: dict, times_ns: list, values: list, unit: str
) -> None:
    from fractions import Fraction

    f = tmp_path / "c.txt"
    f.write_text(text)
    hal = "time" not in text and "t_" not in text
    c = read_command(f, sample_period_s=Fraction(1, 1000) if hal else None, **kwargs)
    assert (c.times * c.unit_ns).tolist() == [x * (10**6 if hal else 1) for x in times_ns]
    assert c.position.tolist() == values and c.unit == unit


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("0,0\n0.001,0.5\n", "no time column with its unit"),
        ("time,position\n0,0\n", "no time column with its unit"),
        ("time_s,position\n0,0\n1,x\n", "line 3: expected numbers"),
        ("time_s,position\n1,0\n0,1\n", "line 3: time goes backwards"),
        ("time_s,position\n0,nan\n", "line 2: nan is not a finite number"),
        ("time_s\n0\n", "no position column"),
        ("", "no rows"),
    ],
)
def test_bad_command_files(tmp_path: Path, text: str, message: str) -> None:
    f = tmp_path / "c.csv"
    f.write_text(text)
    with pytest.raises(UsageError, match=message):
        read_command(f)


def test_units_command_needs_a_scale(
    runs: dict[str, tuple[Path, Path]], capsys: pytest.CaptureFixture[str]
) -> None:
    vcd, cmd = runs["none"]
    assert wavecheck_main(["follow", str(vcd), "--command", str(cmd)]) == 2
    assert "give --scale" in capsys.readouterr().err
    assert wavecheck_main(["follow", str(vcd), "--command", str(cmd), "--delay", "2"]) == 2
    assert "give a unit" in capsys.readouterr().err


def test_plot(runs: dict[str, tuple[Path, Path]], tmp_path: Path) -> None:
    vcd, cmd = runs["uniform:11us"]
    png = tmp_path / "f.png"
    argv = ["follow", str(vcd), "--command", str(cmd), "--column", "steps", "--plot", str(png)]
    assert wavecheck_main(argv) == 0
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 10_000


def test_readme_follow_block(tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys) -> None:
    """README "Following error": the commands run as written and report what it says."""
    from tests.doc_pages import marked

    monkeypatch.chdir(tmp_path)
    for line in marked("follow").strip().splitlines():
        argv = shlex.split(line)
        main = stepgen_main if argv[0] == "stepgen" else wavecheck_main
        assert main(argv[1:]) == 0, line
    out = capsys.readouterr().out
    assert "no step lost or extra" in out and "as a lag" in out
    assert (tmp_path / "follow.png").stat().st_size > 0
