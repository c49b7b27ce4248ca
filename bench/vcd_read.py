"""Read a VCD into per-signal numpy arrays with one reader; print one JSON line.

``python bench/vcd_read.py READER FILE`` with READER one of:

* ``wavecheck`` — :func:`wavecheck.capture.vcd.read_vcd` (edge arrays, int64 ticks);
* ``pywellen`` — pywellen ``Waveform``, each 1-bit ``Signal`` iterated into lists, then numpy
  (the fastest idiom measured in ``../shared/reference/vcd-perf.md``);
* ``vcdvcd`` — ``VCDVCD(path)``, then each signal's ``.tv`` into numpy.

The foreign readers give value changes (times int64, values int8), which is what a user would
start from; wavecheck gives edges (changes to a new level). Timed from just before opening the
file to the last array (imports excluded, as in vcd-perf.md); run it under ``/usr/bin/time -v``
for the peak RSS.
"""

from __future__ import annotations

import json
import sys
import time

import numpy as np


def _wavecheck(path: str) -> tuple[int, int]:
    from wavecheck.capture.vcd import read_vcd

    cap = read_vcd(path)
    n = sum(len(c.edges) for c in cap.channels)
    nbytes = sum(c.edges.nbytes + c.xz_times.nbytes for c in cap.channels)
    return n, nbytes


def _pywellen(path: str) -> tuple[int, int]:
    import pywellen

    w = pywellen.Waveform(path)
    n = nbytes = 0
    for var in w.all_vars():
        sig = var.signal  # the body is parsed on first access
        tl: list[int] = []
        vl: list[object] = []
        for t, v in sig:
            tl.append(t)
            vl.append(v)
        times = np.array(tl, dtype=np.int64)
        values = np.array([x if isinstance(x, int) else 2 for x in vl], dtype=np.int8)
        n += len(times)
        nbytes += times.nbytes + values.nbytes
    return n, nbytes


_VAL = {"0": 0, "1": 1, "x": 2, "X": 2, "z": 3, "Z": 3}


def _vcdvcd(path: str) -> tuple[int, int]:
    from vcdvcd import VCDVCD

    v = VCDVCD(path)
    n = nbytes = 0
    for name in v.signals:
        tv = v[name].tv
        times = np.fromiter((t for t, _ in tv), dtype=np.int64, count=len(tv))
        values = np.fromiter((_VAL.get(x, 2) for _, x in tv), dtype=np.int8, count=len(tv))
        n += len(times)
        nbytes += times.nbytes + values.nbytes
    return n, nbytes


READERS = {"wavecheck": _wavecheck, "pywellen": _pywellen, "vcdvcd": _vcdvcd}


def main() -> None:
    reader, path = sys.argv[1], sys.argv[2]
    fn = READERS[reader]
    if reader == "pywellen":
        import pywellen  # noqa: F401  (import outside the timed region)
    elif reader == "vcdvcd":
        import vcdvcd  # noqa: F401
    else:
        import wavecheck.capture.vcd  # noqa: F401
    t0 = time.perf_counter()
    c0 = time.process_time()
    n, nbytes = fn(path)
    print(
        json.dumps(
            {
                "reader": reader,
                "seconds": time.perf_counter() - t0,
                "cpu_seconds": time.process_time() - c0,
                "items": n,
                "array_bytes": nbytes,
            }
        )
    )


if __name__ == "__main__":
    main()
