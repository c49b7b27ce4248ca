"""The cross-check's comparison: wavecheck's decode against what sigrok's decoders printed.

sigrok's known differences (``../shared/reference/sigrok.md`` §3.1, §7), each accounted for,
not hidden:

1. N steps give N−1 position lines (0 and 1 steps give none); the last step's move is never shown,
   so sigrok's final position is its last line ± one step whose direction it does not print.
2. DIR is read *at* the step's sample: a DIR change in the same sample counts with the new level
   (wavecheck calls such a step ambiguous and counts it neither way).
3. DIR high = +1, fixed; wavecheck's forward level is a choice (``--dir-forward``), so positions are
   compared in sigrok's polarity. ``x``/``z`` read as 0 in sigrok.
4. ``stepper_motor`` steps on rising edges only: for a falling-edge drive its positions are
   compared with wavecheck's rising-edge decode, and ``counter`` checks the falling-edge count.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from wavecheck.crosscheck.sigrok import DecoderOutput, SigrokInput
from wavecheck.drives.datasheet import ActiveEdge
from wavecheck.steps.decode import StepEvents
from wavecheck.steps.interface import RoleSignal

__all__ = ["CrosscheckResult", "compare"]


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


def compare(
    path: str,
    step_sig: RoleSignal,
    dir_sig: RoleSignal | None,
    *,
    active_edge: ActiveEdge,
    forward_level: int,
    steps: StepEvents,
    rising: StepEvents,
    sigrok_input: SigrokInput,
    sigrok: DecoderOutput,
) -> CrosscheckResult:
    """Compare wavecheck's decode (``steps`` on the active edge, ``rising`` on rising edges)
    with sigrok's ``counter`` and ``stepper_motor`` output, explaining the known differences."""
    counts, positions = sigrok.counts, sigrok.positions
    ds = sigrok_input.downsample
    res = CrosscheckResult(
        path=path,
        step_channel=step_sig.channel,
        dir_channel=dir_sig.channel if dir_sig else None,
        active_edge=active_edge,
        sigrok_input=sigrok_input.description,
        downsample=ds,
        wavecheck_steps=steps.count,
        sigrok_count=int(counts[-1]) if len(counts) else 0,
        rising_steps=rising.count,
        sigrok_position_lines=len(positions),
        sigrok_last_position=int(positions[-1, 2]) if len(positions) else None,
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
    if len(counts) and not np.array_equal(counts, np.arange(1, len(counts) + 1)):
        res.disagreements.append("sigrok counter did not count 1, 2, 3, … (a reset or a gap)")
    if sigrok_input.lost:
        res.disagreements.append(
            f"downsample {ds} ticks merges {sigrok_input.lost} STEP/DIR edge(s) into the "
            "samples of others: sigrok cannot see them (give a --downsample no larger than the "
            "shortest gap between edges)"
        )
    elif ds > 1:
        res.explanations.append(
            f"converted with downsample {ds} ticks, at most the shortest gap between STEP/DIR "
            "edges: no edge is merged into another's sample (none lost)"
        )
    if sigrok_input.offset:
        res.explanations.append(
            "an edge falls on the first sample, which sigrok takes for the initial level: every "
            "edge was written one sample later (none lost)"
        )
    if dir_sig is None:
        res.explanations.append("no DIR mapped: only step counts are compared (no positions)")
        return res
    samples = rising.ticks // ds + sigrok_input.offset
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
        got_ss, got_es, got_pos = positions.T
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
    return res
