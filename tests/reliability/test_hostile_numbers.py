"""Huge numbers, NaN and infinity wherever a number is read (issue 27): one line, exit 2.

Each case is a file or an option a user could give: a 5,000-digit time in a Saleae CSV, a NaN
sample rate or a +inf transition time in a Saleae binary export, a 5,000-digit latency, a
latency of 10^400 µs, NaN or 10^308 for ``follow --scale``/``--max-error`` and ``stepgen tune
--inertia``, a command CSV with NaN or an overflowing time. Before issue 27 these ended in a
ValueError/OverflowError traceback (exit 1), a silent PASS (+inf became an edge at -9.2e18
ticks) or a NaN printed as a result (exit 0). The contract: exit 2, exactly one line on stderr
naming the file or the option, no traceback, no RuntimeWarning.
"""

from __future__ import annotations

import struct
from collections.abc import Callable
from pathlib import Path

import pytest

from tests.conftest import write_vcd
from tests.reliability.helpers import cli

RATE = 10_000_000
NAN, INF = float("nan"), float("inf")
BIG = "9" * 5000


def _chunk(rate: float, begin: float, end: float, times: list[float]) -> bytes:
    head = struct.pack("<IdddQ", 0, rate, begin, end, len(times))
    return head + struct.pack(f"<{len(times)}d", *times)


def _saleae_bin(tmp: Path, rate: float, times: list[float], begin: float = 0.0) -> Path:
    folder = tmp / "export"
    folder.mkdir()
    data = b"<SALEAE>" + struct.pack("<iiQ", 1, 0, 1) + _chunk(rate, begin, 1.0, times)
    (folder / "digital_0.bin").write_bytes(data)
    return folder / "digital_0.bin"


def _file(name: str, text: str) -> Callable[[Path], Path]:
    def build(tmp: Path) -> Path:
        path = tmp / name
        path.write_text(text)
        return path

    return build


def _run_vcd(tmp: Path) -> Path:
    """19 steps of 500 ns every 1 us (ns ticks), DIR low."""
    steps = [1000 * k for k in range(1, 20)]
    edges = sorted(steps + [t + 500 for t in steps])
    return write_vcd(tmp / "run.vcd", {"step": (0, edges), "dir": (0, [])}, end=21000)


# (id, program, builder of the input → path, argv given the path, text the error must contain)
CASES: list[tuple[str, str, Callable[[Path], Path], Callable[[Path], list[str]], str]] = [
    ("saleae-csv-5000-digit-time", "wavecheck",
     _file("big.csv", f"Time [s],Channel 0\n0.0,0\n{BIG}.0,1\n"),
     lambda p: ["info", str(p)], "more than 30 digits"),
    ("saleae-csv-time-beyond-int64", "wavecheck",
     _file("far.csv", "Time [s],Channel 0\n0.0,0\n" + "9" * 25 + ".0,1\n2" + "0" * 25 + ".0,0\n"),
     lambda p: ["info", str(p)], "2^62 samples"),
    ("saleae-bin-rate-nan", "wavecheck", lambda t: _saleae_bin(t, NAN, [0.5]),
     lambda p: ["info", str(p)], "sample rate nan"),
    ("saleae-bin-rate-inf", "wavecheck", lambda t: _saleae_bin(t, INF, [0.5]),
     lambda p: ["info", str(p)], "sample rate inf"),
    ("saleae-bin-transition-inf", "wavecheck", lambda t: _saleae_bin(t, RATE, [0.5, INF]),
     lambda p: ["check", str(p), "--drive", "gecko-g202", "--map", "step=Channel 0"],
     "transition 1"),
    ("saleae-bin-begin-nan", "wavecheck", lambda t: _saleae_bin(t, RATE, [0.5], begin=NAN),
     lambda p: ["info", str(p)], "begin time nan"),
    ("latency-file-5000-digits", "stepgen", _file("lat.txt", BIG + "\n"),
     lambda p: ["plan", "--drive", "gecko-g202", "--base-period", "25us", "--latency", str(p)],
     "line 1"),
    ("latency-nox-1e400-us", "stepgen",
     _file("nox.txt", f"   1 s base min: -1.0 us max: {BIG}.0 us sdev: 1.0 us\n"),
     lambda p: ["plan", "--drive", "gecko-g202", "--base-period", "25us", "--latency", str(p)],
     "line 1"),
    ("latency-histogram-5000-digit-count", "stepgen",
     _file("hist.txt", f"# Histogram\n000000 1\n000001 {BIG}\n"),
     lambda p: ["simulate", "--position", "1", "--latency", f"histogram:{p}",
                "--duration", "10ms", "-o", str(p.with_suffix(".vcd"))],
     "line 3"),
    ("follow-command-nan", "wavecheck", _file("nan.csv", "time_s,steps\n0,0\n0.001,nan\n"),
     lambda p: ["follow", str(p.with_name("run.vcd")), "--command", str(p)], "line 3"),
    ("follow-command-time-1e999", "wavecheck", _file("inf.csv", "time_s,steps\n0,0\n1e999,1\n"),
     lambda p: ["follow", str(p.with_name("run.vcd")), "--command", str(p)], "line 3"),
    ("follow-scale-nan", "wavecheck", _file("c.csv", "time_s,position\n0,0\n0.001,1\n"),
     lambda p: ["follow", str(p.with_name("run.vcd")), "--command", str(p), "--scale", "nan"],
     "--scale"),
    ("follow-max-error-nan", "wavecheck", _file("c.csv", "time_s,steps\n0,0\n0.001,1\n"),
     lambda p: ["follow", str(p.with_name("run.vcd")), "--command", str(p), "--max-error", "nan"],
     "--max-error"),
    ("follow-max-error-inf", "wavecheck", _file("c.csv", "time_s,steps\n0,0\n0.001,1\n"),
     lambda p: ["follow", str(p.with_name("run.vcd")), "--command", str(p), "--max-error", "inf"],
     "--max-error"),
    ("follow-command-dev-zero", "wavecheck", lambda t: Path("/dev/zero"),
     lambda p: ["follow", "run.vcd", "--command", str(p)], "/dev/zero"),
    ("tune-inertia-1e308", "stepgen", lambda t: t / "unused",
     lambda p: ["tune", "--inertia", "1e308"], "--inertia"),
    ("tune-inertia-nan", "stepgen", lambda t: t / "unused",
     lambda p: ["tune", "--inertia", "nan"], "--inertia"),
    ("simulate-position-scale-inf", "stepgen", lambda t: t / "unused",
     lambda p: ["simulate", "--position", "1", "--position-scale", "inf", "--duration", "1ms",
                "-o", str(p)],
     "--position-scale"),
]  # fmt: skip


@pytest.mark.parametrize(
    ("prog", "build", "argv", "says"), [c[1:] for c in CASES], ids=[c[0] for c in CASES]
)
def test_hostile_number_is_one_line(
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    prog: str,
    build: Callable[[Path], Path],
    argv: Callable[[Path], list[str]],
    says: str,
) -> None:
    monkeypatch.chdir(tmp_path)
    _run_vcd(tmp_path)
    path = build(tmp_path)
    rc, out, err = cli(prog, argv(path))
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert rc == 2, (rc, out[-300:], err[-600:])
    assert len(lines) == 1 and "Traceback" not in err and "Warning" not in err, err
    assert says in lines[0], lines[0]
    assert "nan" not in out.lower().split()


def test_follow_reads_a_csv_with_a_byte_order_mark(tmp_path: Path) -> None:
    """A CSV saved by a spreadsheet (UTF-8 with BOM) has the same header as one without."""
    vcd = _run_vcd(tmp_path)
    plain = tmp_path / "plain.csv"
    plain.write_text("time_s,steps\n0,0\n0.00002,19\n")
    bom = tmp_path / "bom.csv"
    bom.write_bytes(b"\xef\xbb\xbf" + plain.read_bytes())
    results = [cli("wavecheck", ["follow", str(vcd), "--command", str(p)]) for p in (plain, bom)]
    assert results[0][0] == 0 and results[1][0] == 0, results
    assert results[0][1].replace("plain.csv", "X") == results[1][1].replace("bom.csv", "X")
