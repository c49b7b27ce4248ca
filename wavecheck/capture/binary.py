"""Raw logic samples, as sigrok-cli's ``-O binary`` writes them and its ``-I binary`` reads them.

Layout (``../shared/reference/sigrok.md`` §3b; checked against sigrok-cli 0.7.2): no header, one
sample after another, each ``unitsize = ceil(numchannels / 8)`` bytes, little-endian, bit n =
channel n (bits at and above ``numchannels`` are ignored). The bytes equal a ``.sr`` file's
``logic-1-*`` chunks, so the edges come from the same scan as the ``.sr`` reader's
(:class:`wavecheck.capture.sr.EdgeFinder`); tick n is sample n. Channels are named as sigrok-cli
names them (``0``, ``1``, …) unless names are given.

The input is read ``chunk_bytes`` at a time from a file or a stream (standard input, a pipe):
memory is one chunk plus the edges, whatever the length. A partial sample at the end (a stream
cut short) is refused, where sigrok-cli silently drops it.

The sample rate comes from ``--samplerate``, else the format's ``samplerate=`` option in Hz
(sigrok-cli's spelling, ``binary:numchannels=8:samplerate=24000000``); without either the data
has no time base.
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Iterator, Sequence
from fractions import Fraction
from typing import TYPE_CHECKING, BinaryIO

import numpy as np

from wavecheck.capture.common import resolution_of
from wavecheck.capture.edges import Capture, Channel
from wavecheck.capture.sr import DEFAULT_CHUNK_BYTES, EdgeFinder
from wavecheck.errors import CaptureError, UsageError
from wavecheck.progress import current
from wavecheck.timebase import Timebase
from wavecheck.units import format_frequency

if TYPE_CHECKING:
    from wavecheck.capture.blocks import EdgeBlock

__all__ = [
    "MAX_CHANNELS",
    "BinaryBlocks",
    "BinaryFormat",
    "SampleBlocks",
    "binary_blocks",
    "parse_binary_format",
    "read_binary",
]

#: The most channels a raw sample can carry here (64 bytes per sample, like the ``.sr`` reader).
MAX_CHANNELS = 512


class BinaryFormat:
    """The options of ``--input-format binary[:numchannels=N][:samplerate=HZ]``.

    Attributes:
        numchannels: channels per sample (sigrok-cli's default 8).
        samplerate: the ``samplerate=`` option in Hz (None: not given).
    """

    def __init__(self, numchannels: int = 8, samplerate: Fraction | None = None) -> None:
        self.numchannels = numchannels
        self.samplerate = samplerate

    @property
    def unitsize(self) -> int:
        """Bytes per sample."""
        return (self.numchannels + 7) // 8


def parse_binary_format(spec: str) -> BinaryFormat:
    """``"binary:numchannels=4:samplerate=1000000"`` → its options.

    Raises:
        UsageError: an unknown option, or a value that is not a positive whole number.
    """
    fmt = BinaryFormat()
    for part in spec.split(":")[1:]:
        key, sep, value = (s.strip() for s in part.partition("="))
        if key not in ("numchannels", "samplerate") or not sep:
            raise UsageError(
                f"--input-format {spec!r}: binary takes numchannels=N and samplerate=HZ, "
                f"not {part!r}"
            )
        if not value.isdigit() or int(value) == 0:
            raise UsageError(f"--input-format {spec!r}: {key}={value!r} must be a whole number ≥ 1")
        if key == "numchannels":
            if int(value) > MAX_CHANNELS:
                raise UsageError(
                    f"--input-format {spec!r}: numchannels={value} is more than {MAX_CHANNELS}"
                )
            fmt.numchannels = int(value)
        else:
            fmt.samplerate = Fraction(int(value))
    return fmt


def _read_full(f: BinaryIO, size: int) -> bytes:
    """Up to ``size`` bytes: fewer only at the end of the input (a pipe gives short reads)."""
    first = f.read(size)
    if len(first) == size or not first:
        return first
    parts = [first]
    got = len(first)
    while got < size and (more := f.read(size - got)):
        parts.append(more)
        got += len(more)
    return b"".join(parts)


def _prepare(
    label: str, spec: str, samplerate: Fraction | None, channel_names: Sequence[str] | None
) -> tuple[BinaryFormat, Fraction | None, list[str], list[str]]:
    """The format ``spec`` states, the sample rate (``samplerate`` overrides the format's), the
    channel names and the notes to give (an overridden rate)."""
    try:
        fmt = parse_binary_format(spec)
    except UsageError as err:
        raise UsageError(f"{label}: {err}") from None
    names = list(channel_names or [])
    if len(names) > fmt.numchannels:
        raise UsageError(
            f"{len(names)} channel names given for {fmt.numchannels} channels "
            f"(give --input-format binary:numchannels={len(names)})"
        )
    notes: list[str] = []
    if samplerate is not None and fmt.samplerate is not None and samplerate != fmt.samplerate:
        notes.append(
            f"sample rate {format_frequency(samplerate)} given by --samplerate overrides the "
            f"format's samplerate={fmt.samplerate}"
        )
    return fmt, samplerate if samplerate is not None else fmt.samplerate, names, notes


def _chunks(
    source: str | os.PathLike[str] | BinaryIO, label: str, step: int, *, close: bool
) -> Iterator[bytes]:
    """``step`` bytes at a time (the last piece shorter) of a file, or of a stream (closed at
    the end when ``close``), with progress; a read error is a CaptureError at its byte."""
    total: int | None = None
    report = current()
    if isinstance(source, (str, os.PathLike)):
        try:
            f: BinaryIO = open(source, "rb")  # noqa: SIM115 - closed below
            total = os.fstat(f.fileno()).st_size
        except OSError as err:
            raise CaptureError(label, None, f"cannot open: {err.strerror or err}") from None
        close = True
    else:
        f = source
    done = 0
    try:
        while data := _read_full(f, step):
            done += len(data)
            report(done, total)
            yield data
    except OSError as err:
        raise CaptureError(
            label, f"byte {done}", f"cannot be read: {err.strerror or err}"
        ) from None
    finally:
        if close:
            f.close()


def read_binary(
    source: str | os.PathLike[str] | BinaryIO,
    spec: str = "binary",
    *,
    name: str | None = None,
    samplerate: Fraction | None = None,
    resolution_s: Fraction | None = None,
    channel_names: Sequence[str] | None = None,
    chunk_bytes: int = DEFAULT_CHUNK_BYTES,
    require_time: bool = True,
) -> Capture:
    """Read raw samples from a file or a binary stream into edge arrays (tick = one sample).

    Args:
        source: a path, or an open binary stream (read to its end, not closed).
        spec: the ``--input-format`` value (``binary:numchannels=8``).
        name: what messages and the capture call the input (default: the path).
        samplerate: sample rate in Hz; overrides the format's ``samplerate=``.
        resolution_s: the resolution in seconds, if coarser than one sample.
        channel_names: names of channels 0, 1, … (fewer than numchannels: the rest keep
            sigrok-cli's names).
        chunk_bytes: bytes read and scanned at a time (tests use tiny values).
        require_time: with False, data without a sample rate is read untimed (counts only).

    Raises:
        CaptureError: empty input, a partial last sample, no sample rate.
        UsageError: bad format options or too many channel names.
    """
    label = name if name is not None else str(source)
    if chunk_bytes < 1:
        raise UsageError(f"chunk_bytes must be positive, got {chunk_bytes}")
    fmt, rate, names, notes = _prepare(label, spec, samplerate, channel_names)
    if rate is None and require_time:
        raise CaptureError(
            label, None, "raw binary data states no sample rate (give it, e.g. --samplerate 24MHz)"
        )
    if rate is None:
        notes.append(
            "raw binary data states no sample rate: edges and durations are in samples; "
            "times need --samplerate (e.g. --samplerate 24MHz)"
        )
    us = fmt.unitsize
    bits = list(range(fmt.numchannels))
    finder = EdgeFinder(us, bits)
    done = 0
    for data in _chunks(source, label, max(us, chunk_bytes - chunk_bytes % us), close=False):
        done += len(data)
        finder.add_bytes(data)
    _check_end(label, done, len(finder.partial), us, fmt.numchannels, finder.nsamples)
    tb = Timebase.from_samplerate(rate if rate is not None else 1)
    res = 1
    if resolution_s is not None and rate is not None:
        res, _ = resolution_of(label, tb, [], rate, resolution_s, notes)
    channels = [
        Channel(
            name=names[bit] if bit < len(names) else str(bit),
            index=bit,
            initial=finder.initial[slot],
            edges=finder.edges(slot),
        )
        for slot, bit in enumerate(bits)
    ]
    return Capture(
        path=label,
        format="binary",
        timebase=tb,
        resolution_ticks=res,
        samplerate_hz=rate,
        start=0,
        end=finder.nsamples,
        channels=channels,
        notes=notes,
        time_known=rate is not None,
    )


def _check_end(
    label: str, done: int, carry: int, unitsize: int, numchannels: int, nsamples: int
) -> None:
    """Refuse raw samples that end inside a sample (``carry`` bytes of one, after ``done``
    bytes) or hold none."""
    if carry:
        raise CaptureError(
            label,
            f"byte {done - carry}",
            f"the data ends in a partial sample ({carry} of {unitsize} bytes): not a whole number "
            f"of {unitsize}-byte samples for numchannels={numchannels} (cut short, or another "
            "numchannels?)",
        )
    if nsamples == 0:
        raise CaptureError(label, None, "holds no samples (the input is empty)")


class SampleBlocks:
    """Raw samples arriving piece by piece (a live analyzer's pipe), scanned into
    :class:`~wavecheck.capture.blocks.EdgeBlock` s: the engine's source for
    ``wavecheck watch``. Tick n is sample n; the time base is the sample rate, exactly.

    :meth:`scan` takes any number of bytes (a sample split across two pieces is joined) and gives
    the block of the samples completed so far; :meth:`capture` the finished skeleton.

    Args:
        label: what the capture and messages call the input (``"sigrok-cli demo (live)"``).
        numchannels: channels per sample; unitsize ``ceil(numchannels / 8)`` bytes.
        samplerate: samples per second.
        names: channel names for bits 0, 1, … (the rest are named by their bit number).
    """

    def __init__(
        self, label: str, numchannels: int, samplerate: Fraction, names: Sequence[str] = ()
    ) -> None:
        if not 1 <= numchannels <= MAX_CHANNELS:
            raise UsageError(f"numchannels must be 1..{MAX_CHANNELS}, got {numchannels}")
        self.label = label
        self.unitsize = (numchannels + 7) // 8
        self.bits = list(range(numchannels))
        self.names = [names[b] if b < len(names) else str(b) for b in self.bits]
        self.rate = samplerate
        self.finder = EdgeFinder(self.unitsize, self.bits)
        self.wanted = set(self.bits)
        self.counts = [0] * numchannels
        self.notes: list[str] = []
        self.skeleton = self._capture(0)

    @property
    def nsamples(self) -> int:
        """Whole samples scanned so far."""
        return self.finder.nsamples

    def want(self, channels: Iterable[int]) -> None:
        """Extract the edges of ``channels`` (bits) only; the others are only counted."""
        self.wanted = set(channels)
        self.finder.want(slot for slot, b in enumerate(self.bits) if b in self.wanted)

    def scan(self, data: bytes) -> EdgeBlock:
        """The block of the samples ``data`` completes (its ``end`` is :attr:`nsamples`)."""
        from wavecheck.capture.blocks import EdgeBlock

        first = self.finder.last is None
        self.finder.add_bytes(data)
        block = EdgeBlock(end=self.finder.nsamples)
        if first and self.finder.last is not None:
            block.start = 0
            block.known = {b: (0, self.finder.initial[b]) for b in self.bits}
        for b in self.bits:  # slot b is bit b
            if self.finder.wanted[b] and len(e := self.finder.edges(b)):
                block.edges[b] = e
        self.counts = list(self.finder.counted)
        return block

    @property
    def partial(self) -> int:
        """Bytes of a sample not yet complete."""
        return len(self.finder.partial)

    def _capture(self, end: int) -> Capture:
        return Capture(
            path=self.label,
            format="binary",
            timebase=Timebase.from_samplerate(self.rate),
            resolution_ticks=1,
            samplerate_hz=self.rate,
            start=0,
            end=end,
            channels=[
                Channel(
                    name=self.names[b],
                    index=b,
                    initial=self.finder.initial[b],
                    edges=np.zeros(0, dtype=np.int64),
                    counted=self.counts[b],
                )
                for b in self.bits
            ],
            notes=list(self.notes),
        )

    def capture(self) -> Capture:
        """The capture so far, without edges (each channel's edge count, the end)."""
        return self._capture(self.finder.nsamples)


class BinaryBlocks:
    """Raw samples from a file or a stream (standard input) as a block source: read and scanned
    ``chunk_bytes`` at a time (:class:`SampleBlocks`), never held whole. The engine's source for
    ``--input-format binary:…`` when the sample rate is known and no ``--resolution`` is given
    (:func:`wavecheck.capture.open.open_source`; otherwise :func:`read_binary` reads it whole).

    Raises (from :meth:`blocks`):
        CaptureError: empty input, a partial last sample, a read error.
    """

    def __init__(
        self,
        source: str | os.PathLike[str] | BinaryIO,
        fmt: BinaryFormat,
        samplerate: Fraction,
        *,
        name: str,
        channel_names: Sequence[str] = (),
        chunk_bytes: int = DEFAULT_CHUNK_BYTES,
        notes: Sequence[str] = (),
    ) -> None:
        self.source, self.label = source, name
        self.scanner = SampleBlocks(name, fmt.numchannels, samplerate, channel_names)
        self.scanner.notes += notes
        self.step = max(fmt.unitsize, chunk_bytes - chunk_bytes % fmt.unitsize)
        self.skeleton = self.scanner.skeleton
        self._read = False

    def want(self, channels: Iterable[int]) -> None:
        """Extract the edges of ``channels`` only (from the next block on)."""
        self.scanner.want(channels)

    def blocks(self) -> Iterator[EdgeBlock]:
        """A block per chunk read (the edges of the samples it completes)."""
        if self._read:
            raise UsageError(f"{self.label}: raw samples are read once (blocks taken already)")
        self._read = True
        done = 0
        for data in _chunks(self.source, self.label, self.step, close=True):
            done += len(data)
            yield self.scanner.scan(data)
        sc = self.scanner
        _check_end(self.label, done, sc.partial, sc.unitsize, len(sc.bits), sc.nsamples)

    def capture(self) -> Capture:
        """The finished skeleton (each channel's edge count, the end)."""
        return self.scanner.capture()


def binary_blocks(
    source: str | os.PathLike[str] | BinaryIO,
    spec: str,
    *,
    name: str,
    samplerate: Fraction | None,
    resolution_s: Fraction | None,
    channel_names: Sequence[str] | None,
    chunk_bytes: int | None = None,
) -> BinaryBlocks | None:
    """Raw samples as a :class:`BinaryBlocks` source, or None where they must be read whole
    (:func:`read_binary`): no sample rate (read untimed) or a ``--resolution`` to apply.
    Arguments as :func:`read_binary`'s."""
    fmt, rate, names, notes = _prepare(name, spec, samplerate, channel_names)
    if rate is None or resolution_s is not None:
        return None
    return BinaryBlocks(
        source, fmt, rate, name=name, channel_names=names,
        chunk_bytes=chunk_bytes or DEFAULT_CHUNK_BYTES, notes=notes,
    )  # fmt: skip
