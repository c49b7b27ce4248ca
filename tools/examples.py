"""Example captures for the README: ``python -m tools.examples --write|--check``.

``captures/examples/two-axis.vcd``: a two-axis machine made from two golden stepgen traces of
the Gecko G202 story (LinuxCNC's Stepper Tuning chapter): axis x is BASE_PERIOD 20 us with the
worst-case 11 us latency on DIR hold (9 us < 20 us: fails), axis y is the planned 16 us with
dirhold 2 (passes). Channels ``x_step``, ``x_dir``, ``y_step``, ``y_dir``; 1 ns timescale.
"""

from __future__ import annotations

import argparse
import filecmp
import sys
import tempfile
from pathlib import Path

from wavecheck.capture.open import open_capture
from wavecheck.capture.vcd.writer import VcdWire, write_vcd

ROOT = Path(__file__).resolve().parent.parent
GOLDEN = ROOT / "captures" / "golden"
EXAMPLES = ROOT / "captures" / "examples"
AXES = {"x": "g202-p20-worst-dirhold.vcd", "y": "g202-p16-dirhold2-worst.vcd"}


def write_two_axis(target: Path, golden: Path = GOLDEN) -> Path:
    """Write the two-axis example to ``target``."""
    wires = []
    end = 0
    for axis, name in AXES.items():
        cap = open_capture(golden / name)
        end = max(end, cap.end)
        for role in ("step", "dir"):
            ch = cap.channel(role)
            wires.append(VcdWire(f"{axis}_{role}", ch.initial, ch.edges))
    write_vcd(target, wires, timescale="1 ns", end=end, scope="machine")
    return target


def main(argv: list[str] | None = None) -> int:
    """``--write`` regenerates the examples; ``--check`` fails when one differs byte for byte."""
    p = argparse.ArgumentParser(prog="python -m tools.examples", description=__doc__)
    g = p.add_mutually_exclusive_group(required=True)
    g.add_argument("--write", action="store_true")
    g.add_argument("--check", action="store_true")
    args = p.parse_args(argv)
    if args.write:
        EXAMPLES.mkdir(parents=True, exist_ok=True)
        print(write_two_axis(EXAMPLES / "two-axis.vcd"))
        return 0
    with tempfile.TemporaryDirectory() as tmp:
        fresh = write_two_axis(Path(tmp) / "two-axis.vcd")
        same = filecmp.cmp(fresh, EXAMPLES / "two-axis.vcd", shallow=False)
    print("two-axis.vcd:", "as written" if same else "DIFFERENT (python -m tools.examples --write)")
    return 0 if same else 1


if __name__ == "__main__":
    sys.exit(main())
