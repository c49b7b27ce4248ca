"""How a line's timing relates to an axis's motion: copies, step requests, level lines, gates.

Pure ``numpy`` passes over edge and motion arrays (``searchsorted``), used by
:mod:`wavecheck.roles.infer` to tell a line that only echoes or frames an axis's steps from an
axis of its own.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import numpy.typing as npt

from wavecheck.capture.edges import Channel
from wavecheck.roles.features import Pulses

__all__ = ["REQUEST_SHARE", "copies", "max_steps_inside", "off_around", "steps_right_after"]

I64 = npt.NDArray[np.int64]

#: Share of an axis's changes that come right after a line's pulses for that line to be the
#: axis's step request.
REQUEST_SHARE = 0.9


def copies(chans: Sequence[Channel]) -> dict[int, Channel]:
    """Channel index → the earlier channel whose waveform it repeats edge for edge (a simulator
    dumps a port and the signal it drives as two: GHDL's ``tb.a`` and ``tb.dut.a``)."""
    first: dict[tuple[int, bytes], Channel] = {}
    out: dict[int, Channel] = {}
    for c in chans:
        if not len(c.edges):
            continue
        key = (c.initial, c.edges.tobytes())
        if key in first:
            out[c.index] = first[key]
        else:
            first[key] = c
    return out


def steps_right_after(p: Pulses, motion: I64, resolution: int) -> int:
    """How many of ``motion`` come within two pulse widths after a pulse of ``p`` starts (a
    sequencer's tick, and the state change it causes a clock later)."""
    reach = 2 * max(int(np.median(p.widths)), resolution, 1)
    k = np.searchsorted(p.starts, motion, side="right") - 1
    near = (k >= 0) & (motion - p.starts[np.maximum(k, 0)] <= reach)
    return int(np.count_nonzero(near))


def max_steps_inside(p: Pulses, motion: I64) -> int:
    """The most of ``motion`` (sorted) that fall inside one pulse of ``p``."""
    if not p.count:
        return 0
    inside = np.searchsorted(motion, p.ends) - np.searchsorted(motion, p.starts)
    return int(inside.max())


def off_around(e: Channel, active: int, motion: I64, start: int) -> bool:
    """Whether ``e`` is seen at its inactive level on both sides of some of ``motion`` (the
    capture starting at tick ``start``): a line that changed only before the first step or only
    after the last one (a strobe at start-up, a testbench variable) shows no gating."""
    starts = np.r_[start, e.edges]
    levels = e.initial ^ (np.arange(len(starts)) & 1)
    off = starts[levels != active]
    return len(np.unique(np.searchsorted(np.sort(motion), off))) >= 2
