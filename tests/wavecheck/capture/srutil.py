"""Build small .sr files for tests (the project's one .sr writer, :mod:`wavecheck.capture.srzip`)
and count their edges independently of the reader (zipfile + numpy)."""

from __future__ import annotations

import functools
import zipfile
from pathlib import Path

import numpy as np
import numpy.typing as npt

from wavecheck.capture.srzip import sr_metadata
from wavecheck.capture.srzip import write_sr as write_srzip


def write_sr(
    path: Path,
    samples: npt.NDArray[np.uint8] | bytes,
    *,
    probes: dict[int, str] | None = None,
    total: int = 8,
    unitsize: int = 1,
    samplerate: str | None = "1 MHz",
    chunk: int = 1 << 20,
    extra_meta: str = "",
    members: dict[str, bytes] | None = None,
    version: bytes = b"2",
    compression: int = zipfile.ZIP_DEFLATED,
) -> Path:
    """Write ``samples`` (raw bytes, ``unitsize`` per sample) as ``logic-1-N`` chunks of ``chunk`` bytes.

    ``members`` replaces the ``logic-1-N`` members by these (names as given), for layouts the
    writer does not make (a single ``logic-1``, gaps, odd names); ``unitsize=0`` writes none.
    """
    meta = sr_metadata(
        probes if probes is not None else {i: f"D{i}" for i in range(total)},
        samplerate=samplerate,
        unitsize=unitsize,
        total_probes=total,
        total_analog=None,
        extra=extra_meta,
    )
    if members is None:
        write_srzip(
            path,
            samples,
            metadata=meta,
            chunk_bytes=chunk,
            version=version,
            compression=compression,
        )
        return path
    write_srzip(path, [], metadata=meta, version=version)
    with zipfile.ZipFile(path, "a") as z:
        for name, data in members.items():
            z.writestr(name, data, compress_type=compression)
    return path


def edges_by_unpacking(raw: bytes, unitsize: int, bit: int) -> tuple[int, list[int]]:
    """Initial level and edge sample numbers of ``bit``, with unpackbits over all samples."""
    u8 = np.frombuffer(raw, np.uint8).reshape(-1, unitsize)
    bits = np.unpackbits(u8, axis=1, bitorder="little")[:, bit].astype(np.int8)
    return int(bits[0]), (np.flatnonzero(np.diff(bits)) + 1).tolist()


@functools.lru_cache(maxsize=4)
def count_edges_by_members(path: Path) -> tuple[list[int], list[int], int]:
    """Initial level and edge count per bit of a unitsize-1 ``.sr``, member by member.

    Independent of the reader: whole members read with ``ZipFile.read``, each bit shifted out
    and compared with its neighbour, the last sample prepended to the next member.
    Returns (initial per bit, edges per bit, samples).
    """
    with zipfile.ZipFile(path) as z:
        names = sorted(
            (n for n in z.namelist() if n.startswith("logic-1-")), key=lambda n: int(n[8:])
        )
        counts = [0] * 8
        prev: np.ndarray | None = None
        initial: list[int] = []
        samples = 0
        for n in names:
            raw = np.frombuffer(z.read(n), np.uint8)
            samples += len(raw)
            if prev is None:
                initial = [(int(raw[0]) >> b) & 1 for b in range(8)]
            else:
                raw = np.concatenate([prev, raw])
            for b in range(8):
                bits = (raw >> b) & 1
                counts[b] += int(np.count_nonzero(bits[1:] != bits[:-1]))
            prev = raw[-1:]
    return initial, counts, samples
