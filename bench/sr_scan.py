"""The ``.sr`` edge scan alone: today's ``_EdgeFinder`` against the one it replaced (issue 18).

``python bench/sr_scan.py FILE.sr`` inflates the file's samples once into memory, cuts them into
the reader's 1 MiB blocks, then times (CPU, best of ``--repeat``, interleaved) the two scans
over all blocks and checks that they give the same edges. Prints one JSON line.

The old scan (issue 7): per byte column, XOR each sample with the one before into a reused
buffer, then ``flatnonzero`` on ``uint64`` words and inside the non-zero words. The new one
compares 8-byte words with the same bytes one sample earlier (an unaligned view) and XORs only
inside the differing words (``wavecheck.capture.sr._changed_words``).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np
import numpy.typing as npt

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from wavecheck.capture import sr  # noqa: E402
from wavecheck.capture.zipdir import Archive  # noqa: E402

_OFFSETS = np.arange(8, dtype=np.int64)


class OldEdgeFinder:
    """The scan before issue 18, kept here as the baseline (same results, slower)."""

    def __init__(self, unitsize: int, bits: list[int]) -> None:
        self.unitsize = unitsize
        self.columns: dict[int, list[tuple[int, int]]] = {}
        for slot, bit in enumerate(bits):
            self.columns.setdefault(bit // 8, []).append((bit % 8, slot))
        self.prev: dict[int, int] = {}
        self.parts: list[list[npt.NDArray[np.int64]]] = [[] for _ in bits]
        self.nsamples = 0
        self._xor = np.empty(0, dtype=np.uint8)

    def add(self, block: npt.NDArray[np.uint8]) -> None:
        n = len(block) // self.unitsize
        rows = block.reshape(n, self.unitsize)
        base = self.nsamples
        for col, slots in self.columns.items():
            x = rows[:, col] if self.unitsize > 1 else block
            if col in self.prev:
                d0 = int(x[0]) ^ self.prev[col]
                for bit, slot in slots:
                    if (d0 >> bit) & 1:
                        self.parts[slot].append(np.array([base], dtype=np.int64))
            self.prev[col] = int(x[-1])
            if len(self._xor) < n - 1:
                self._xor = np.empty(n - 1, dtype=np.uint8)
            d = self._xor[: n - 1]
            np.bitwise_xor(x[1:], x[:-1], out=d)
            m = len(d) & ~7
            w = np.flatnonzero(d[:m].view(np.uint64))
            nz: npt.NDArray[np.int64] = w
            if len(w):
                nz = (w[:, None] * 8 + _OFFSETS).ravel()
                nz = nz[d[nz] != 0]
            if m < len(d):
                nz = np.concatenate([nz, np.flatnonzero(d[m:]) + m])
            if len(nz):
                dv = d[nz]
                pos = nz + (base + 1)
                for bit, slot in slots:
                    sel = (dv & np.uint8(1 << bit)) != 0
                    if sel.any():
                        self.parts[slot].append(pos[sel])
        self.nsamples += n

    def edges(self, slot: int) -> npt.NDArray[np.int64]:
        parts = self.parts[slot]
        return np.concatenate(parts) if parts else np.zeros(0, dtype=np.int64)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("file")
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    with Archive(args.file) as zf:
        meta = sr.read_sr_metadata(args.file, zf)
        data = b"".join(zf.read(m.filename) for m in meta.members)
    bits = sorted(meta.probes)
    step = sr.DEFAULT_CHUNK_BYTES - sr.DEFAULT_CHUNK_BYTES % meta.unitsize
    blocks = [
        np.frombuffer(data, np.uint8, min(step, len(data) - i), i)
        for i in range(0, len(data), step)
    ]

    def scan(cls: type) -> tuple[float, list[list[int]]]:
        finder = cls(meta.unitsize, bits)
        c0 = time.process_time()
        for b in blocks:
            finder.add(b)
        cpu = time.process_time() - c0
        return cpu, [finder.edges(s).tolist() for s in range(len(bits))]

    new_s, old_s = [], []
    for _ in range(args.repeat):  # interleaved, so load hits both alike
        t, new_edges = scan(sr._EdgeFinder)
        new_s.append(t)
        t, old_edges = scan(OldEdgeFinder)
        old_s.append(t)
    same = new_edges == old_edges
    print(json.dumps({
        "file": args.file, "samples": len(data) // meta.unitsize, "edges": sum(map(len, new_edges)),
        "new_cpu_s": min(new_s), "old_cpu_s": min(old_s), "speedup": min(old_s) / min(new_s),
        "same_edges": same,
    }))  # fmt: skip
    if not same:
        sys.exit("the two scans disagree")


if __name__ == "__main__":
    main()
