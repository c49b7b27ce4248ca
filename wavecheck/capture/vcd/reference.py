"""The deliberately simple VCD reader: pyvcd's tokenizer and a plain loop per change.

Slow and meant for tests: the fast reader (:func:`wavecheck.capture.vcd.reader.read_vcd`) must
give the same capture on every file. It shares only :mod:`wavecheck.capture.vcd.header` with it
(the header parsing and the final assembly), none of the fast reader's body code.
"""

from __future__ import annotations

import io
import os
from fractions import Fraction
from typing import Any

import numpy as np

from wavecheck.capture.edges import NEVER, Capture
from wavecheck.capture.vcd.header import (
    SCALAR_VALUES,
    SignalEdges,
    build_capture,
    header_timebase,
    layout_of,
    open_vcd,
    parse_header,
    vectors_of,
)
from wavecheck.errors import CaptureError

__all__ = ["read_vcd_reference"]


def read_vcd_reference(
    path: str | os.PathLike[str],
    *,
    samplerate: Fraction | None = None,
    resolution_s: Fraction | None = None,
) -> Capture:
    """Read a VCD the simple way: pyvcd's tokenizer and a plain loop per change.

    Slow (about 0.2 M changes/s) and meant for tests: it must give the same capture as
    :func:`read_vcd`. Errors are less precise.
    """
    from vcd.reader import TokenKind, tokenize

    with open_vcd(path) as f:
        data = f.read()
    if not data.strip():
        raise CaptureError(path, None, "the file is empty (no VCD header)")
    header = parse_header(path, data)
    notes: list[str] = []
    tb = header_timebase(header, notes)
    lay = layout_of(header)
    notes += lay.notes
    index = {c: i for i, c in enumerate(lay.ids)}
    changes: list[list[tuple[int, int]]] = [[] for _ in lay.ids]
    time: int | None = None
    first: int | None = None
    pre = False
    try:
        for tok in tokenize(io.BytesIO(data)):
            payload: Any = tok.data
            if tok.kind is TokenKind.CHANGE_TIME:
                t = int(payload)
                if time is not None and t < time:
                    raise CaptureError(path, f"line {tok.span.start.line}", "time goes backwards")
                time = t
                first = t if first is None else first
            elif tok.kind in (TokenKind.CHANGE_SCALAR, TokenKind.CHANGE_VECTOR):
                code, value = payload.id_code, payload.value
                if code in lay.vector_ids:
                    continue
                if code not in index:
                    raise CaptureError(
                        path, f"line {tok.span.start.line}", f"unknown id code {code!r}"
                    )
                if tok.kind is TokenKind.CHANGE_VECTOR:
                    value = str(value)[-1]
                if time is None:
                    pre = True
                changes[index[code]].append((time or 0, SCALAR_VALUES[str(value).lower()]))
    except CaptureError:
        raise
    except Exception as err:  # pyvcd's parse errors
        raise CaptureError(path, None, f"not a valid VCD: {err}") from None
    signals: list[SignalEdges] = []
    for ch in changes:
        last_raw = -1
        last_known = -1
        initial, known_from = 0, None
        edges: list[int] = []
        xz: list[int] = []
        xz_end: list[int] = []
        # last change at a timestamp wins
        dedup = [c for j, c in enumerate(ch) if j + 1 == len(ch) or ch[j + 1][0] != c[0]]
        for t, v in dedup:
            if v >= 2:
                if last_known >= 0 and 0 <= last_raw < 2:
                    xz.append(t)
            elif last_known >= 0 and last_raw >= 2:  # a known value back after x/z
                xz_end.append(t)
            if v >= 2:
                pass
            elif last_known < 0:
                initial, known_from = v, t
                last_known = v
            elif v != last_known:
                edges.append(t)
                last_known = v
            last_raw = v
        xz_end += [NEVER] * (len(xz) - len(xz_end))
        signals.append(
            SignalEdges(
                initial,
                known_from,
                np.array(edges, dtype=np.int64),
                np.array(xz, dtype=np.int64),
                np.array(xz_end, dtype=np.int64),
            )
        )
    cap = build_capture(
        path, header, lay, tb, signals, first, time, pre, notes, samplerate, resolution_s
    )
    cap.vectors = vectors_of(header)
    cap.bit_source = os.fspath(path)
    return cap
