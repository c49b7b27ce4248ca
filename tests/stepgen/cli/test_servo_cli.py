"""``stepgen simulate --pid`` and ``stepgen tune`` on the command line: their outputs (the servo
plant's A/B quadrature read back by wavecheck, ``.sr``, ``tune --html``) and their error paths
(exit 2, one line naming the option and the value, nothing written)."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

import wavecheck
from stepgen.cli import main
from tests.engine_probe import run_check
from wavecheck.capture.open import open_capture

# a servo whose loop is stable with P = 20, I = 100 (test_servo_loop's "stiff"-like plant)
SERVO = ["--pid", "--plant", "servo", "--pgain", "20", "--igain", "100"]


def _vcd_vector(path: Path, name: str) -> tuple[np.ndarray, np.ndarray]:
    """(times, values) of a VCD integer variable, read from the text (wavecheck reads wires)."""
    text = path.read_text()
    ident = re.search(rf"\$var integer \d+ (\S+) {name} \$end", text)
    assert ident
    t, times, values = 0, [], []
    for line in text.splitlines():
        if line.startswith("#"):
            t = int(line[1:])
        elif line.startswith("b") and line.endswith(" " + ident.group(1)):
            times.append(t)
            values.append(int(line[1:].split()[0], 2))
    return np.asarray(times), np.asarray(values)


def test_servo_quadrature_decodes_back_to_the_encoder_counts(tmp_path: Path) -> None:
    """The encoder's phase-A/phase-B in the VCD follow stepgen type 2's table, so wavecheck's
    type 2 decoder (the one that reads stepgen's quadrature) gives back, step by step, the
    ``counts`` the plant recorded beside them — forward and reverse (the move goes out to 1
    and back to 0.3)."""
    out = tmp_path / "q.vcd"
    code = main(
        [
            "simulate",
            *SERVO,
            "--encoder-counts",
            "1000",
            "--move",
            "1, 0.3",
            "--move-vel",
            "2",
            "--move-accel",
            "40",
            "-q",
            "-o",
            str(out),
        ]
    )
    assert code == 0
    t_counts, v_counts = _vcd_vector(out, "counts")
    steps = run_check(open_capture(out), "gecko-g202", step_type_number=2).steps
    assert steps.forward > 900 and steps.reverse > 600 and steps.unknown == 0
    assert len(steps.sequence_errors) == 0
    assert (
        steps.ticks.tolist() == t_counts[1:].tolist()
    )  # one step per count change (t = 0 is the start)
    assert steps.position.tolist() == v_counts[1:].tolist()
    assert steps.final_position == v_counts[-1]
    assert abs(v_counts[-1] - 300) < 10  # near 0.3 units at 1000 counts/unit, still settling


def test_servo_sr_decodes_to_the_same_counts(tmp_path: Path) -> None:
    """The .sr of a slow move: the edges lie on the sub-step grid (125 µs here, 8 kHz), exact."""
    vcd, sr = tmp_path / "q.vcd", tmp_path / "q.sr"
    args = [
        *SERVO,
        "--encoder-counts",
        "100",
        "--move",
        "1, 0.3",
        "--move-vel",
        "0.5",
        "--move-accel",
        "10",
        "-q",
    ]
    assert main(["simulate", *args, "-o", str(vcd)]) == 0
    assert main(["simulate", *args, "-o", str(sr)]) == 0
    a = run_check(open_capture(vcd), "gecko-g202", step_type_number=2).steps
    b = run_check(open_capture(sr), "gecko-g202", step_type_number=2).steps
    cap = open_capture(sr)
    assert [c.name for c in cap.channels] == ["phase-A", "phase-B"]
    assert b.position.tolist() == a.position.tolist() and b.final_position == 30
    tick_ns = cap.timebase.tick_s * 10**9
    assert (b.ticks * tick_ns).tolist() == a.ticks.tolist()  # the same instants, exactly


def test_stepgen_loop_writes_sr(tmp_path: Path) -> None:
    """pid + stepgen written as .sr: the STEP edges of the closed loop, read back by wavecheck."""
    vcd, sr = tmp_path / "l.vcd", tmp_path / "l.sr"
    args = [
        "--pid",
        "--move",
        "1",
        "--move-vel",
        "5",
        "--move-accel",
        "100",
        "--position-scale",
        "200",
        "--maxvel",
        "10",
        "--maxaccel",
        "200",
        "-q",
    ]
    assert main(["simulate", *args, "-o", str(vcd)]) == 0
    assert main(["simulate", *args, "-o", str(sr)]) == 0
    steps = [wavecheck.check(p, "gecko-g202").steps for p in (vcd, sr)]
    assert steps[0].final_position == steps[1].final_position == 200  # 1 unit at 200 steps/unit


def test_diverged_loop_fails_and_says_so(tmp_path: Path, capsys) -> None:
    """Absurd but finite gains are a simulation, not a usage error: the loop stops when it
    diverges, the check fails (exit 1) and the VCD is still written."""
    out = tmp_path / "d.vcd"
    code = main(
        [
            "simulate",
            "--pid",
            "--plant",
            "servo",
            "--encoder-counts",
            "1000",
            "--pgain",
            "1e9",
            "--position",
            "1",
            "--duration",
            "200ms",
            "-o",
            str(out),
        ]
    )
    text = capsys.readouterr()
    assert code == 1 and "the loop diverged: stopped after" in text.out
    assert "following-error check FAIL" in text.out and out.exists()


def test_tune_html_is_self_contained(tmp_path: Path) -> None:
    """--html: one page, every stage a row and an inline PNG of its response, the final gains as
    INI/HAL lines; no request of its own (no http, no src other than data:)."""
    page = tmp_path / "t.html"
    code = main(
        [
            "tune",
            "--inertia",
            "2e-4",
            "--viscous",
            "0.02",
            "--load",
            "0.05",
            "--settle",
            "300ms",
            "--html",
            str(page),
        ]
    )
    assert code == 0
    text = page.read_text()
    rows = re.findall(r'<tr><td><a href="#stage-(\d+)">', text)
    imgs = re.findall(r'<img alt="[^"]*" src="data:image/png;base64,([A-Za-z0-9+/=]+)">', text)
    assert len(rows) == len(imgs) >= 4
    assert "1 oscillation" in text and "final" in text and "setp pid.0.Pgain [JOINT_0]P" in text
    outside = re.sub(r"data:image/png;base64,[A-Za-z0-9+/=]+", "", text)
    assert "http" not in outside and not re.search(r'(src|href)="(?!data:|#)', text)
    import base64

    assert all(base64.b64decode(i).startswith(b"\x89PNG") for i in imgs)


# --- error paths: exit 2, one line, nothing written --------------------------------------------

SIM = ["simulate", "--pid", "--position", "1", "--duration", "10ms"]
TUNE = ["tune", "--window", "200ms", "--settle", "100ms"]


@pytest.mark.parametrize(
    "argv,message",
    [
        ([*SIM, "--pgain", "nan"], r"argument --pgain: 'nan': nan/inf is not a number here"),
        ([*SIM, "--igain", "1e999"], r"argument --igain: '1e999': out of range"),
        ([*SIM, "--pgain", "fast"], r"argument --pgain: 'fast': not a number"),
        ([*SIM, "--ferror", "-1"], r"--ferror -1\.0 must be a number > 0"),
        ([*SIM, "--min-ferror", "nan"], r"argument --min-ferror: 'nan': nan/inf"),
        ([*SIM, "--joint-max-velocity", "0"], r"--joint-max-velocity 0\.0 must be a number > 0"),
        ([*SIM, "--servo-period", "1"], r"--servo-period 1: give a unit"),
        ([*SIM, "--servo-period", "0s"], r"--servo-period 0s: must be > 0"),
        ([*SIM, "--plant", "servo", "--inertia", "0"], r"--inertia 0\.0 is out of range"),
        (
            [*SIM, "--plant", "servo", "--encoder-counts", "-5"],
            r"--encoder-counts -5\.0 is out of range",
        ),
        ([*SIM, "--plant", "servo", "--viscous", "inf"], r"argument --viscous: 'inf': nan/inf"),
        ([*TUNE, "--servo-period", "1"], r"--servo-period '1': .*unit"),
        ([*TUNE, "--servo-period", "10ns"], r"--servo-period 10ns: below 1 us"),
        ([*TUNE, "--settle", "5"], r"--settle '5': .*unit"),
        ([*TUNE, "--settle", "2s"], r"--settle 2 s must be > 0 and shorter than --window 0\.2 s"),
        ([*TUNE, "--window", "1000s"], r"--window 1000 s is 1e\+06 servo periods per response"),
        ([*TUNE, "--step", "0"], r"--step 0\.0 must be a nonzero number"),
        ([*TUNE, "--step", "nan"], r"argument --step: 'nan': nan/inf"),
        ([*TUNE, "--band", "1.5"], r"--band 1\.5 must be between 0 and 1"),
        ([*TUNE, "--p-start", "0"], r"--p-start 0\.0 must be a number > 0"),
        ([*TUNE, "--p-start=-inf"], r"argument --p-start: '-inf': nan/inf"),
        ([*TUNE, "--joint", "-1"], r"--joint -1 must be 0 or more"),
        (
            [*TUNE, "--ff-velocity", "0", "--plant", "stepgen"],
            r"--ff-velocity 0\.0 must be a speed > 0",
        ),
        ([*TUNE, "--inertia", "-1"], r"--inertia -1\.0 is out of range"),
        (
            [*TUNE, "--plant", "stepgen", "--position-scale", "nan"],
            r"argument --position-scale: 'nan': nan/inf",
        ),
    ],
)
def test_errors_exit_2_in_one_line(tmp_path: Path, capsys, argv: list[str], message: str) -> None:
    outputs = {
        "simulate": ["-o", str(tmp_path / "o.vcd")],
        "tune": ["--html", str(tmp_path / "o.html")],
    }
    try:
        code = main([*argv, *outputs[argv[0]]])
    except SystemExit as exc:  # argparse's own refusals (a value that is not a number)
        code = exc.code
    err = capsys.readouterr().err.strip()
    assert code == 2
    assert len(err.splitlines()) == 1 and re.search(message, err), err
    assert not list(tmp_path.iterdir())  # nothing written
