"""FST against VCD of the same simulation, per value change (issue 16; bench/README.md).

Icarus Verilog writes one run of a step generator twice, as VCD and as FST (``vvp -fst``); each
reader runs in its own process (wall time and peak RSS from ``getrusage``), best of ``--runs``:

- wavecheck on the VCD (the fast VCD reader),
- wavecheck on the FST (the native reader, :mod:`wavecheck.capture.fst`: the default),
- wavecheck's fst2vcd route on the FST (GTKWave's ``fst2vcd`` streamed into the VCD reader: the
  default before round 6, still used for FastLZ-packed files),
- wavecheck's pywellen path on the FST (the route without ``fst2vcd`` before round 6; also the
  GHW reader),
- pylibfst (the other FST reader on PyPI, the bench extra): its block iterator with a callback.

Run: ``.venv/bin/python bench/fst_read.py [--steps 500000] [--runs 3]`` (needs iverilog).
"""

from __future__ import annotations

import argparse
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

TB = """`timescale 1ns/1ps
module tb;
  reg step = 0, dir = 0; reg [3:0] bus = 0; integer i;
  initial begin
    $dumpfile(`DUMP); $dumpvars(0, tb);
    for (i = 0; i < STEPS; i = i + 1) begin
      #3 step = 1; bus[0] = 1; #2 step = 0; bus[0] = 0;
      if (i % 7 == 0) begin #1 dir = ~dir; bus[1] = dir; end
    end
    #5 $finish;
  end
endmodule
"""

READERS = {
    "wavecheck VCD": "from wavecheck.capture.open import open_capture as o; c = o({vcd!r}); n = sum(len(x.edges) for x in c.channels)",
    "wavecheck FST (native)": "from wavecheck.capture.open import open_capture as o; c = o({fst!r}); n = sum(len(x.edges) for x in c.channels)",
    "wavecheck FST (fst2vcd)": (
        "import shutil\n"
        "from wavecheck.capture.blocks import assemble\n"
        "from wavecheck.capture.wellen import FstBlocks\n"
        "s = FstBlocks({fst!r}, shutil.which('fst2vcd')); b = list(s.blocks())\n"
        "c = assemble(s.capture(), b); n = sum(len(x.edges) for x in c.channels)"
    ),
    "wavecheck FST (pywellen)": "from wavecheck.capture.wellen import read_wellen as r; c = r({fst!r}, kind='fst'); n = sum(len(x.edges) for x in c.channels)",
    "pylibfst": (
        "import pylibfst as p\n"
        "h = p.lib.fstReaderOpen({fst!r}.encode())\n"
        "p.lib.fstReaderSetFacProcessMaskAll(h)\n"
        "n = [0]\n"
        "@p.ffi.callback('void(void *, uint64_t, fstHandle, const unsigned char *)')\n"
        "def cb(u, t, f, v): n[0] += 1\n"
        "p.lib.fstReaderIterBlocks(h, cb, p.ffi.NULL, p.ffi.NULL)\n"
        "p.lib.fstReaderClose(h)"
    ),
}


def _run(code: str) -> tuple[float, float]:
    before = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    t = time.perf_counter()
    subprocess.run([sys.executable, "-c", code], check=True)
    wall = time.perf_counter() - t
    rss = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    return wall, max(rss, before) / 1024


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=500_000)
    ap.add_argument("--runs", type=int, default=3)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp)
        (d / "tb.v").write_text(TB.replace("STEPS", str(args.steps)))
        for ext, flag in (("vcd", []), ("fst", ["-fst"])):
            subprocess.run(
                ["iverilog", f'-DDUMP="{ext}.{ext}"', "-o", f"{ext}.vvp", "tb.v"], cwd=d, check=True
            )
            subprocess.run(
                ["vvp", "-n", f"{ext}.vvp", *flag], cwd=d, check=True, capture_output=True
            )
        vcd, fst = str(d / "vcd.vcd"), str(d / "fst.fst")
        count = subprocess.run(
            [
                sys.executable,
                "-c",
                f"from wavecheck.capture.vcd import read_vcd; print(sum(len(c.edges) for c in read_vcd({vcd!r}).channels))",
            ],
            check=True,
            capture_output=True,
            text=True,
        ).stdout.strip()
        print(
            f"{args.steps} steps; {count} edges of 1-bit signals; VCD {Path(vcd).stat().st_size / 1e6:.1f} MB, FST {Path(fst).stat().st_size / 1e6:.2f} MB"
        )
        for name, code in READERS.items():
            best = min(
                (_run(code.format(vcd=vcd, fst=fst)) for _ in range(args.runs)), key=lambda r: r[0]
            )
            print(f"{name:<26} {best[0]:6.2f} s  {best[0] / int(count) * 1e9:7.0f} ns/edge")


if __name__ == "__main__":
    main()
