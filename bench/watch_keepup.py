"""Live keep-up of ``wavecheck watch`` on sigrok's demo driver (issue 14, "Keep up").

``python bench/watch_keepup.py [--seconds S]`` runs ``wavecheck watch`` on the real demo device
(sigrok-cli 0.7.2) for S seconds of samples, twice:

- ``24MHz``: 24 MHz × 8 channels, the demo's default ``sigrok`` pattern (sigrok-cli cannot set
  another pattern and the sample rate in one run): every channel toggles millions of times a
  second (measured: 6–9 M edges/s per channel), STEP on D0 and DIR on D1, so every interval
  fails — far denser than any machine;
- ``200kHz-counter``: the ``incremental`` pattern at the demo's own 200 kHz, STEP on D3 (12.5 k
  steps/s) and DIR on D6;
- ``grbl-replay``: the real grbl capture's raw samples (2 MHz, 4 channels, 96.7 M samples; Y axis
  STEP) given to ``watch`` as fast as a pipe takes them, by a stand-in for sigrok-cli (a small
  script passed as ``--sigrok-cli`` that answers ``--show``/``--get`` like the demo device and
  then writes the file): what ``watch`` can process of a real machine's signals, not paced.

For each, from what ``watch`` prints: ``keep_up``, the samples wavecheck can process per second
of its processor time ÷ the samples arriving per second (samples ÷ its CPU seconds ÷ the rate;
≥ 1 keeps up, the goal is ≥ 2 = under half a core); ``core_share``, its processor time ÷ wall
time (sigrok-cli's not counted); and ``paced``, samples ÷ wall seconds ÷ the rate (about 1 when
the analyzer sets the pace; below 1 the pipe backed up and a real analyzer would lose samples).
``vs_24MHz`` is the same capacity against 24 MHz (the demo's fastest rate here). One JSON line
per case.
"""

from __future__ import annotations

import argparse
import json
import re
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from stdin_pipe import GRBL, raw_samples  # noqa: E402

CASES = {
    "24MHz": (["--driver", "demo:analog_channels=0", "--samplerate", "24MHz"], "step=D0,dir=D1",
              24_000_000),
    "200kHz-counter": (["--driver", "demo:analog_channels=0", "--channel-group", "Logic",
                        "--config", "pattern=incremental"], "step=D3,dir=D6", 200_000),
    "grbl-replay": (["--driver", "replay", "--samplerate", "2MHz"], "step=D1", 2_000_000),
}  # fmt: skip
#: The stand-in for sigrok-cli of ``grbl-replay`` (argv[1]: the raw samples).
STAND_IN = """#!/bin/sh
case "$*" in
  *--show*) echo "replay - Stand-in with 4 channels: D0 D1 D2 D3";;
  *--get*) echo 2000000;;
  *) exec cat "{raw}";;
esac
"""
_LINE = re.compile(
    r"watched (?P<n>[\d,]+) samples in (?P<wall>[\d.]+) s .*?used (?P<cpu>[\d.]+) s of processor"
)


def run_case(name: str, seconds: int) -> dict[str, object]:
    """One watch run; its figures."""
    device, mapping, rate = CASES[name]
    with tempfile.TemporaryDirectory() as tmp:
        limit = ["--time", f"{seconds}s"]
        if name == "grbl-replay":
            raw = HERE / "data" / "grbl_cnc_1.bin"
            raw.parent.mkdir(exist_ok=True)
            raw_samples(GRBL, raw)
            stand_in = Path(tmp) / "sigrok-cli"
            stand_in.write_text(STAND_IN.format(raw=raw))
            stand_in.chmod(0o755)
            device, limit = [*device, "--sigrok-cli", str(stand_in)], []
        done = subprocess.run(
            [sys.executable, "-m", "wavecheck", "watch", *device, *limit,
             "--drive", "drv8825", "--map", mapping, "--format", "json", "-o", f"{tmp}/r.json",
             "--status", "never"],
            capture_output=True, text=True, timeout=600,
        )  # fmt: skip
    m = _LINE.search(done.stderr)
    if m is None:
        raise SystemExit(f"{name}: no figures in wavecheck's output: {done.stderr[-300:]}")
    n, wall, cpu = int(m["n"].replace(",", "")), float(m["wall"]), float(m["cpu"])
    return {
        "case": name,
        "samples": n,
        "wall_s": wall,
        "cpu_s": cpu,
        "keep_up": round(n / cpu / rate, 2),
        "paced": round(n / wall / rate, 3),
        "vs_24MHz": round(n / cpu / 24_000_000, 2),
        "core_share": round(cpu / wall, 3),
        "exit": done.returncode,
    }


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=int, default=10, help="seconds of samples per case")
    ap.add_argument("--case", action="append", choices=sorted(CASES), help="default: both")
    args = ap.parse_args()
    for name in args.case or list(CASES):
        print(json.dumps(run_case(name, args.seconds)), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
