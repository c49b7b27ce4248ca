"""Bench (issue 35): grbl 1.1h on the simulated ATmega328P, 1 s of X motion at 12.5 kHz.

``python bench/mcu_grbl.py [SECONDS ...]`` builds (cached) the patched simavr runner and grbl,
runs ``G1 X{50*s} F3000`` at ``$100=250`` (50 mm/s x 250 steps/mm = 12.5 kHz) for each length,
under ``/usr/bin/time -v``, and prints one JSON line per run: the simulated seconds (the runner's
end cycle / 16 MHz), the runner's CPU seconds, its max RSS, the steps in the VCD and the VCD's
size. Goals: CPU ≤ 0.5 s per simulated second; max RSS flat in the run's length (the VCD is
written as the simulation goes).
"""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
SRC = REPO.parent / "shared" / "firmware-src"
SETTINGS = ["$0=10", "$100=250", "$110=3000", "$120=5000"]


def one(runner: Path, elf: Path, seconds: int, tmp: Path) -> dict[str, float]:
    vcd = tmp / f"grbl-{seconds}s.vcd"
    lines = [*SETTINGS, f"G1 X{50 * seconds} F3000", "G4 P0"]
    timing = tmp / "time.txt"
    cmd = ["/usr/bin/time", "-v", "-o", str(timing), str(runner), str(elf), "atmega328p"]
    cmd += ["16000000", str(vcd), "Grbl ", str(16_000_000 * 600), "16000"]
    cmd += ["X_STEP=D.2", "X_DIR=D.5", "ENABLE=B.0"]
    out = subprocess.run(
        cmd, input="\n".join(lines) + "\n", capture_output=True, text=True, check=True
    ).stdout
    end = int(out.strip().splitlines()[-1].split()[2])
    t = timing.read_text()

    def field(name: str) -> float:
        m = re.search(rf"{re.escape(name)}: (.+)", t)
        return float(m.group(1)) if m else 0.0

    steps = sum(1 for ln in vcd.open() if ln.startswith("1!"))
    return {
        "seconds_motion": seconds,
        "simulated_s": end / 16_000_000,
        "cpu_s": field("User time (seconds)") + field("System time (seconds)"),
        "max_rss_mb": field("Maximum resident set size (kbytes)") / 1024,
        "steps": steps,
        "vcd_bytes": os.path.getsize(vcd),
    }


def main() -> int:
    sys.path.insert(0, str(REPO))
    from wavecheck.mcu.build import build_firmware, build_runner

    runner = build_runner(SRC / "simavr")
    target = ["build/main.elf", "CLOCK=16000000"]
    elf = build_firmware(SRC / "grbl-1.1h", "grbl/stepper.c", {}, target, "build/main.elf")
    lengths = [int(a) for a in sys.argv[1:]] or [1, 2]
    with tempfile.TemporaryDirectory() as tmp:
        for s in lengths:
            print(json.dumps(one(runner, elf, s, Path(tmp))), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
