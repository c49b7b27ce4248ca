"""``.sr`` read against its numpy floor (issue 29): ``read_sr`` against the least any reader
of the file must do, in the same process, CPU best of ``--repeat``, interleaved.

The floor: every chunk member inflated straight from the file with zlib-ng in the reader's
1 MiB pieces, its CRC-32 taken, and each piece's 8-byte words compared with the same bytes one
sample earlier (``!=`` on unaligned ``uint64`` views into a reused buffer, then ``flatnonzero``):
what tells which words hold a change, before any byte, bit or position of it is known. The
reader does that, then finds the changed bits of every channel and their sample numbers, and
keeps the edges. Prints one JSON line.

    .venv/bin/python bench/sr_floor.py FILE.sr [--repeat 7]
"""

from __future__ import annotations

import argparse
import json
import struct
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from wavecheck.capture import sr
from wavecheck.capture.zipdir import Archive

PIECE = sr.DEFAULT_CHUNK_BYTES


def floor(path: str) -> int:
    """Inflate + CRC-32 + word scan of every chunk member; returns the differing words."""
    zlib = sr._zlib  # zlib-ng, as the reader
    found = 0
    ne = np.empty(PIECE // 8, dtype=bool)
    with Archive(path) as zf, open(path, "rb") as raw:
        meta = sr.read_sr_metadata(path, zf)
        step = meta.unitsize
        for info in meta.members:
            raw.seek(info.header_offset)
            name_len, extra_len = struct.unpack("<HH", raw.read(30)[26:30])
            raw.seek(info.header_offset + 30 + name_len + extra_len)
            inflater, tail, crc = zlib.decompressobj(-15), raw.read(info.compress_size), 0
            while True:
                out = inflater.decompress(tail, PIECE)
                tail = inflater.unconsumed_tail
                crc = zlib.crc32(out, crc)
                b = np.frombuffer(out, dtype=np.uint8)
                words = (len(b) - step) // 8
                if words > 0:
                    cur = b[step : step + 8 * words].view(np.uint64)
                    np.not_equal(cur, b[: 8 * words].view(np.uint64), out=ne[:words])
                    found += len(np.flatnonzero(ne[:words]))
                if inflater.eof or not out:
                    break
            assert crc == info.CRC
    return found


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("file")
    ap.add_argument("--repeat", type=int, default=7)
    args = ap.parse_args()
    cpu: dict[str, list[float]] = {"floor": [], "read_sr": []}
    edges = 0
    for _ in range(args.repeat):
        c0 = time.process_time()
        floor(args.file)
        cpu["floor"].append(time.process_time() - c0)
        c0 = time.process_time()
        cap = sr.read_sr(args.file)
        cpu["read_sr"].append(time.process_time() - c0)
        edges = sum(len(c.edges) for c in cap.channels)
    best = {k: min(v) for k, v in cpu.items()}
    out = {"file": args.file, "samples": cap.end, "edges": edges, "cpu_s": best, "runs": cpu,
           "ratio": best["read_sr"] / best["floor"]}  # fmt: skip
    print(json.dumps(out))


if __name__ == "__main__":
    main()
