"""Standard-input throughput of raw samples (issue 14, "From a pipe").

``python bench/stdin_pipe.py [FILE.sr] [--runs N]`` writes the capture's raw samples once (what
``sigrok-cli -O binary`` prints: the ``.sr``'s logic bytes, in order) to ``bench/data/``, then
times, interleaved, ``wavecheck check -`` fed those bytes through a real pipe (``cat FILE |``)
with ``--input-format binary:numchannels=N --samplerate R``, and ``wavecheck check FILE.sr`` on
the same capture. Prints one JSON line: medians of wall and CPU (the pipe's reader process,
start-up included; ``cat``'s copy included), bytes and samples per second of wall time, and the ratio to the arrival
rate of sigrok's demo driver at 24 MHz × 8 channels (24 MB/s), the rate ``watch`` must keep up
with. Default capture: grbl_cnc_1.sr (2 MHz, 96.7 M one-byte samples).
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import time
import zipfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from wavecheck.capture.sr import read_sr_metadata  # noqa: E402
from wavecheck.capture.zipdir import Archive  # noqa: E402

GRBL = ROOT.parent / "shared/captures/sigrok-dumps/stepper_motor/grbl_cnc/grbl_cnc_1.sr"
DEMO_RATE = 24_000_000  # bytes/s: sigrok's demo driver, 24 MHz × 8 channels, one byte a sample


def raw_samples(sr: Path, out: Path) -> tuple[int, int, int]:
    """Write ``sr``'s logic bytes to ``out`` (once); returns (bytes, unitsize, samplerate Hz)."""
    with Archive(sr) as directory:
        meta = read_sr_metadata(sr, directory)
    with zipfile.ZipFile(sr) as zf:
        if not out.exists() or out.stat().st_size != sum(m.file_size for m in meta.members):
            tmp = out.with_suffix(".part")
            with open(tmp, "wb") as f:
                for info in meta.members:
                    with zf.open(info.filename) as member:
                        while block := member.read(1 << 22):
                            f.write(block)
            tmp.replace(out)
    assert meta.samplerate is not None
    return out.stat().st_size, meta.unitsize, int(meta.samplerate)


def _timed(argv: list[str], stdin_file: Path | None) -> tuple[float, float]:
    """Wall and CPU seconds of ``argv`` (its stdin a pipe from ``cat stdin_file``)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    feeder = None
    if stdin_file is not None:
        feeder = subprocess.Popen(["cat", str(stdin_file)], stdout=subprocess.PIPE)
    proc = subprocess.run(
        argv,
        stdin=feeder.stdout if feeder is not None else subprocess.DEVNULL,
        stdout=subprocess.DEVNULL,
        check=False,
    )
    if feeder is not None:
        assert feeder.stdout is not None
        feeder.stdout.close()
        feeder.wait()
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if proc.returncode not in (0, 1, 3):
        raise SystemExit(f"{argv} failed with exit {proc.returncode}")
    # with a pipe, cat's CPU (a copy into the pipe) is included
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("capture", nargs="?", type=Path, default=GRBL)
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--numchannels", type=int, default=None, help="default: 8 × unitsize")
    args = ap.parse_args()
    data = ROOT / "bench" / "data"
    data.mkdir(parents=True, exist_ok=True)
    raw = data / f"{args.capture.stem}.bin"
    size, unitsize, rate = raw_samples(args.capture, raw)
    n = args.numchannels or 8 * unitsize
    exe = [sys.executable, "-m", "wavecheck", "check"]
    common = ["--drive", "gecko-g202", "--map", "step=1,dir=0", "-q"]
    piped = [*exe, "-", "--input-format", f"binary:numchannels={n}", "--samplerate", f"{rate}Hz",
             *common]  # fmt: skip
    direct = [*exe, str(args.capture), *common]
    walls: dict[str, list[float]] = {"pipe": [], "sr": []}
    cpus: dict[str, list[float]] = {"pipe": [], "sr": []}
    env_load = os.getloadavg()[0]
    for _ in range(args.runs):
        for key, argv, src in (("pipe", piped, raw), ("sr", direct, None)):
            w, c = _timed(argv, src)
            walls[key].append(w)
            cpus[key].append(c)
    wall = statistics.median(walls["pipe"])
    samples = size // unitsize
    print(
        json.dumps(
            {
                "capture": args.capture.name,
                "bytes": size,
                "samples": samples,
                "pipe_wall_s": round(wall, 3),
                "pipe_cpu_s": round(statistics.median(cpus["pipe"]), 3),
                "sr_wall_s": round(statistics.median(walls["sr"]), 3),
                "sr_cpu_s": round(statistics.median(cpus["sr"]), 3),
                "MB_per_s": round(size / wall / 1e6, 1),
                "Msamples_per_s": round(samples / wall / 1e6, 1),
                "vs_demo_24MHz_x8": round(size / wall / DEMO_RATE, 2),
                "load_1min": round(env_load, 2),
            }
        )
    )


if __name__ == "__main__":
    main()
