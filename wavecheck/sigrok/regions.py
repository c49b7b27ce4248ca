"""Violation regions: runs of violations merged into spans a whole-capture view can show.

PulseView draws an annotation narrower than a pixel as a 1-pixel line, and a run of them as
hatching in one colour (grey when the run mixes classes); at full zoom-out a 9 us violation in a
500 ms capture, or 31 k violations in 17 s, are not seen as red. The decoder therefore also puts
one annotation per *region*: violations closer than :data:`GAP_SHARE` of the input apart are one
region, and a region narrower than :data:`WIDTH_SHARE` of the input is widened about its middle
to that width (clipped to the input), so that at full zoom-out (about a thousand pixels across)
each region is a few pixels wide and apart from the next: drawn as its own box, in its class's
colour. Each region says how many violations of which rules it holds. Pure numpy over the
violations; no libsigrokdecode here.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

__all__ = ["GAP_SHARE", "WIDTH_SHARE", "Region", "regions"]

#: Violations less than input / GAP_SHARE apart are one region (about 3 pixels at full zoom-out).
GAP_SHARE = 400
#: The narrowest region: input / WIDTH_SHARE (about 10 pixels at full zoom-out).
WIDTH_SHARE = 100


@dataclass(frozen=True)
class Region:
    """A span of the input and the violations in it, per rule (rule id → count)."""

    start: int
    end: int
    counts: dict[str, int]

    def texts(self) -> list[str]:
        """The annotation's texts, long to short: ``3 violations: dir_hold ×2, step_low ×1``."""
        total = sum(self.counts.values())
        most = sorted(self.counts.items(), key=lambda item: (-item[1], item[0]))
        parts = ", ".join(f"{rule} ×{n}" for rule, n in most)
        noun = "violation" if total == 1 else "violations"
        return [f"{total} {noun}: {parts}", parts, str(total), "!"]


def regions(
    starts: Sequence[int], ends: Sequence[int], rules: Sequence[str], begin: int, end: int
) -> list[Region]:
    """The regions of the violations ``starts[k]..ends[k]`` of rule ``rules[k]`` (samples, in
    any order), scaled to the input ``begin``..``end``."""
    if not len(starts):
        return []
    lo = np.minimum(np.asarray(starts, np.int64), np.asarray(ends, np.int64))
    hi = np.maximum(np.asarray(starts, np.int64), np.asarray(ends, np.int64))
    order = np.argsort(lo, kind="stable")
    lo, hi = lo[order], hi[order]
    ids, rule_of = np.unique(np.asarray(rules, dtype=str), return_inverse=True)
    rule_of = rule_of.reshape(-1)[order]
    span = max(end - begin, 1)
    gap, width = max(1, span // GAP_SHARE), max(1, span // WIDTH_SHARE)
    reach = np.maximum.accumulate(hi)
    breaks = np.flatnonzero(lo[1:] > reach[:-1] + gap) + 1
    firsts = np.concatenate([[0], breaks])
    lasts = np.concatenate([breaks, [len(lo)]])
    group = np.repeat(np.arange(len(firsts)), lasts - firsts)
    keys, tally = np.unique(group * len(ids) + rule_of, return_counts=True)
    per_group: list[dict[str, int]] = [{} for _ in firsts]
    for key, n in zip(keys.tolist(), tally.tolist(), strict=True):
        per_group[key // len(ids)][str(ids[key % len(ids)])] = n
    out: list[Region] = []
    for a, b, counts in zip(firsts.tolist(), lasts.tolist(), per_group, strict=True):
        r0, r1 = int(lo[a]), int(reach[b - 1])
        if r1 - r0 < width:  # widened about its middle, within the input
            r0 = max(begin, min((r0 + r1 - width) // 2, end - width))
            r1 = min(end, r0 + width)
        if out and r0 <= out[-1].end + gap:  # widening closed the gap to the one before
            prev = out.pop()
            merged = dict(prev.counts)
            for name, n in counts.items():
                merged[name] = merged.get(name, 0) + n
            out.append(Region(prev.start, max(prev.end, r1), merged))
        else:
            out.append(Region(r0, r1, counts))
    return out
