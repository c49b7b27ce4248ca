"""sigrok-cli's side of the cross-check: the ``.sr`` it reads, one run of its ``counter`` and
``stepper_motor`` decoders, and the parsing of their annotations.

Input: a ``.sr`` is given to sigrok-cli as is (sample n = tick n). A VCD is first written with only
the mapped 1-bit wires (sigrok's VCD input aborts on vectors, ``../shared/reference/sigrok.md``
§7) and converted to ``.sr`` with an explicit ``downsample`` no larger than the shortest gap
between any two STEP/DIR edges, so no pulse or DIR/STEP order is lost (§7: "downsampling drops
pulses"). Other formats are converted again by sigrok-cli. sigrok-cli's exit status is not
trusted (stderr is checked, see :mod:`wavecheck.capture.sigrokcli`).

Output: a line per step and decoder (~80 bytes a step), written to a file and read back a block
at a time, with numpy where the block holds only the two decoders' usual lines
(:func:`parse_annotation_file`; :func:`parse_annotations` is the plain line reader).
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path

import numpy as np

from wavecheck.capture.edges import Capture, EdgeArray
from wavecheck.capture.sigrokcli import SAMPLERATE_OPTION_FORMATS, convert, run_sigrok, show
from wavecheck.capture.vcd.writer import VcdWire, write_vcd
from wavecheck.drives.datasheet import ActiveEdge
from wavecheck.errors import CaptureError, UsageError
from wavecheck.units import SI_TIME

__all__ = [
    "MAX_SAMPLES",
    "DecoderOutput",
    "SigrokInput",
    "parse_annotation_file",
    "parse_annotations",
    "pick_downsample",
    "prepare_input",
    "run_decoders",
]

#: Above this many samples a VCD conversion is refused (sigrok-cli needs ~1 min per 1e10).
MAX_SAMPLES = 2 * 10**9
_LINE = re.compile(r"^(\d+)-(\d+) (\S+?)-\d+: (.*)$")
_UNITS = tuple((-exp, name) for name, exp in SI_TIME[:6])  # s down to fs


@dataclass(frozen=True)
class SigrokInput:
    """The ``.sr`` sigrok-cli decodes: its path, the names of the mapped channels in it (step,
    then dir), the capture ticks per sample (1 unless a VCD was downsampled), and whether it is
    a conversion (not the capture itself)."""

    path: str
    channels: list[str]
    downsample: int
    converted: bool
    offset: int = 0
    """Samples every edge was moved later by (1 when an edge would fall on sample 0, where
    sigrok takes it for the initial level)."""
    lost: int = 0
    """Edges the downsample merged into another's sample (lost to sigrok: a given
    ``--downsample`` above the shortest gap)."""

    @property
    def description(self) -> str:
        """What sigrok-cli read, for the report."""
        return (
            f"converted .sr (downsample {self.downsample})" if self.converted else "the .sr itself"
        )


@dataclass(frozen=True, eq=False)
class DecoderOutput:
    """What the decoders printed: ``counter`` values (int64), ``stepper_motor`` lines as rows
    (start sample, end sample, position) of an (n, 3) int64 array."""

    counts: np.ndarray
    positions: np.ndarray

    @classmethod
    def of(cls, counts: Sequence[int], positions: Sequence[tuple[int, int, int]]) -> DecoderOutput:
        """From lists (as printed)."""
        return cls(
            np.array(counts, dtype=np.int64),
            np.array(positions, dtype=np.int64).reshape(-1, 3),
        )


def _sigrok_name(name: str, path: str) -> str:
    if ":" in name or "=" in name:
        raise UsageError(
            f"{path}: channel name {name!r} contains ':' or '=', which sigrok-cli's decoder "
            "options cannot carry (rename the channel)"
        )
    return name


def pick_downsample(times: list[EdgeArray]) -> int:
    """The largest downsample that keeps every pair of distinct edge times in distinct samples:
    the shortest gap between successive distinct times (1 when there are fewer than two)."""
    allt = np.sort(np.concatenate([np.asarray(t, dtype=np.int64) for t in times]))
    if len(allt) < 2:
        return 1
    gaps = np.diff(allt)
    gaps = gaps[gaps > 0]
    return int(gaps.min()) if len(gaps) else 1


def _unit_for(tick_s: Fraction) -> tuple[str, int]:
    """A timescale ``1 <unit>`` that divides ``tick_s``, and the tick in those units."""
    for exp, unit in _UNITS:
        m = tick_s * 10**exp
        if m.denominator == 1:
            return unit, int(m)
    raise UsageError(f"tick {tick_s} s is not a whole number of femtoseconds")


#: sigrok-cli keeps the VCD input's ``downsample`` in a signed 32-bit int (it wraps above).
MAX_SIGROK_DOWNSAMPLE = 2**31 - 1


def merged_edges(edges: EdgeArray, ds: int) -> int:
    """Edges of one channel that share their sample with another after ``// ds`` (two toggles in
    one sample cancel; of an odd number, one survives)."""
    _, counts = np.unique(np.asarray(edges, dtype=np.int64) // ds, return_counts=True)
    return int(np.sum(np.where(counts % 2 == 0, counts, counts - 1)))


def _write_mapped_vcd(
    capture: Capture, names: list[str], out_names: list[str], path: Path, ds: int, offset: int
) -> int:
    """The channels ``names`` only (called ``out_names``), already downsampled: each edge at
    sample ``tick // ds`` (distinct edge times stay distinct, as ``ds`` is at most their shortest
    gap), ending one sample after the last edge (sigrok drops the values at the last one).

    The timescale is the sample period ``ds`` ticks where a VCD timescale can state it; the
    returned factor (the ``downsample`` sigrok-cli is given, always below 2^31) is what the
    sample numbers are scaled by in the file. A 1 fs VCD (GHDL's default) once needed a factor
    above 2^31 here, which sigrok-cli wraps.
    """
    chans = [capture.channel(n) for n in names]
    last = max([capture.end, *(int(c.edges[-1]) for c in chans if len(c.edges))]) // ds + 1 + offset
    unit, factor = _unit_for(capture.timebase.tick_s * ds)
    if factor > MAX_SIGROK_DOWNSAMPLE:
        unit, factor = "s", 1  # the sample period cannot be stated: sample numbers stay exact
    write_vcd(
        path,
        [
            VcdWire(o, c.initial, (np.asarray(c.edges, dtype=np.int64) // ds + offset) * factor)
            for o, c in zip(out_names, chans, strict=True)
        ],
        timescale=f"1 {unit}",
        end=last * factor,
        scope="crosscheck",
    )
    return factor


def prepare_input(
    capture: Capture,
    names: list[str],
    edges: list[EdgeArray],
    tmp: Path,
    *,
    downsample: int | None,
    input_format: str | None,
) -> SigrokInput:
    """The ``.sr`` for sigrok-cli: ``capture`` itself, or a conversion written into ``tmp``.

    ``names`` are the mapped channels (step, then dir), ``edges`` their edges (for a VCD's
    downsample).

    Raises:
        UsageError: a channel name sigrok-cli cannot take, a conversion too large.
        CaptureError: sigrok-cli fails, or the conversion has no samples.
    """
    if capture.format == "sr":
        return SigrokInput(
            capture.path, [_sigrok_name(n, capture.path) for n in names], 1, converted=False
        )
    sr = str(tmp / "capture.sr")
    ds, offset, lost = 1, 0, 0
    if capture.format == "vcd" or ":" not in capture.format:  # not read through sigrok-cli
        ds = downsample or pick_downsample(edges)
        if (capture.end // ds) > MAX_SAMPLES:
            raise UsageError(
                f"{capture.path}: converting for sigrok-cli would make "
                f"{capture.end // ds} samples (downsample {ds}); give --downsample N"
            )
        sr_names = ["step", "dir"][: len(names)]
        vcd = tmp / "mapped.vcd"
        # an edge on sample 0 would be taken for the initial level: every edge a sample later
        offset = int(any(len(e) and int(np.min(e)) // ds <= 0 for e in edges))
        lost = sum(merged_edges(e, ds) for e in edges)
        factor = _write_mapped_vcd(capture, names, sr_names, vcd, ds, offset)
        convert(vcd, sr, input_format=f"vcd:downsample={factor}:skip=0")
    else:
        # the same sigrok-cli input spec the capture was read with (options included)
        fmt = input_format or capture.format.split(":", 1)[1]
        name = fmt.split(":", 1)[0]
        rate = capture.samplerate_hz
        if (
            name in SAMPLERATE_OPTION_FORMATS
            and "samplerate=" not in fmt
            and rate is not None
            and rate.denominator == 1
        ):
            fmt = f"{fmt}:samplerate={int(rate)}"
        convert(capture.path, sr, input_format=fmt)
        sr_names = [_sigrok_name(n, capture.path) for n in names]
    info = show(sr)
    if not info.sample_count:
        raise CaptureError(capture.path, "sigrok-cli", "the converted capture has 0 samples")
    return SigrokInput(sr, sr_names, ds, converted=True, offset=offset, lost=lost)


def run_decoders(
    sr: str, step: str, dir_: str | None, edge: ActiveEdge, path: str, tmp: Path
) -> DecoderOutput:
    """One sigrok-cli run of ``counter`` (on ``edge``) and, with a DIR, ``stepper_motor``.

    Their annotations (a line per step and decoder: ~80 bytes a step) go to a file in ``tmp``,
    read back a block at a time (:func:`parse_annotation_file`), so memory does not grow with
    them.

    Raises:
        UsageError: ``edge`` is ``both`` (sigrok's counter counts one edge).
        CaptureError: sigrok-cli fails, or prints a line that cannot be read.
    """
    counter_edge = "rising" if edge == "rising" else "falling"
    args = ["-i", sr]
    ann = []
    if dir_ is not None:
        args += ["-P", f"stepper_motor:step={step}:dir={dir_}"]
        ann.append("stepper_motor=position")
    if edge == "both":
        raise UsageError("crosscheck: --active-edge both is not supported (sigrok counts one edge)")
    args += ["-P", f"counter:data={step}:data_edge={counter_edge}"]
    ann.append("counter=edge_count")
    args += ["-A", ",".join(ann), "--protocol-decoder-samplenum"]
    out = tmp / "annotations.txt"
    with open(out, "wb") as fh:
        run_sigrok(args, path=path, stdout=fh)
    return parse_annotation_file(out, path)


def parse_annotations(out: str, path: str) -> DecoderOutput:
    """The ``counter`` values and ``stepper_motor`` positions in sigrok-cli's output
    (``--protocol-decoder-samplenum`` lines ``SS-ES decoder-N: text``); other lines are ignored.
    The plain reader, line by line; :func:`parse_annotation_file` gives the same faster.

    Raises:
        CaptureError: a ``stepper_motor`` line that is not ``N steps``, a ``counter`` line that
            is not a number, a number beyond 64 bits.
    """
    counts: list[int] = []
    positions: list[tuple[int, int, int]] = []
    for line in out.splitlines():
        m = _LINE.match(line.strip())
        if not m:
            continue
        ss, es, pd, text = int(m.group(1)), int(m.group(2)), m.group(3), m.group(4)
        if pd == "counter":
            try:
                numbers = [int(text)]
            except ValueError:
                raise CaptureError(
                    path, "sigrok-cli", f"unexpected counter line {line!r}"
                ) from None
            counts.append(numbers[0])
        elif pd == "stepper_motor":
            pm = re.fullmatch(r"(-?\d+) steps", text.strip())
            if pm is None:
                raise CaptureError(path, "sigrok-cli", f"unexpected stepper_motor line {line!r}")
            numbers = [ss, es, int(pm.group(1))]
            positions.append((ss, es, numbers[2]))
        else:
            continue
        if any(not -(2**63) <= x < 2**63 for x in numbers):
            raise CaptureError(path, "sigrok-cli", f"number out of range in line {line!r}")
    return DecoderOutput.of(counts, positions)


#: Bytes of sigrok-cli's annotations read at a time.
READ_BYTES = 1 << 20


def parse_annotation_file(file: Path, path: str, block: int = READ_BYTES) -> DecoderOutput:
    """:func:`parse_annotations` of a file, a block of whole lines at a time: with numpy
    (:func:`_parse_plain_lines`) where every line of the block is a ``counter`` or
    ``stepper_motor`` line in its usual form, else with :func:`parse_annotations`."""
    counts: list[np.ndarray] = []
    positions: list[np.ndarray] = []

    def parse(data: bytes) -> None:
        got = _parse_plain_lines(data)
        if got is None:
            got = parse_annotations(data.decode("utf-8", "replace"), path)
        counts.append(got.counts)
        positions.append(got.positions)

    with open(file, "rb") as fh:
        rest = b""
        while chunk := fh.read(block):
            data = rest + chunk
            cut = data.rfind(b"\n") + 1
            rest = data[cut:]
            if cut:
                parse(data[:cut])
        if rest:
            parse(rest)
    return DecoderOutput(
        np.concatenate(counts) if counts else np.zeros(0, dtype=np.int64),
        np.concatenate(positions) if positions else np.zeros((0, 3), dtype=np.int64),
    )


_STEPPER = np.frombuffer(b"stepper_motor-", dtype=np.uint8)
_COUNTER = np.frombuffer(b"counter-", dtype=np.uint8)
_STEPS = np.frombuffer(b" steps", dtype=np.uint8)
_POW10 = 10 ** np.arange(18, dtype=np.int64)
_MAX_DIGITS = 18  # int64 holds every 18-digit number


def _parse_plain_lines(data: bytes) -> DecoderOutput | None:
    """The annotations in ``data`` (whole lines) when every line is ``SS-ES counter-N: V`` or
    ``SS-ES stepper_motor-N: P steps`` (numbers of at most 18 digits, a sign only before V or
    P, ``\\r\\n`` or ``\\n``), else None. Each line is cut at the first ``-`` after its start,
    the first space after that and the first ``:`` after the decoder's name; every piece is
    checked (digits where numbers are), so what is accepted is read as the line reader does."""
    a = np.frombuffer(data, dtype=np.uint8)
    end = np.flatnonzero(a == 10)
    if not len(end) or end[-1] != len(a) - 1:
        return None
    start = np.concatenate(([0], end[:-1] + 1))
    end = end - ((a[end - 1] == 13) & (end > start))  # a \r before the \n
    other = np.concatenate(([0], np.cumsum((a - 48) >= 10)))  # non-digits before each byte

    def digits(lo: np.ndarray, hi: np.ndarray) -> bool:
        n = hi - lo
        return bool(((n > 0) & (n <= _MAX_DIGITS) & (other[hi] == other[lo])).all())

    def first(char: int, after: np.ndarray) -> np.ndarray | None:
        at = np.flatnonzero(a == char)
        i = np.searchsorted(at, after)
        return at[i] if len(at) and (i < len(at)).all() else None

    dash = first(45, start)
    space = None if dash is None else first(32, dash)
    if dash is None or space is None or not digits(start, dash) or not digits(dash + 1, space):
        return None
    name = space + 1
    kind = a[np.minimum(name, len(a) - 1)]
    stepper, counter = kind == 115, kind == 99  # "s", "c"
    if not (stepper | counter).all():
        return None
    for rows, word in ((stepper, _STEPPER), (counter, _COUNTER)):
        window = np.minimum(name[rows, None] + np.arange(len(word)), len(a) - 1)
        if not (a[window] == word).all():
            return None
    number = name + np.where(stepper, len(_STEPPER), len(_COUNTER))
    colon = first(58, number)
    if colon is None or not digits(number, colon) or not (a[colon + 1] == 32).all():
        return None
    value = colon + 2
    negative = a[np.minimum(value, len(a) - 1)] == 45
    value = value + negative
    value_end = end - np.where(stepper, len(_STEPS), 0)
    window = np.minimum(value_end[stepper, None] + np.arange(len(_STEPS)), len(a) - 1)
    if not digits(value, value_end) or not (a[window] == _STEPS).all():
        return None
    v = _number(a, value, value_end)
    v[negative] *= -1
    ss, es = _number(a, start, dash), _number(a, dash + 1, space)
    return DecoderOutput(v[counter], np.stack([ss[stepper], es[stepper], v[stepper]], axis=1))


def _number(a: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """The decimal numbers ``a[lo:hi]`` (checked: 1 … 18 digits) as int64."""
    width = int((hi - lo).max()) if len(lo) else 0
    k = np.arange(width)
    at = np.maximum(hi[:, None] - 1 - k, 0)
    d = np.where(k < (hi - lo)[:, None], a[at].astype(np.int64) - 48, 0)
    return d @ _POW10[:width]
