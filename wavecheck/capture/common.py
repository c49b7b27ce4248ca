"""What the capture readers share: the sample rate a file's text states, the logic-analyzer
programs whose timestamps are samples, the resolution of a capture from the user's values and the
file's, and a path given to another program (fst2vcd, sigrok-cli)."""

from __future__ import annotations

import os
import re
from fractions import Fraction

from wavecheck.errors import CaptureError, UnitError
from wavecheck.timebase import Timebase
from wavecheck.units import parse_frequency

__all__ = [
    "ANALYZER_WRITERS",
    "analyzer_writer",
    "path_argument",
    "resolution_of",
    "stated_samplerate",
]

_RATE = r"(\d+(?:\.\d+)?\s*[kMG]?Hz)\b"
#: A stated sample rate: libsigrok/PulseView/DSView's "Acquisition with 8/8 channels at 12 MHz",
#: or "sample rate: 12 MHz", "samplerate=12MHz", "sampling rate 12 MHz".
_SAMPLERATE_RES = (
    re.compile(r"\bchannels\s+at\s+" + _RATE),
    re.compile(r"\bsampl(?:e|ing)[ _-]?rate\s*[:=]?\s*" + _RATE, re.IGNORECASE),
)
#: Programs that write VCDs of logic-analyzer samples, recognised in ``$version``/``$comment``
#: text: their timestamps are sample numbers on the timescale, not exact simulation times.
#: (Simulators — Icarus, GHDL, Verilator, pyvcd, ModelSim … — write exact times.)
ANALYZER_WRITERS: tuple[tuple[str, str], ...] = (
    (r"libsigrok|sigrok|pulseview", "sigrok"),
    (r"chronovu", "ChronoVu"),
    (r"saleae", "Saleae Logic"),
    (r"dsview|dreamsourcelab", "DSView"),
    (r"logicport|intronix", "Intronix LogicPort"),
    (r"kingst", "Kingst"),
    (r"waveforms|digilent", "Digilent WaveForms"),
    (r"scanalogic|ikalogic", "Ikalogic ScanaStudio"),
    (r"logic[ -]?analy[sz]er", "a logic analyzer"),
)
_ANALYZER_RES = [(re.compile(rf"\b(?:{p})", re.IGNORECASE), name) for p, name in ANALYZER_WRITERS]


def analyzer_writer(texts: list[str]) -> str | None:
    """The logic-analyzer program named in ``texts`` (``$version``, ``$comment``), or None."""
    for text in texts:
        for pattern, name in _ANALYZER_RES:
            if pattern.search(text):
                return name
    return None


def stated_samplerate(texts: list[str]) -> tuple[Fraction, str] | None:
    """The sample rate ``texts`` state (``"… channels at 12 MHz"``): (Hz, as written), or None."""
    for text in texts:
        for pattern in _SAMPLERATE_RES:
            match = pattern.search(text)
            if match:
                try:
                    rate = parse_frequency(match.group(1))
                except UnitError:
                    continue
                if rate > 0:
                    return rate, match.group(1)
    return None


def resolution_of(
    path: str | os.PathLike[str],
    tb: Timebase,
    comments: list[str],
    samplerate: Fraction | None,
    resolution_s: Fraction | None,
    notes: list[str],
    version: str | None = None,
) -> tuple[int, Fraction | None]:
    """Resolution in ticks and sample rate: user values first, then a rate the file states
    (``$comment``), then one tick for a file written by a logic analyzer's software (its
    timestamps are samples); a simulator's VCD (none of these) is exact, resolution 0."""
    texts = ([version] if version else []) + comments
    rate = samplerate
    if rate is None:
        stated = stated_samplerate(texts)
        if stated is not None:
            rate = stated[0]
            notes.append(f"sample rate {stated[1]} from the file's $comment")
    sample_res: int | None = None
    if rate:
        # a sampled capture: an edge is known to one sample period T; when T is not a whole
        # number of ticks the timestamps are rounded to the timescale (sigrok-cli writes
        # round(i·T) for sample i, sigrok.md §7), which adds up to one tick to an interval
        ticks = 1 / rate / tb.tick_s
        sample_res = -((-ticks.numerator) // ticks.denominator)
        if ticks.denominator != 1:
            sample_res += 1
            notes.append(
                f"the sample period {float(ticks * tb.tick_ns):g} ns is not a whole number of "
                f"{float(tb.tick_ns):g} ns ticks, so the timestamps are rounded; resolution "
                f"{sample_res} ticks covers the period and the rounding"
            )
    elif (writer := analyzer_writer(texts)) is not None:
        sample_res = 1
        notes.append(
            f"written by {writer} (a logic analyzer's software) with no sample rate stated: its "
            f"timestamps are samples, so the resolution is one {float(tb.tick_ns):g} ns tick of "
            "the timescale (give --samplerate or --resolution if it sampled more coarsely)"
        )
    if resolution_s is None:
        return (0 if sample_res is None else sample_res), rate
    if resolution_s < 0:
        raise CaptureError(path, None, f"resolution {resolution_s} s must not be negative")
    ticks = resolution_s / tb.tick_s
    res = -((-ticks.numerator) // ticks.denominator)
    if ticks.denominator != 1:
        notes.append(
            f"resolution {float(resolution_s * 10**9):g} ns is not a whole number of "
            f"{float(tb.tick_ns):g} ns ticks; rounded up to {res} ticks"
        )
    if sample_res is not None and res < sample_res:
        notes.append(
            f"resolution {float(resolution_s * 10**9):g} ns is finer than the sample period; "
            f"using {sample_res} ticks"
        )
        res = sample_res
    return res, rate


def path_argument(path: str | os.PathLike[str]) -> str:
    """``path`` as an argument of another program (fst2vcd, sigrok-cli): a relative path that
    starts with ``-`` gets ``./`` so that it is never read as an option (``-fother.fst`` is
    fst2vcd's ``-f other.fst``)."""
    text = os.fspath(path)
    return f"./{text}" if text.startswith("-") else text
