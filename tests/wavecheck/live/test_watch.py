"""``wavecheck watch`` against a real sigrok-cli driver: the ``demo`` device (issue 14, "Live from
a logic analyzer").

Facts used (sigrok-cli 0.7.2, ``../shared/reference/sigrok.md`` §(a)): the demo device runs at
its sample rate in real time, 200 kHz unless told; with ``-g Logic --config pattern=incremental``
its 8 logic channels carry a counter, so D_k toggles every 2**k samples: D3 is a step train of
8-sample (40 us) pulses every 16 samples, rising at samples 8, 24, …, and D6 (toggling every 64
samples, at D3's falling edges) a DIR line 8 samples before and after the nearest rising edge.
A capture of the same pattern to a file (``sigrok-cli --samples N -o X.sr``) is the reference.
"""

from __future__ import annotations

import contextlib
import json
import os
import shutil
import signal
import subprocess
import sys
import time
import zipfile
from fractions import Fraction
from pathlib import Path

import pytest

from tests.bounds import HANG_GUARD_S

pytestmark = pytest.mark.skipif(
    shutil.which("sigrok-cli") is None, reason="needs Debian's sigrok-cli (make system-deps)"
)

DEMO = ["--driver", "demo:analog_channels=0", "--channel-group", "Logic",
        "--config", "pattern=incremental"]  # fmt: skip
CHECK = ["--drive", "drv8825", "--map", "step=D3,dir=D6"]
RATE = 200_000


def _wavecheck(*args: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "wavecheck", *args],
        capture_output=True, text=True, cwd=cwd, timeout=120,
    )  # fmt: skip


def _start(*args: str, cwd: Path) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [sys.executable, "-m", "wavecheck", "watch", *DEMO, *CHECK, "--status", "always", *args],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=cwd,
    )  # fmt: skip


def _first_status(proc: subprocess.Popen[str]) -> str:
    """Wait for a status line with steps in it (the watch is checking)."""
    assert proc.stderr is not None
    deadline = time.monotonic() + HANG_GUARD_S  # a guard against a hang (tests/bounds.py)
    while time.monotonic() < deadline:
        line = proc.stderr.readline()
        if " steps" in line and not line.startswith("[   0.0"):
            return line
    raise AssertionError("no status line")


def _rules(report: dict[str, object]) -> dict[str, object]:
    return {k: v for k, v in report.items() if k != "capture"}


def test_watch_reports_the_figures_of_a_file_capture_of_the_same_pattern(tmp_path: Path) -> None:
    live = _wavecheck("watch", *DEMO, *CHECK, "--time", "1s", "--format", "json",
                      "--save", "kept.sr", cwd=tmp_path)  # fmt: skip
    assert live.returncode == 0, live.stderr
    got = json.loads(live.stdout)
    subprocess.run(
        ["sigrok-cli", "-d", "demo:analog_channels=0", "-g", "Logic", "--config",
         "pattern=incremental", "--samples", str(RATE), "-o", "file.sr"],
        check=True, cwd=tmp_path, capture_output=True,
    )  # fmt: skip
    ref = json.loads(
        _wavecheck("check", "file.sr", *CHECK, "--format", "json", cwd=tmp_path).stdout
    )
    assert _rules(got) == _rules(ref)
    assert got["capture"]["duration_s"] == 1 and got["capture"]["samplerate_hz"] == RATE
    # the known pulse train: (200000 + 7) // 16 rising edges of D3, each 40 us high and low
    assert got["steps"]["count"] == (RATE + 7) // 16
    by = {r["id"]: r for r in got["rules"]}
    assert by["step_high"]["min_measured_ns"] == by["step_low"]["min_measured_ns"] == 40_000
    assert by["dir_setup"]["min_measured_ns"] == by["dir_hold"]["min_measured_ns"] == 40_000
    # --save kept the stream: the same bytes as sigrok-cli's own file of the pattern
    kept = json.loads(
        _wavecheck("check", "kept.sr", *CHECK, "--format", "json", cwd=tmp_path).stdout
    )
    assert _rules(kept) == _rules(got)
    with zipfile.ZipFile(tmp_path / "kept.sr") as a, zipfile.ZipFile(tmp_path / "file.sr") as b:

        def logic(z: zipfile.ZipFile) -> bytes:
            names = sorted((n for n in z.namelist() if n.startswith("logic-1-")),
                           key=lambda n: int(n.rsplit("-", 1)[1]))  # fmt: skip
            return b"".join(z.read(n) for n in names)

        assert logic(a) == logic(b)


def test_require_ends_the_watch_with_exit_4_and_why(tmp_path: Path) -> None:
    """``--require`` as ``check``'s (issue 26): every DRV8825 rule is decided on the demo's
    pattern; enable_setup, which the DRV8825 states no figure for, is not."""
    live = _wavecheck("watch", *DEMO, *CHECK, "--time", "200ms", "--require", "all",
                      "--require", "enable_setup", cwd=tmp_path)  # fmt: skip
    assert live.returncode == 4, live.stderr
    no_figure = "enable_setup not checked: drive drv8825 states no figure"
    assert live.stdout.splitlines()[:2] == [
        f"verdict: NOT DECIDED (exit 4: required {no_figure}); the rules checked: "
        f"PASS ({no_figure})",
        f"required but not decided: {no_figure}",
    ]


def test_ctrl_c_ends_with_the_complete_report_of_what_arrived(tmp_path: Path) -> None:
    proc = _start("--format", "json", cwd=tmp_path)
    _first_status(proc)
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=60)
    assert proc.returncode == 0, err
    report = json.loads(out)
    n = Fraction(str(report["capture"]["duration_s"])) * RATE
    assert n.denominator == 1 and n > RATE // 10
    assert report["steps"]["count"] == (int(n) + 7) // 16  # every sample that came was checked
    assert "(interrupted)" in err


def test_sigrok_cli_killed_gives_exit_2_with_what_was_checked(tmp_path: Path) -> None:
    proc = _start(cwd=tmp_path)
    _first_status(proc)
    children = subprocess.run(
        ["pgrep", "-P", str(proc.pid), "sigrok-cli"], capture_output=True, text=True
    ).stdout.split()
    assert len(children) == 1
    os.kill(int(children[0]), signal.SIGKILL)
    out, err = proc.communicate(timeout=60)
    assert proc.returncode == 2
    assert out.startswith("verdict: PASS") and "steps:" in out  # the report of what arrived
    last = err.strip().splitlines()[-1]
    assert last.startswith("wavecheck: error:") and "killed by SIGKILL" in last
    assert "Traceback" not in err


def test_stop_on_fail_and_snippets_around_each_violation(tmp_path: Path) -> None:
    """--limit dir_setup=60us makes every DIR change fail by 20 us (it has 40 us)."""
    run = _wavecheck("watch", *DEMO, *CHECK, "--limit", "dir_setup=60us", "--stop-on-fail",
                     "--snippets", "snips", "--snippet-window", "200us", "--max-snippets", "3",
                     "--format", "json", cwd=tmp_path)  # fmt: skip
    assert run.returncode == 1, run.stderr
    assert "(stop on fail)" in run.stderr
    report = json.loads(run.stdout)
    assert {r["id"]: r["min_margin_ns"] for r in report["rules"]}["dir_setup"] == -20_000
    snippets = sorted((tmp_path / "snips").iterdir())
    assert len(snippets) == 3
    # the report says how many violations were seen, and why most have no snippet of their own
    seen = sum(r["violations"] for r in report["rules"])
    summary = f"snippets: 3 file(s) in snips for {seen} violation(s) seen ("
    assert summary in run.stderr and summary in json.dumps(report)
    assert "beyond --max-snippets 3" in run.stderr
    for snip in snippets:
        meta = zipfile.ZipFile(snip).read("metadata").decode()
        first = int(meta.split("first_sample=")[1].split()[0])
        # issue 27: the snippet carries its drive, map and step type: no options needed
        check = json.loads(_wavecheck("check", str(snip), "--format", "json",
                                      cwd=tmp_path).stdout)  # fmt: skip
        given = json.loads(_wavecheck("check", str(snip), *CHECK, "--limit", "dir_setup=60us",
                                      "--format", "json", cwd=tmp_path).stdout)  # fmt: skip
        assert check == given
        v = check["violations"][0]
        assert v["rule"] == "dir_setup" and v["margin_ns"] == -20_000
        # the name is the violation's time in the watched stream
        at = Fraction(str(v["time_s"])) + Fraction(first, RATE)
        assert snip.name == f"{float(at):013.6f}s-dir_setup.sr"


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--driver", "fx2lafw"], "found no device for driver 'fx2lafw'"),
        ([*DEMO, "--time", "7us"], "--time 7us: not a whole number of samples"),
        ([*DEMO, "--channels", "D1,Q9"], "--channels: Q9 not among"),
        (["--driver", "demo", "--samplerate", "24"], "--samplerate"),
    ],
)
def test_unusable_watch_is_one_line_and_exit_2(
    tmp_path: Path, args: list[str], message: str
) -> None:
    run = _wavecheck("watch", *args, *CHECK, cwd=tmp_path)
    assert run.returncode == 2
    assert message in run.stderr and len(run.stderr.strip().splitlines()) == 1


def test_the_readme_watch_block_runs_as_written(tmp_path: Path) -> None:
    import shlex

    from tests.doc_pages import marked

    argv = shlex.split(marked("watch").replace("\\\n", " "))
    assert argv[:2] == ["wavecheck", "watch"]
    run = _wavecheck(*argv[1:], cwd=tmp_path)
    assert run.returncode == 0, run.stderr
    assert "steps:   25000" in run.stdout  # 2 s at 200 kHz: (400000 + 7) // 16 rising edges of D3
    assert (tmp_path / "demo.sr").is_file() and (tmp_path / "snippets").is_dir()


def test_save_is_readable_after_the_watcher_is_killed(tmp_path: Path) -> None:
    """Issue 27: ``--save`` was a hidden temporary file renamed at the end, so a watch killed
    after an hour left nothing. Killed with SIGKILL (no handler runs), the file is a complete
    ``.sr`` holding all but at most the last checkpoint interval of what had been checked."""
    import re

    from wavecheck.capture.open import open_capture
    from wavecheck.live.record import CHECKPOINT_SECONDS

    proc = _start("--save", "kept.sr", cwd=tmp_path)
    assert proc.stderr is not None
    seen = 0
    deadline = time.monotonic() + HANG_GUARD_S  # a guard against a hang (tests/bounds.py)
    while seen < 3 * RATE and time.monotonic() < deadline:
        m = re.search(r"([\d,]+) samples", proc.stderr.readline())
        if m:
            seen = int(m.group(1).replace(",", ""))
    children = subprocess.run(
        ["pgrep", "-P", str(proc.pid)], capture_output=True, text=True
    ).stdout.split()
    proc.kill()
    proc.communicate(timeout=30)
    for pid in children:  # sigrok-cli sees its input end and stops; make sure
        with contextlib.suppress(ProcessLookupError):
            os.kill(int(pid), signal.SIGKILL)
    assert seen >= 3 * RATE
    kept = tmp_path / "kept.sr"
    with zipfile.ZipFile(kept) as z:
        assert z.testzip() is None
        stored = sum(i.file_size for i in z.infolist() if i.filename.startswith("logic-1-"))
    assert seen - (CHECKPOINT_SECONDS + 0.5) * RATE <= stored
    shown = subprocess.run(["sigrok-cli", "-i", str(kept), "--show"], capture_output=True,
                           text=True, check=True).stdout  # fmt: skip
    assert f"Logic sample count: {stored}" in shown  # libsigrok (PulseView) reads it whole
    cap = open_capture(kept)
    d3 = next(c for c in cap.channels if c.name == "D3")
    assert (len(d3.edges) + 1) // 2 == (stored + 7) // 16  # every pulse of the counter's D3


def test_a_snippet_repeats_the_check_of_several_axes_without_options(tmp_path: Path) -> None:
    """Two axes, an inverted DIR, a DIR sense, a shared ENABLE, a drive file and limits: the
    check of a snippet without options equals the check with all of them (issue 27)."""
    drive = tmp_path / "mine.toml"
    drive.write_text((Path(__file__).resolve().parents[3] / "rules" / "drv8825.toml").read_text())
    opts = ["--drive", "x=drv8825", "--drive", f"y={drive}", "--map",
            "x.step=D3,x.dir=D6", "--map", "y.step=D2,y.dir=D5", "--map", "enable=D7",
            "--invert", "y.dir", "--dir-forward", "y=high", "--type", "x=0",
            "--limit", "dir_setup=60us", "--margin", "+100ns"]  # fmt: skip
    run = _wavecheck("watch", *DEMO, *opts, "--time", "50ms", "--snippets", "snips",
                     "--max-snippets", "2", "--format", "json", cwd=tmp_path)  # fmt: skip
    assert run.returncode == 1, run.stderr
    snips = sorted((tmp_path / "snips").iterdir())
    assert snips
    for snip in snips:
        bare = _wavecheck("check", str(snip), "--format", "json", cwd=tmp_path)
        full = _wavecheck("check", str(snip), *opts, "--format", "json", cwd=tmp_path)
        assert bare.returncode == full.returncode == 1, bare.stderr
        assert json.loads(bare.stdout) == json.loads(full.stdout)
        assert "checked with the options it carries" in bare.stderr
    # a capture that carries none still needs --drive, in one line
    plain = _wavecheck("check", str(tmp_path / "mine.toml"), cwd=tmp_path)
    assert plain.returncode == 2 and "--drive" in plain.stderr


def test_save_to_dev_null_keeps_the_report(tmp_path: Path) -> None:
    """Issue 34: ``--save /dev/null`` with a fast source was a struct.error traceback, and the
    report was lost."""
    run = _wavecheck("watch", *DEMO, *CHECK, "--samplerate", "2MHz", "--time", "1s",
                     "--format", "json", "--save", "/dev/null", cwd=tmp_path)  # fmt: skip
    assert "Traceback" not in run.stderr and "struct.error" not in run.stderr
    assert run.returncode in (0, 1, 2), run.stderr  # 2: a demo device too slow on a busy host
    assert json.loads(run.stdout)["capture"]["samplerate_hz"] == 2_000_000


def test_save_to_the_reports_stream_is_refused(tmp_path: Path) -> None:
    """A zip and a report in one file would be neither: refused before the device starts."""
    with open(tmp_path / "rec.sr", "wb") as out:
        run = subprocess.run(
            [sys.executable, "-m", "wavecheck", "watch", *DEMO, *CHECK, "--time", "1s",
             "--save", "/dev/stdout"],
            stdout=out, stderr=subprocess.PIPE, text=True, cwd=tmp_path, timeout=120,
        )  # fmt: skip
    assert run.returncode == 2
    assert (
        run.stderr.count("\n") == 1 and "the report goes there too (standard output)" in run.stderr
    )
    assert (tmp_path / "rec.sr").read_bytes() == b""
    same = _wavecheck("watch", *DEMO, *CHECK, "--time", "1s", "--save", "r.sr", "-o", "r.sr",
                      cwd=tmp_path)  # fmt: skip
    assert same.returncode == 2 and "r.sr" in same.stderr


def test_save_to_dev_stdout_with_the_report_elsewhere(tmp_path: Path) -> None:
    with open(tmp_path / "rec.sr", "wb") as out:
        run = subprocess.run(
            [sys.executable, "-m", "wavecheck", "watch", *DEMO, *CHECK, "--time", "1s",
             "--save", "/dev/stdout", "-o", "report.txt"],
            stdout=out, stderr=subprocess.PIPE, text=True, cwd=tmp_path, timeout=120,
        )  # fmt: skip
    assert run.returncode == 0, run.stderr
    assert (tmp_path / "report.txt").read_text().startswith("verdict: PASS")
    with zipfile.ZipFile(tmp_path / "rec.sr") as z:
        assert z.testzip() is None
    cap = _wavecheck("info", "rec.sr", "--format", "json", cwd=tmp_path)
    assert cap.returncode == 0 and json.loads(cap.stdout)["samplerate_hz"] == RATE
