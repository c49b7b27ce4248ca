"""FST and GHW through pywellen, and single bits of vectors from any simulator dump.

FST (Verilator's, GTKWave's, ``vvp -fst``) is decoded natively (:mod:`wavecheck.capture.fst`);
a FastLZ-packed one (``vcd2fst -F``, which that decoder leaves out) is read by GTKWave's own
``fst2vcd`` streamed into the fast VCD reader when it is installed, else by pywellen
(``bench/fst_read.py``, bench/README.md). GHW (GHDL's ``--wave``) is read with pywellen.

The semantics are the VCD reader's (:mod:`wavecheck.capture.vcd.reader`): exact integer ticks of
the file's timescale; several changes of a signal at one time, the last wins; unknown values
(VHDL's ``U``, ``X``, ``Z``, ``W``, ``-``; Verilog's ``x``, ``z``) are unknown stretches
(:meth:`Channel.unknown_stretches`); ``L``/``H`` read as 0/1.

A bit of a vector (``stout[3]``) is read only when it is mapped (:meth:`Capture.bit`): its edges
come from the vector's value changes, read again from the file with pywellen.
"""

from __future__ import annotations

import contextlib
import io
import os
import re
import select
import shutil
import subprocess
import sys
import tempfile
from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from fractions import Fraction
from typing import TYPE_CHECKING, Any, BinaryIO, cast

import numpy as np

from wavecheck.capture.common import path_argument, resolution_of
from wavecheck.capture.edges import Capture, Channel, Vector
from wavecheck.capture.ghw import DEFAULT_TIME_UNIT, read_ghw_header
from wavecheck.capture.vcd.header import SignalEdges
from wavecheck.capture.vcd.reader import EdgeBuilder
from wavecheck.errors import CaptureError, UsageError
from wavecheck.timebase import Timebase
from wavecheck.units import format_time

if TYPE_CHECKING:
    import numpy.typing as npt

    from wavecheck.capture.blocks import EdgeBlock

__all__ = ["FstBlocks", "ghw_timebase", "load_bit", "read_fst", "read_wellen"]

#: pywellen's text of a signal's identity (``str(var.signal_ref)``)
_SIGNAL_ID = re.compile(r"SignalId\((\d+)\)")

# unknown is 2 (x, u, w, -) or 3 (z), as in the VCD reader
_CODES = {"0": 0, "1": 1, "l": 0, "h": 1, "z": 3}


def _code(ch: str) -> int:
    return _CODES.get(ch.lower(), 2)


@contextlib.contextmanager
def _rust_output() -> Iterator[list[str]]:
    """While pywellen runs, its Rust code's output goes to a temporary file, not the user's
    terminal: warnings are printed to standard output (``WARN: time decreased … Skipping!``)
    and panics to standard error. The lines (at most 64 KiB) are added to the list yielded."""
    lines: list[str] = []
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(Exception):
            stream.flush()
    with tempfile.TemporaryFile() as tmp:
        try:
            saved = [os.dup(1), os.dup(2)]
        except OSError:  # a closed descriptor: nothing to keep clean
            yield lines
            return
        try:
            os.dup2(tmp.fileno(), 1)
            os.dup2(tmp.fileno(), 2)
            yield lines
        finally:
            os.dup2(saved[0], 1)
            os.dup2(saved[1], 2)
            for fd in saved:
                os.close(fd)
            tmp.seek(0)
            lines += tmp.read(1 << 16).decode("utf-8", "replace").splitlines()


def _reason(err: BaseException) -> str:
    text = " ".join(str(err).split()) or type(err).__name__
    return text.removeprefix("failed to load Ghw: ").removeprefix("[ghw] ")[:200]


@contextlib.contextmanager
def _guarded(path: str | os.PathLike[str], kind: str) -> Iterator[None]:
    """Run pywellen on ``path``: every failure, a Rust panic included (pyo3's PanicException
    is not an Exception), and every warning that data was skipped, is one CaptureError."""
    failure: BaseException | None = None
    with _rust_output() as lines:
        try:
            yield
        except (KeyboardInterrupt, SystemExit, GeneratorExit, CaptureError):
            raise
        except BaseException as err:  # noqa: BLE001 - a Rust panic derives from BaseException
            failure = err
    if failure is not None:
        raise CaptureError(path, None, f"cannot read the {kind} file: {_reason(failure)}")
    skipped = [ln for ln in lines if "decreased" in ln or "Skipping" in ln]
    if skipped:
        raise CaptureError(
            path, None, f"corrupt {kind} file: {skipped[0].removeprefix('WARN: ')[:160]}"
        )


def _open(path: str | os.PathLike[str]) -> Any:
    import pywellen

    return pywellen.Waveform(str(path), multi_threaded=False)


def _timebase(w: Any) -> Timebase:
    ts = w.timescale
    if ts is None:
        return Timebase(Fraction(1))
    return Timebase(Fraction(int(ts.factor)) * Fraction(10) ** int(ts.unit.to_exponent()))


def _changes(sig: Any, width: int, pos: int) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.int8]]:
    """Times and value codes of bit ``pos`` (0 = rightmost) of a pywellen signal."""
    pairs = list(sig)
    n = len(pairs)
    times = np.fromiter((t for t, _ in pairs), dtype=np.int64, count=n)
    values = [v for _, v in pairs]
    if set(map(type, values)) <= {int}:  # every value known: the bits at once
        return times, (
            (np.array(values, dtype=object if width > 62 else np.int64) >> pos) & 1
        ).astype(np.int8)
    codes = np.empty(n, dtype=np.int8)
    for i, v in enumerate(values):
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


@dataclass
class _Var:
    """What read_wellen needs of one pywellen variable (read inside the guard)."""

    full: str
    name: str
    width: int
    skipped: str | None = None  # "a real", "a string"
    key: int | None = None  # the signal's index (a signal declared twice has one); None: unknown
    times: npt.NDArray[np.int64] | None = None
    codes: npt.NDArray[np.int8] | None = None


def _signal_key(ref: Any) -> int | None:
    """The index of the signal a pywellen variable reads (a port and the signal it is
    connected to, ``tb.a`` and ``tb.dut.a`` in a GHW file, share one), or None when pywellen
    does not tell it. pywellen 0.25's ``SignalId`` gives its index only in its text
    (``SignalId(7)``); the object is made anew at each access, so its ``id()`` is no identity:
    once the object is freed, another signal's may get the same address."""
    index = getattr(ref, "index", None)
    if callable(index):
        return int(index())
    found = _SIGNAL_ID.fullmatch(str(ref))
    return int(found.group(1)) if found else None


def _load(path: str | os.PathLike[str]) -> tuple[Timebase, list[_Var]]:
    """The time base and variables of a pywellen waveform, the 1-bit ones with their changes
    (read once per signal: a second name of one has its key only)."""
    w = _open(path)
    out: list[_Var] = []
    read: set[int] = set()
    for v in w.all_vars():
        var = _Var(v.full_name, v.name, int(v.bitwidth or 0))
        if v.is_real or v.is_string:
            var.skipped = "a real" if v.is_real else "a string"
        elif var.width == 1:
            var.key = _signal_key(v.signal_ref)
            if var.key is None or var.key not in read:
                var.times, var.codes = _changes(v.signal, 1, 0)
            if var.key is not None:
                read.add(var.key)
        out.append(var)
    return _timebase(w), out


def read_wellen(
    path: str | os.PathLike[str],
    *,
    kind: str,
    samplerate: Fraction | None = None,
    resolution_s: Fraction | None = None,
    timescale: Fraction | None = None,
) -> Capture:
    """Read the 1-bit signals of an FST or GHW file with pywellen (``kind`` ``"fst"``/``"ghw"``).

    A GHW file records no time unit (:mod:`wavecheck.capture.ghw`): its ticks are
    ``timescale`` seconds each, by default GHDL's default resolution (1 fs), and a note says
    which; its vectors' declared ranges come from its header.

    Raises:
        CaptureError: the file cannot be read (its reason is given), is corrupt, or its header
            is malformed.
    """
    notes: list[str] = []
    ranges: dict[str, tuple[int, int]] = {}
    if kind == "ghw":
        ranges = read_ghw_header(path).ranges
    with _guarded(path, kind.upper()):
        tb, variables = _load(path)
    if kind == "ghw":
        tb, note = ghw_timebase(timescale)
        notes.append(note)
    by_short: dict[str, int] = {}
    for v in variables:
        by_short[v.name] = by_short.get(v.name, 0) + 1
    seen: dict[int, str] = {}  # signal index -> channel name (a signal declared twice)
    aliases: dict[str, str] = {}
    skipped: dict[str, str] = {}
    vectors: dict[str, Vector] = {}
    unranged: list[str] = []
    found: list[tuple[str, SignalEdges]] = []
    first, last = None, None
    for v in variables:
        full = v.full
        if v.skipped:
            skipped[full] = v.skipped
            continue
        if v.width != 1:
            if v.width > 1:
                if full in ranges:
                    vectors[full] = Vector(v.width, *ranges[full], full)
                else:
                    unranged.append(full)
                skipped.setdefault(full, f"a {v.width}-bit vector")
            continue
        name = v.name if by_short[v.name] == 1 else full
        if v.key is not None and v.key in seen:
            aliases[full] = seen[v.key]
            continue
        assert v.times is not None and v.codes is not None
        if len(v.times):
            first = int(v.times[0]) if first is None else min(first, int(v.times[0]))
            last = int(v.times[-1]) if last is None else max(last, int(v.times[-1]))
        if v.key is not None:
            seen[v.key] = name
        if name != full:
            aliases[full] = name
        found.append((name, _edges(v.times, v.codes)))
    if vectors:
        notes.append(
            f"{len(vectors)} vector(s) not read as channels; a bit of one maps as a channel "
            "(--map step=NAME[0], NAME[i] an index of its declared range)"
        )
    if unranged:
        why = (
            "pywellen does not give an FST vector's declared range (GTKWave's fst2vcd does: "
            "install gtkwave)"
            if kind == "fst"
            else "integers and enumerations have no range of bits"
        )
        notes.append(
            f"{len(unranged)} vector(s) whose bits cannot be mapped ({', '.join(unranged[:5])}): "
            + why
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


def ghw_timebase(timescale: Fraction | None) -> tuple[Timebase, str]:
    """The time base of a GHW file's ticks and the note that says how it was decided."""
    if timescale is not None:
        return Timebase(timescale), (
            f"time unit: {format_time(timescale)} per tick (ghw:timescale given; a GHW file "
            "records none)"
        )
    unit = Fraction(1, 10**15)
    return Timebase(unit), (
        f"time unit: 1 {DEFAULT_TIME_UNIT} per tick ASSUMED: a GHW file records none, and 1 fs "
        "is GHDL's default --time-resolution; if the simulation ran with another (e.g. "
        "--time-resolution=ps), give --input-format ghw:timescale=1ps"
    )


#: Seconds fst2vcd may go without output before it is taken as hung (a corrupt FST can make
#: GTKWave 3.3's fst2vcd loop forever without output).
FST2VCD_STALL_SECONDS = 10.0
#: fst2vcd's output may be at most this many times the FST file (plus 64 MiB): a real FST is
#: 5-50 times smaller than its VCD; a corrupt one could make fst2vcd write forever.
FST2VCD_MAX_EXPANSION = 4096


class _Watched(io.RawIOBase):
    """fst2vcd's standard output for the VCD reader, with bounds: no output for
    :data:`FST2VCD_STALL_SECONDS`, or more than ``limit`` bytes, kills it (a CaptureError)."""

    def __init__(self, path: str | os.PathLike[str], proc: subprocess.Popen[bytes], limit: int):
        super().__init__()
        assert proc.stdout is not None
        self.path = path
        self.proc = proc
        self.fd = proc.stdout.fileno()
        self.left = limit

    def readable(self) -> bool:
        return True

    def readinto(self, buffer: Any) -> int:
        if not select.select([self.fd], [], [], FST2VCD_STALL_SECONDS)[0]:
            self.proc.kill()
            raise CaptureError(
                self.path, None, f"fst2vcd gave nothing for {FST2VCD_STALL_SECONDS:g} s (a "
                "corrupt FST file?): stopped",
            )  # fmt: skip
        data = os.read(self.fd, min(len(buffer), 1 << 20))
        self.left -= len(data)
        if self.left < 0:
            self.proc.kill()
            raise CaptureError(
                self.path,
                None,
                "fst2vcd's output grows beyond any FST's (a corrupt file?): stopped",
            )
        memoryview(buffer).cast("B")[: len(data)] = data
        return len(data)


def read_fst(
    path: str | os.PathLike[str],
    *,
    samplerate: Fraction | None = None,
    resolution_s: Fraction | None = None,
) -> Capture:
    """Read an FST file: decoded natively (:mod:`wavecheck.capture.fst_source`); a FastLZ-packed
    one through GTKWave's ``fst2vcd`` streamed into the VCD reader, or pywellen when ``fst2vcd``
    is not installed (same result, slower). fst2vcd is bounded (:class:`_Watched`): it is
    stopped when it stalls or writes beyond any FST's expansion.

    Raises:
        CaptureError: the file cannot be read as FST.
    """
    from wavecheck.capture.fst import FstUnsupported
    from wavecheck.capture.fst_source import read_native

    try:
        return read_native(path, samplerate=samplerate, resolution_s=resolution_s)
    except FstUnsupported:
        pass  # FastLZ packing: GTKWave's reader, or pywellen's
    tool = shutil.which("fst2vcd")
    if tool is None:
        return read_wellen(path, kind="fst", samplerate=samplerate, resolution_s=resolution_s)
    from wavecheck.capture.blocks import assemble

    source = FstBlocks(path, tool, samplerate=samplerate, resolution_s=resolution_s)
    blocks = list(source.blocks())
    cap = assemble(source.capture(), blocks)
    cap.bit_reader = None  # read: a bit of a vector comes from the file again (load_bit)
    return cap


class FstBlocks:
    """An FST file as a block source: GTKWave's ``fst2vcd`` (``tool``: its path) streamed into
    :class:`~wavecheck.capture.vcd.reader.VcdBlocks`, never held whole; fst2vcd is bounded
    (:class:`_Watched`) and stopped however the source is left. :func:`read_fst` is these
    blocks assembled.

    Raises (from the constructor and :meth:`blocks`):
        CaptureError: the file cannot be read as FST, or fst2vcd fails or stalls.
    """

    def __init__(
        self,
        path: str | os.PathLike[str],
        tool: str,
        *,
        samplerate: Fraction | None = None,
        resolution_s: Fraction | None = None,
        chunk_bytes: int | None = None,
    ) -> None:
        import weakref

        from wavecheck.capture.vcd.reader import DEFAULT_CHUNK_BYTES, VcdBlocks

        self.path = path
        try:
            limit = FST2VCD_MAX_EXPANSION * os.path.getsize(path) + (64 << 20)
        except OSError as err:
            raise CaptureError(path, None, f"cannot open: {err.strerror or err}") from None
        self._errors = tempfile.TemporaryFile()  # noqa: SIM115 - closed with the process
        self.proc = subprocess.Popen(
            [tool, path_argument(path)], stdout=subprocess.PIPE, stderr=self._errors
        )
        weakref.finalize(self, _end, self.proc, self._errors)  # however the source is left
        source = io.BufferedReader(_Watched(path, self.proc, limit), buffer_size=1 << 20)
        try:
            self.vcd = VcdBlocks(
                path, samplerate=samplerate, resolution_s=resolution_s,
                chunk_bytes=chunk_bytes or DEFAULT_CHUNK_BYTES, source=cast(BinaryIO, source),
            )  # fmt: skip
        except CaptureError as err:
            _end(self.proc, self._errors)
            raise CaptureError(path, None, f"not a readable FST file ({err.msg})") from None
        self.skeleton = self._as_fst(self.vcd.skeleton)

    def _as_fst(self, cap: Capture) -> Capture:
        cap.format = "fst"
        cap.notes = [n for n in cap.notes if "$comment" not in n]
        return cap

    def want(self, channels: Iterable[int]) -> None:
        """Extract the edges of ``channels`` only (from the next block on)."""
        self.vcd.want(channels)

    def blocks(self) -> Iterator[EdgeBlock]:
        """The VCD reader's blocks of fst2vcd's output; fst2vcd's exit status checked at the end."""
        try:
            yield from self.vcd.blocks()
        except CaptureError as err:
            _end(self.proc, self._errors)
            raise CaptureError(self.path, None, f"not a readable FST file ({err.msg})") from None
        status = self.proc.wait()
        self._errors.seek(0)
        err_text = self._errors.read(4096).decode("utf-8", "replace").strip()
        _end(self.proc, self._errors)
        if status != 0:
            raise CaptureError(self.path, None, f"fst2vcd cannot read it: {err_text[:200]}")

    def capture(self) -> Capture:
        """The finished skeleton, as :func:`read_fst` names it."""
        cap = self._as_fst(self.vcd.capture())
        cap.bit_source = str(self.path)
        return cap


def _end(proc: subprocess.Popen[bytes], errors: Any) -> None:
    """Stop fst2vcd if it still runs and close its pipes."""
    if proc.poll() is None:
        proc.kill()
        proc.wait()
    if proc.stdout is not None:
        proc.stdout.close()
    errors.close()


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
    with _guarded(capture.bit_source, capture.format.upper()):
        w = _open(capture.bit_source)
        var = next((v for v in w.all_vars() if v.full_name == key), None)
        if var is not None:
            times, codes = _changes(var.signal, vec.width, pos)
    if var is None:
        raise UsageError(f"{capture.path}: vector {key!r} not found when reading it again")
    index = max((c.index for c in capture.channels), default=-1) + 1
    return _edges(times, codes).channel(f"{key}[{bit}]", index, capture.end)
