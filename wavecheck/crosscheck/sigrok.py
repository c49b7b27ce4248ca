"""sigrok-cli's side of the cross-check: the ``.sr`` it reads, one run of its ``counter`` and
``stepper_motor`` decoders, and the parsing of their annotations.

Input: a ``.sr`` is given to sigrok-cli as is (sample n = tick n). A VCD is first written with only
the mapped 1-bit wires (sigrok's VCD input aborts on vectors, ``../shared/reference/sigrok.md``
§7) and converted to ``.sr`` with an explicit ``downsample`` no larger than the shortest gap
between any two STEP/DIR edges, so no pulse or DIR/STEP order is lost (§7: "downsampling drops
pulses"). Other formats are converted again by sigrok-cli. sigrok-cli's exit status is not
trusted (stderr is checked, see :mod:`wavecheck.capture.sigrokcli`).
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path

import numpy as np

from wavecheck.capture.edges import Capture, EdgeArray
from wavecheck.capture.sigrokcli import SAMPLERATE_OPTION_FORMATS, convert, run_sigrok, show
from wavecheck.capture.vcd.writer import VcdWire, write_vcd
from wavecheck.drives.model import ActiveEdge
from wavecheck.errors import CaptureError, UsageError
from wavecheck.units import SI_TIME

__all__ = [
    "MAX_SAMPLES",
    "DecoderOutput",
    "SigrokInput",
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

    @property
    def description(self) -> str:
        """What sigrok-cli read, for the report."""
        return (
            f"converted .sr (downsample {self.downsample})" if self.converted else "the .sr itself"
        )


@dataclass(frozen=True)
class DecoderOutput:
    """What the decoders printed: ``counter`` values, ``stepper_motor`` (start sample, end
    sample, position) lines."""

    counts: list[int]
    positions: list[tuple[int, int, int]]


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


def _write_mapped_vcd(
    capture: Capture, names: list[str], out_names: list[str], path: Path, ds: int
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
    last = max([capture.end, *(int(c.edges[-1]) for c in chans if len(c.edges))]) // ds + 1
    unit, factor = _unit_for(capture.timebase.tick_s * ds)
    if factor > MAX_SIGROK_DOWNSAMPLE:
        unit, factor = "s", 1  # the sample period cannot be stated: sample numbers stay exact
    write_vcd(
        path,
        [
            VcdWire(o, c.initial, (np.asarray(c.edges, dtype=np.int64) // ds) * factor)
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
    ds = 1
    if capture.format == "vcd":
        ds = downsample or pick_downsample(edges)
        if (capture.end // ds) > MAX_SAMPLES:
            raise UsageError(
                f"{capture.path}: converting for sigrok-cli would make "
                f"{capture.end // ds} samples (downsample {ds}); give --downsample N"
            )
        sr_names = ["step", "dir"][: len(names)]
        vcd = tmp / "mapped.vcd"
        factor = _write_mapped_vcd(capture, names, sr_names, vcd, ds)
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
    return SigrokInput(sr, sr_names, ds, converted=True)


def run_decoders(
    sr: str, step: str, dir_: str | None, edge: ActiveEdge, path: str
) -> DecoderOutput:
    """One sigrok-cli run of ``counter`` (on ``edge``) and, with a DIR, ``stepper_motor``.

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
    return parse_annotations(run_sigrok(args, path=path).stdout, path)


def parse_annotations(out: str, path: str) -> DecoderOutput:
    """The ``counter`` values and ``stepper_motor`` positions in sigrok-cli's output
    (``--protocol-decoder-samplenum`` lines ``SS-ES decoder-N: text``); other lines are ignored.

    Raises:
        CaptureError: a ``stepper_motor`` line that is not ``N steps``.
    """
    counts: list[int] = []
    positions: list[tuple[int, int, int]] = []
    for line in out.splitlines():
        m = _LINE.match(line.strip())
        if not m:
            continue
        ss, es, pd, text = int(m.group(1)), int(m.group(2)), m.group(3), m.group(4)
        if pd == "counter":
            counts.append(int(text))
        elif pd == "stepper_motor":
            pm = re.fullmatch(r"(-?\d+) steps", text.strip())
            if pm is None:
                raise CaptureError(path, "sigrok-cli", f"unexpected stepper_motor line {line!r}")
            positions.append((ss, es, int(pm.group(1))))
    return DecoderOutput(counts, positions)
