"""Valid seed files of the newer readers for the fuzz driver (issue 27): GHW and FST made by the
real tools (GHDL, GTKWave's ``vcd2fst``), Saleae Logic 2 CSV and binary exports as Saleae
documents them, latency files as cyclictest, ``latency-histogram --nox`` and LinuxCNC's
``latency-test`` write them, and ``wavecheck follow`` command files (CSV, halsampler).

A seed a missing tool cannot make is left out (:func:`tool_seeds` returns none), and the fuzz
run says so.
"""

from __future__ import annotations

import functools
import shutil
import struct
import subprocess
import tempfile
from pathlib import Path

from tests.reliability.corpus import vcd_text

SIM = Path(__file__).resolve().parents[1] / "wavecheck" / "capture" / "sim"


@functools.cache
def ghw_seeds() -> tuple[bytes, ...]:
    """gen.vhd (tests/wavecheck/capture/sim) dumped by GHDL, at its default resolution and at
    ps; empty without ghdl."""
    if shutil.which("ghdl") is None:
        return ()
    with tempfile.TemporaryDirectory(prefix="ghw-seed-") as tmp:
        shutil.copy(SIM / "gen.vhd", Path(tmp) / "gen.vhd")
        for argv in (["-a", "gen.vhd"], ["-e", "tb"]):
            subprocess.run(["ghdl", *argv], check=True, cwd=tmp, capture_output=True)
        out = []
        for res in ("fs", "ps"):
            subprocess.run(["ghdl", "-r", f"--time-resolution={res}", "tb", f"--wave={res}.ghw"],
                           check=True, cwd=tmp, capture_output=True)  # fmt: skip
            out.append((Path(tmp) / f"{res}.ghw").read_bytes())
        return tuple(out)


@functools.cache
def fst_seeds() -> tuple[bytes, ...]:
    """The VCD seed converted by GTKWave's vcd2fst; empty without it."""
    if shutil.which("vcd2fst") is None:
        return ()
    with tempfile.TemporaryDirectory(prefix="fst-seed-") as tmp:
        vcd, fst = Path(tmp) / "s.vcd", Path(tmp) / "s.fst"
        vcd.write_text(vcd_text())
        subprocess.run(["vcd2fst", str(vcd), str(fst)], check=True, capture_output=True)
        return (fst.read_bytes(),)


def saleae_csv_seeds() -> tuple[bytes, ...]:
    """Logic 2 digital CSV exports: a step train at 10 MHz printed to 9 decimals."""
    rows = ["Time [s],Channel 0,Channel 1"]
    level = 0
    for k in range(40):
        level ^= 1
        rows.append(f"{k * 25e-7 - 1e-5:.9f},{level},{(k // 10) & 1}")
    return ("\n".join(rows) + "\n").encode(), ("\ufeff" + "\n".join(rows[:10]) + "\n").encode()


def _chunk(initial: int, rate: float, begin: float, end: float, times: list[float]) -> bytes:
    return struct.pack("<IdddQ", initial, rate, begin, end, len(times)) + struct.pack(
        f"<{len(times)}d", *times
    )


def saleae_bin_seeds() -> tuple[bytes, ...]:
    """Logic 2 digital binary exports: version 1 with two chunks (a gap), and version 0."""
    rate = 10_000_000
    times = [-0.25 + k / rate for k in (100, 150, 500, 550, 900, 950)]
    v1 = b"<SALEAE>" + struct.pack("<iiQ", 1, 0, 2)
    v1 += _chunk(0, rate, -0.25, -0.25 + 600 / rate, times[:4])
    v1 += _chunk(0, rate, -0.25 + 800 / rate, -0.25 + 1200 / rate, times[4:])
    v0 = b"<SALEAE>" + struct.pack("<iiIddQ", 0, 0, 1, -0.25, -0.25 + 1200 / rate, len(times))
    v0 += struct.pack(f"<{len(times)}d", *times)
    return v1, v0


def latency_seeds() -> tuple[bytes, ...]:
    """``~/.latency``, a cyclictest summary, a cyclictest -h histogram, latency-histogram --nox."""
    summary = (
        "T: 0 ( 1234) P:99 I:1000 C:  10000 Min:      2 Act:    5 Avg:    4 Max:      17\n"
        "T: 1 ( 1235) P:99 I:1500 C:   6667 Min:      3 Act:    6 Avg:    5 Max:      21\n"
    )
    hist = "# Histogram\n" + "".join(f"{b:06d} {max(0, 90 - b * 9)} {max(0, 80 - b * 8)}\n"
                                     for b in range(12))  # fmt: skip
    hist += "# Total: 000000495 000000440\n# Min Latencies: 00001 00001\n"
    hist += "# Max Latencies: 00009 00010\n# Histogram Overflows: 00000 00000\n"
    nox = "".join(
        f"{t:4d} s base min: -{1.5 + t / 10:.3f} us max: {4 + t / 5:.3f} us sdev: 0.9{t} us\n"
        for t in range(1, 6)
    )
    return b"11500\n", summary.encode(), hist.encode(), nox.encode()


def follow_seeds() -> tuple[bytes, ...]:
    """A command CSV (time_s, position) and halsampler output (read with a sample period)."""
    csv = "time_s,position\n" + "".join(f"{k / 1000:.3f},{k * 0.01:.4f}\n" for k in range(50))
    hal = "".join(f"{k} {k * 0.01:.4f} {k}\n" for k in range(50))
    return csv.encode(), hal.encode()
