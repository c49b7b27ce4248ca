"""``wavecheck watch`` without ``--map``: the roles told from the first samples, as ``check`` tells
them from a file (issue 13's inference, live).

sigrok-cli is replaced here by a stand-in (``--sigrok-cli``, a shell script) that answers
``--show`` like a device with the capture's channels and then writes a real capture's raw samples
(the Smoothieware capture of ``../shared/captures``: 12 MHz, two axes on unlabelled channels 0–7),
because no sigrok driver sends a stepper's waveforms; the live path is the same.
"""

from __future__ import annotations

import json
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

SHARED = Path(__file__).resolve().parents[4] / "shared" / "captures" / "sigrok-dumps"
SMOOTHIE = SHARED / "stepper_motor" / "smoothieware" / "smoothieware_snippet.sr"
pytestmark = pytest.mark.skipif(not SMOOTHIE.exists(), reason="needs ../shared/captures")

# as sigrok-cli does: --samples N gives N samples (one byte each here) and ends; --continuous
# gives samples until a line comes on standard input (ending by itself would be a failure)
STAND_IN = """#!/bin/sh
case "$*" in
  *--show*) echo "replay - Stand-in with 8 channels: 0 1 2 3 4 5 6 7";;
  *--get*) echo 12000000;;
  *--samples*) exec head -c "$(echo "$*" | sed 's/.*--samples \\([0-9]*\\).*/\\1/')" "{raw}";;
  *) cat "{raw}"; read line;;
esac
"""
#: 87 ms at 12 MHz: the whole samples of the Smoothieware capture's first 87 ms (of 87.38 ms)
TIME, SAMPLES = "87ms", 1_044_000


def _stand_in(tmp: Path, raw: bytes) -> Path:
    (tmp / "raw.bin").write_bytes(raw)
    script = tmp / "sigrok-cli"
    script.write_text(STAND_IN.format(raw=tmp / "raw.bin"))
    script.chmod(0o755)
    return script


def _logic(sr: Path) -> bytes:
    with zipfile.ZipFile(sr) as z:
        names = sorted(
            (n for n in z.namelist() if n == "logic-1" or n.startswith("logic-1-")),
            key=lambda n: int(n[8:] or 0),
        )  # "logic-1" (one member) or "logic-1-N"
        return b"".join(z.read(n) for n in names)


def _run(*args: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "wavecheck", *args], capture_output=True,
                          text=True, cwd=cwd, timeout=120)  # fmt: skip


def test_roles_learned_live_give_check_s_report(tmp_path: Path) -> None:
    from wavecheck.capture.srzip import sr_metadata, write_sr

    raw = _logic(SMOOTHIE)
    script = _stand_in(tmp_path, raw)
    live = _run("watch", "--driver", "replay", "--sigrok-cli", str(script), "--drive",
                "gecko-g202", "--format", "json", "--time", TIME, cwd=tmp_path)  # fmt: skip
    meta = sr_metadata([str(k) for k in range(8)], samplerate=12_000_000)
    write_sr(tmp_path / "ref.sr", raw[:SAMPLES], metadata=meta)
    ref = _run("check", "ref.sr", "--drive", "gecko-g202", "--format", "json", cwd=tmp_path)
    assert live.returncode == ref.returncode == 1, live.stderr
    got, want = json.loads(live.stdout), json.loads(ref.stdout)
    assert [a["map"] for a in got["axes"]] == [a["map"] for a in want["axes"]]
    for a, b in zip(got["axes"], want["axes"], strict=True):
        assert {k: v for k, v in a.items() if k != "capture"} == {
            k: v for k, v in b.items() if k != "capture"
        }
    # the --map line to copy is printed as soon as the roles are known
    assert "channels mapped from their waveforms: --map" in live.stderr


def test_undecided_roles_end_with_the_candidates_and_exit_2(tmp_path: Path) -> None:
    """Samples with no pulse train at all (every channel low): no STEP can be found."""
    script = _stand_in(tmp_path, bytes(120_000))
    run = _run("watch", "--driver", "replay", "--sigrok-cli", str(script), "--drive",
               "gecko-g202", "--learn", "5ms", "--time", "10ms", cwd=tmp_path)  # fmt: skip
    assert run.returncode == 2
    last = run.stderr.strip().splitlines()[-1]
    assert "no step signal found: the lines look like unchanging" in last
    assert "give --map" in last


def test_a_device_that_fails_at_once_is_one_line_exit_2_and_no_files(tmp_path: Path) -> None:
    script = tmp_path / "sigrok-cli"
    script.write_text(
        '#!/bin/sh\ncase "$*" in\n  *--show*) echo "replay - Stand-in with 2 channels: A B";;\n'
        '  *) echo "sr: fx2lafw: Unable to claim USB interface." >&2; exit 1;;\nesac\n'
    )
    script.chmod(0o755)
    for mapping in ([], ["--map", "step=A,dir=B"]):
        run = _run("watch", "--driver", "replay", "--sigrok-cli", str(script), "--samplerate",
                   "1MHz", "--drive", "gecko-g202", *mapping, "--save", "kept.sr",
                   cwd=tmp_path)  # fmt: skip
        assert run.returncode == 2 and run.stdout == ""
        last = run.stderr.strip().splitlines()[-1]
        assert "Unable to claim USB interface" in last and "nothing was checked" in last
        assert not (tmp_path / "kept.sr").exists()
