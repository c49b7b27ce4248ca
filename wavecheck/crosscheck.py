"""Cross-check wavecheck's step decoding against sigrok-cli's ``counter`` and ``stepper_motor``.

Two independent decoders run on the same capture:

- ``counter`` (``data_edge`` = the active edge) counts STEP edges, the final step included;
- ``stepper_motor`` (rising edges only) writes one position line per step *except the last*:
  line k spans [edge k, edge k+1] in samples and shows the position after step k.

Both are compared with :func:`wavecheck.decode.decode` on the same channels. sigrok's known
differences (``../shared/reference/sigrok.md`` §3.1, §7), each accounted for, not hidden:

1. N steps give N−1 position lines (0 and 1 steps give none); the last step's move is never shown,
   so sigrok's final position is its last line ± one step whose direction it does not print.
2. DIR is read *at* the step's sample: a DIR change in the same sample counts with the new level
   (wavecheck calls such a step ambiguous and counts it neither way).
3. DIR high = +1, fixed; wavecheck's forward level is a choice (``--dir-forward``), so positions are
   compared in sigrok's polarity. ``x``/``z`` read as 0 in sigrok.
4. ``stepper_motor`` steps on rising edges only: for a falling-edge drive its positions are
   compared with wavecheck's rising-edge decode, and ``counter`` checks the falling-edge count.

Input: a ``.sr`` is given to sigrok-cli as is (sample n = tick n). A VCD is first written with only
the mapped 1-bit wires (sigrok's VCD input aborts on vectors, §7) and converted to ``.sr`` with an
explicit ``downsample`` no larger than the shortest gap between any two STEP/DIR edges, so no pulse
or DIR/STEP order is lost (§7: "downsampling drops pulses"). Other formats are converted again
by sigrok-cli. sigrok-cli's exit status is not trusted (stderr is checked, see
:mod:`wavecheck.capture.sigrokcli`).
"""

from __future__ import annotations

import os
import re
import tempfile
from dataclasses import dataclass, field
from fractions import Fraction
from pathlib import Path

import numpy as np

from wavecheck.capture.model import Capture, EdgeArray
from wavecheck.capture.sigrokcli import (
    _SAMPLERATE_OPTION_FORMATS,
    convert,
    find_sigrok_cli,
    run_sigrok,
    show,
)
from wavecheck.decode import decode
from wavecheck.drives.model import ActiveEdge
from wavecheck.errors import CaptureError, UsageError
from wavecheck.interface import build_interface

__all__ = ["CrosscheckResult", "crosscheck", "pick_downsample"]

#: Above this many samples a VCD conversion is refused (sigrok-cli needs ~1 min per 1e10).
MAX_SAMPLES = 2 * 10**9
_LINE = re.compile(r"^(\d+)-(\d+) (\S+?)-\d+: (.*)$")
_UNITS = ((0, "s"), (3, "ms"), (6, "us"), (9, "ns"), (12, "ps"), (15, "fs"))


@dataclass
class CrosscheckResult:
    """What each side saw, the differences, and why the known ones are not disagreements."""

    path: str
    step_channel: str
    dir_channel: str | None
    active_edge: ActiveEdge
    sigrok_input: str
    downsample: int
    wavecheck_steps: int
    sigrok_count: int
    rising_steps: int
    sigrok_position_lines: int
    sigrok_last_position: int | None
    expected_last_position: int | None
    wavecheck_final_position: int | None
    final_sigrok_polarity: int | None
    ambiguous: int
    disagreements: list[str] = field(default_factory=list)
    explanations: list[str] = field(default_factory=list)

    @property
    def agree(self) -> bool:
        return not self.disagreements


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


def _write_vcd(
    capture: Capture, names: list[str], out_names: list[str], path: Path, scale: int, unit: str
) -> None:
    """The channels ``names`` only (called ``out_names``), times × ``scale`` in ``1 <unit>``,
    ending with a timestamp after the last edge (sigrok drops the values at the last one)."""
    ids = {n: chr(33 + i) for i, n in enumerate(names)}
    chans = [capture.channel(n) for n in names]
    lines = [f"$timescale 1 {unit} $end", "$scope module crosscheck $end"]
    lines += [f"$var wire 1 {ids[n]} {o} $end" for n, o in zip(names, out_names, strict=True)]
    lines += ["$upscope $end", "$enddefinitions $end", "#0", "$dumpvars"]
    lines += [f"{c.initial}{ids[n]}" for n, c in zip(names, chans, strict=True)]
    lines.append("$end")
    events: dict[int, list[str]] = {}
    for n, c in zip(names, chans, strict=True):
        for i, t in enumerate(c.edges.tolist()):
            events.setdefault(t, []).append(f"{c.level_after(i)}{ids[n]}")
    with open(path, "w", encoding="ascii", newline="\n") as f:
        f.write("\n".join(lines) + "\n")
        for t in sorted(events):
            if t:
                f.write(f"#{t * scale}\n")
            f.write("\n".join(events[t]) + "\n")
        last = max([capture.end, *events]) + 1
        f.write(f"#{last * scale}\n")


def _run_decoders(
    sr: str, step: str, dir_: str | None, edge: ActiveEdge, path: str
) -> tuple[list[int], list[tuple[int, int, int]]]:
    """(counter values, stepper_motor (ss, es, position) lines) from one sigrok-cli run."""
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
    out = run_sigrok(args, path=path).stdout
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
    return counts, positions


def crosscheck(
    capture: Capture,
    mapping: dict[str, str],
    *,
    active_edge: ActiveEdge = "rising",
    forward_level: int = 0,
    downsample: int | None = None,
    input_format: str | None = None,
    workdir: str | os.PathLike[str] | None = None,
) -> CrosscheckResult:
    """Run sigrok-cli's decoders on ``capture`` and compare with wavecheck's decode.

    Raises:
        UsageError: no ``step`` role, unknown channel, unsupported edge.
        CaptureError: sigrok-cli is missing or fails on the file.
    """
    if "step" not in mapping:
        raise UsageError("crosscheck needs --map step=CHANNEL (and dir=CHANNEL for positions)")
    extra = set(mapping) - {"step", "dir"}
    if extra:
        raise UsageError(
            f"crosscheck compares step/dir only; drop --map {', '.join(sorted(extra))}"
        )
    if find_sigrok_cli() is None:
        raise CaptureError(
            capture.path, None, "crosscheck needs sigrok-cli (apt-get install sigrok-cli)"
        )
    iface = build_interface(capture, mapping)
    step_sig = iface.require("step")
    dir_sig = iface.get("dir")
    names = [step_sig.channel] + ([dir_sig.channel] if dir_sig else [])
    # wavecheck's decode: on the active edge (counter), and on rising edges (stepper_motor)
    steps = decode(iface, 0, active_edge=active_edge, forward_level=forward_level)
    rising = steps if active_edge == "rising" else decode(iface, 0, active_edge="rising",
                                                          forward_level=forward_level)  # fmt: skip
    with tempfile.TemporaryDirectory(prefix="wavecheck-xc-", dir=workdir) as tmp:
        ds = 1
        if capture.format == "sr":
            sr = capture.path
            sr_names = [_sigrok_name(n, capture.path) for n in names]
        else:
            sr = str(Path(tmp) / "capture.sr")
            if capture.format == "vcd":
                ds = downsample or pick_downsample(
                    [step_sig.edges] + ([dir_sig.edges] if dir_sig else [])
                )
                if (capture.end // ds) > MAX_SAMPLES:
                    raise UsageError(
                        f"{capture.path}: converting for sigrok-cli would make "
                        f"{capture.end // ds} samples (downsample {ds}); give --downsample N"
                    )
                unit, scale = _unit_for(capture.timebase.tick_s)
                sr_names = ["step", "dir"][: len(names)]
                vcd = Path(tmp) / "mapped.vcd"
                _write_vcd(capture, names, sr_names, vcd, scale, unit)
                convert(vcd, sr, input_format=f"vcd:downsample={ds * scale}:skip=0")
            else:
                # the same sigrok-cli input spec the capture was read with (options included)
                fmt = input_format or capture.format.split(":", 1)[1]
                name = fmt.split(":", 1)[0]
                rate = capture.samplerate_hz
                if (
                    name in _SAMPLERATE_OPTION_FORMATS
                    and "samplerate=" not in fmt
                    and rate is not None
                    and rate.denominator == 1
                ):
                    fmt = f"{fmt}:samplerate={int(rate)}"
                convert(capture.path, sr, input_format=fmt)
                sr_names = [_sigrok_name(n, capture.path) for n in names]
            info = show(sr)
            if not info.sample_count:
                raise CaptureError(
                    capture.path, "sigrok-cli", "the converted capture has 0 samples"
                )
        counts, positions = _run_decoders(
            sr, sr_names[0], sr_names[1] if dir_sig else None, active_edge, capture.path
        )
    res = CrosscheckResult(
        path=capture.path,
        step_channel=step_sig.channel,
        dir_channel=dir_sig.channel if dir_sig else None,
        active_edge=active_edge,
        sigrok_input="the .sr itself"
        if capture.format == "sr"
        else f"converted .sr (downsample {ds})",
        downsample=ds,
        wavecheck_steps=steps.count,
        sigrok_count=counts[-1] if counts else 0,
        rising_steps=rising.count,
        sigrok_position_lines=len(positions),
        sigrok_last_position=positions[-1][2] if positions else None,
        expected_last_position=None,
        wavecheck_final_position=steps.final_position,
        final_sigrok_polarity=None,
        ambiguous=int(len(rising.ambiguous)),
    )
    if res.sigrok_count != steps.count:
        res.disagreements.append(
            f"step count: sigrok counter {res.sigrok_count}, wavecheck {steps.count} "
            f"({active_edge} edges of {step_sig.channel!r})"
        )
    if counts and counts != list(range(1, len(counts) + 1)):
        res.disagreements.append("sigrok counter did not count 1, 2, 3, … (a reset or a gap)")
    if dir_sig is None:
        res.explanations.append("no DIR mapped: only step counts are compared (no positions)")
        return res
    samples = rising.ticks // ds
    n = rising.count
    # the DIR level sigrok reads at each step's sample (changes in that sample included);
    # derived from wavecheck's decode: a known direction gives the level before the edge
    fl = forward_level
    level = np.where(rising.direction > 0, fl, 1 - fl).astype(np.int64)
    amb = np.isin(rising.ticks, rising.ambiguous)
    if amb.any():
        # DIR changed at this very step: sigrok reads the new level
        k = np.searchsorted(dir_sig.edges, rising.ticks[amb], side="right")
        level[amb] = dir_sig.initial ^ (k & 1)
    unknown = (rising.direction == 0) & ~amb
    if unknown.any():
        level[unknown] = 0  # DIR not yet known (x): sigrok reads x as 0
        res.explanations.append(
            f"{int(unknown.sum())} step(s) before DIR is known: sigrok reads x/z as 0"
        )
    sign = np.where(level == 1, 1, -1)
    expected = np.cumsum(sign)
    want_lines = max(n - 1, 0)
    if len(positions) != want_lines:
        res.disagreements.append(
            f"stepper_motor wrote {len(positions)} position lines; {n} rising-edge steps "
            f"should give {want_lines}"
        )
    else:
        got_ss = np.array([p[0] for p in positions], dtype=np.int64)
        got_es = np.array([p[1] for p in positions], dtype=np.int64)
        got_pos = np.array([p[2] for p in positions], dtype=np.int64)
        bad_edges = np.flatnonzero((got_ss != samples[:-1]) | (got_es != samples[1:]))
        if len(bad_edges):
            i = int(bad_edges[0])
            res.disagreements.append(
                f"{len(bad_edges)} step(s) at different samples, first step {i + 1}: sigrok "
                f"{int(got_ss[i])}, wavecheck {int(samples[i])}"
            )
        bad_pos = np.flatnonzero(got_pos != expected[:-1])
        if len(bad_pos):
            i = int(bad_pos[0])
            res.disagreements.append(
                f"{len(bad_pos)} position(s) differ, first after step {i + 1} (sample "
                f"{int(samples[i])}): sigrok {int(got_pos[i])}, wavecheck {int(expected[i])} "
                "(DIR-high = + polarity)"
            )
    if n:
        res.expected_last_position = int(expected[-2]) if n >= 2 else None
        res.final_sigrok_polarity = int(expected[-1])
    res.explanations.append(
        f"stepper_motor writes N-1 position lines for N steps: {len(positions)} lines for {n} "
        "steps; the last step's move is never printed"
        + (
            f" (sigrok's last line {res.sigrok_last_position}, then a step of "
            f"{'+1' if sign[-1] > 0 else '-1'} gives {res.final_sigrok_polarity})"
            if n >= 2
            else ""
        )
    )
    res.explanations.append(
        "sigrok counts DIR high as +1; wavecheck's forward level is DIR "
        f"{'low' if fl == 0 else 'high'}, so its positions are compared with the sign "
        f"{'flipped' if fl == 0 else 'kept'}"
    )
    if res.ambiguous:
        res.explanations.append(
            f"{res.ambiguous} step(s) with DIR changing at the step's own sample: sigrok counts "
            "them with the new DIR level, wavecheck leaves them ambiguous (expected positions use "
            "sigrok's reading)"
        )
    if active_edge != "rising":
        res.explanations.append(
            "stepper_motor counts rising edges only: positions are compared with wavecheck's "
            "rising-edge decode; the counter checks the falling-edge count"
        )
    if ds > 1:
        res.explanations.append(
            f"the VCD was converted with downsample {ds} ticks, the shortest gap between "
            "STEP/DIR edges, so no pulse and no STEP/DIR order is lost"
        )
    return res
