"""FST and GHW through pywellen, and single bits of vectors from any simulator dump.

FST (Verilator's, GTKWave's, ``vvp -fst``) is read by GTKWave's own ``fst2vcd`` streamed into the
fast VCD reader when it is installed: measured faster per value change than pywellen's per-change
Python objects and than reading the same run's VCD (``bench/fst_read.py``, bench/README.md), in
bounded memory. GHW (GHDL's ``--wave``), and FST without ``fst2vcd``, are read with pywellen.

The semantics are the VCD reader's (:mod:`wavecheck.capture.vcd.reader`): exact integer ticks of
the file's timescale; several changes of a signal at one time, the last wins; unknown values
(VHDL's ``U``, ``X``, ``Z``, ``W``, ``-``; Verilog's ``x``, ``z``) are unknown stretches
(:meth:`Channel.unknown_stretches`); ``L``/``H`` read as 0/1.

A bit of a vector (``stout[3]``) is read only when it is mapped (:meth:`Capture.bit`): its edges
come from the vector's value changes, read again from the file with pywellen.
"""

from __future__ import annotations

import os
import shutil
import subprocess
from fractions import Fraction
from typing import Any, BinaryIO, cast

import numpy as np
import numpy.typing as npt

from wavecheck.capture.edges import Capture, Channel, Vector
from wavecheck.capture.vcd.header import SignalEdges, resolution_of
from wavecheck.capture.vcd.reader import EdgeBuilder
from wavecheck.errors import CaptureError, UsageError
from wavecheck.timebase import Timebase

__all__ = ["load_bit", "read_fst", "read_wellen"]

# unknown is 2 (x, u, w, -) or 3 (z), as in the VCD reader
_CODES = {"0": 0, "1": 1, "l": 0, "h": 1, "z": 3}


def _code(ch: str) -> int:
    return _CODES.get(ch.lower(), 2)


def _open(path: str | os.PathLike[str]) -> Any:
    import pywellen

    try:
        return pywellen.Waveform(str(path), multi_threaded=False)
    except Exception as err:  # pywellen raises its own (Rust) errors with the reason
        raise CaptureError(path, None, f"cannot read the waveform: {err}") from None


def _timebase(w: Any) -> Timebase:
    ts = w.timescale
    if ts is None:
        return Timebase(Fraction(1))
    return Timebase(Fraction(int(ts.factor)) * Fraction(10) ** int(ts.unit.to_exponent()))


def _changes(sig: Any, width: int, pos: int) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.int8]]:
    """Times and value codes of bit ``pos`` (0 = rightmost) of a pywellen signal."""
    pairs = list(sig)
    times = np.fromiter((t for t, _ in pairs), dtype=np.int64, count=len(pairs))
    codes = np.empty(len(pairs), dtype=np.int8)
    for i, (_, v) in enumerate(pairs):
        if isinstance(v, int):
            codes[i] = (v >> pos) & 1
        else:
            text = str(v)
            if len(text) < width:  # a shortened value extends with x/z, else with 0
                text = text.rjust(width, text[0] if text[:1].lower() in ("x", "z") else "0")
            codes[i] = _code(text[len(text) - 1 - pos])
    return times, codes


def _edges(times: npt.NDArray[np.int64], codes: npt.NDArray[np.int8]) -> SignalEdges:
    b = EdgeBuilder(1)
    b.add(np.zeros(len(times), dtype=np.int32), times, codes)
    return b.signals()[0]


def read_wellen(
    path: str | os.PathLike[str],
    *,
    kind: str,
    samplerate: Fraction | None = None,
    resolution_s: Fraction | None = None,
) -> Capture:
    """Read the 1-bit signals of an FST or GHW file with pywellen (``kind`` ``"fst"``/``"ghw"``).

    Raises:
        CaptureError: pywellen cannot read the file (its reason is given).
    """
    w = _open(path)
    tb = _timebase(w)
    notes: list[str] = []
    variables = list(w.all_vars())
    by_short: dict[str, int] = {}
    for v in variables:
        by_short[v.name] = by_short.get(v.name, 0) + 1
    seen: dict[Any, str] = {}  # signal id -> channel name (a signal declared twice)
    aliases: dict[str, str] = {}
    skipped: dict[str, str] = {}
    vectors: dict[str, Vector] = {}
    found: list[tuple[str, SignalEdges]] = []
    first, last = None, None
    for v in variables:
        full = v.full_name
        if v.is_real or v.is_string:
            skipped[full] = "a real" if v.is_real else "a string"
            continue
        width = int(v.bitwidth or 0)
        if width != 1:
            if width > 1:
                vectors[full] = Vector(width, width - 1, 0, full)
                skipped.setdefault(full, f"a {width}-bit vector")
            continue
        ref = v.signal_ref
        key = ref.index() if hasattr(ref, "index") else id(ref)
        name = v.name if by_short[v.name] == 1 else full
        if key in seen:
            aliases[full] = seen[key]
            continue
        times, codes = _changes(v.signal, 1, 0)
        if len(times):
            first = int(times[0]) if first is None else min(first, int(times[0]))
            last = int(times[-1]) if last is None else max(last, int(times[-1]))
        seen[key] = name
        if name != full:
            aliases[full] = name
        found.append((name, _edges(times, codes)))
    if vectors:
        notes.append(
            f"{len(vectors)} vector(s) not read as channels; a bit of one maps as a channel "
            "(--map step=NAME[0]); ranges taken as [width-1:0]"
        )
    start, end = first or 0, last or 0
    channels = [s.channel(n, i, end) for i, (n, s) in enumerate(found)]
    never = [c.name for c in channels if c.never_known]
    if never:
        notes.append(f"{len(never)} channel(s) never have a known level: {', '.join(never[:10])}")
    res, rate = resolution_of(path, tb, [], samplerate, resolution_s, notes)
    return Capture(
        path=str(path),
        format=kind,
        timebase=tb,
        resolution_ticks=res,
        samplerate_hz=rate,
        start=start,
        end=end,
        channels=channels,
        notes=notes,
        skipped=skipped,
        aliases=aliases,
        vectors=vectors,
        bit_source=str(path),
    )


def read_fst(
    path: str | os.PathLike[str],
    *,
    samplerate: Fraction | None = None,
    resolution_s: Fraction | None = None,
) -> Capture:
    """Read an FST file: GTKWave's ``fst2vcd`` streamed into the VCD reader, or pywellen when
    ``fst2vcd`` is not installed (slower per value change, same result).

    Raises:
        CaptureError: the file cannot be read as FST.
    """
    tool = shutil.which("fst2vcd")
    if tool is None:
        return read_wellen(path, kind="fst", samplerate=samplerate, resolution_s=resolution_s)
    from wavecheck.capture.vcd import read_vcd

    with subprocess.Popen(
        [tool, os.fspath(path)], stdout=subprocess.PIPE, stderr=subprocess.PIPE
    ) as proc:
        assert proc.stdout is not None
        try:
            cap = read_vcd(
                path,
                samplerate=samplerate,
                resolution_s=resolution_s,
                source=cast(BinaryIO, proc.stdout),
            )
        except CaptureError as err:
            proc.kill()
            raise CaptureError(path, None, f"not a readable FST file ({err.msg})") from None
        finally:
            proc.stdout.close()
        err_text = proc.stderr.read().decode("utf-8", "replace").strip() if proc.stderr else ""
        if proc.wait() != 0:
            raise CaptureError(path, None, f"fst2vcd cannot read it: {err_text[:200]}")
    cap.format = "fst"
    cap.bit_source = str(path)
    cap.notes = [n for n in cap.notes if "$comment" not in n]
    return cap


def load_bit(capture: Capture, key: str, vec: Vector, bit: int) -> Channel:
    """Bit ``bit`` (declared index) of vector ``key`` of ``capture`` as a new channel.

    Raises:
        UsageError: the bit is outside the vector's range, or the file cannot be read again.
    """
    pos = vec.position(bit)
    if pos is None:
        raise UsageError(
            f"{capture.path}: {key}{vec.range_text} has no bit {bit} "
            f"(bits {min(vec.msb, vec.lsb)} to {max(vec.msb, vec.lsb)})"
        )
    if capture.bit_source is None:
        raise UsageError(
            f"{capture.path}: a bit of a vector ({key}[{bit}]) can be mapped only from a file "
            "(the vector's changes are read again); save the input to a file first"
        )
    w = _open(capture.bit_source)
    var = next((v for v in w.all_vars() if v.full_name == key), None)
    if var is None:
        raise UsageError(f"{capture.path}: vector {key!r} not found when reading it again")
    times, codes = _changes(var.signal, vec.width, pos)
    index = max((c.index for c in capture.channels), default=-1) + 1
    return _edges(times, codes).channel(f"{key}[{bit}]", index, capture.end)
