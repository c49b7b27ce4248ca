"""UP/DOWN lines: two pulse lines that never pulse together and take turns.

Two pulse trains fit as an up/down pair when they have the same pulse level and about the same
pulse width (one step generator drives both: medians within 20 %, and each line's median width
within the other's range of widths, as latency varies both alike), never overlap, and at each switch from one line to
the other the period is no shorter than the periods beside it (a line pulsing within the other's
run is another axis). Which pairs to propose is decided in :mod:`wavecheck.roles.infer`.
"""

from __future__ import annotations

import numpy as np

from wavecheck.capture.edges import Channel
from wavecheck.record import record
from wavecheck.roles.features import Pulses

__all__ = ["UpDownFit", "up_down"]

_SWITCH_GAP = 0.9  # the period across a switch is at least this times its neighbours'
_SAME_WIDTH = 1.2  # median pulse widths of the two lines within this factor


@record(frozen=True)
class UpDownFit:
    """Two pulse lines that never pulse together and take turns ``switches`` times."""

    switches: int

    def evidence(self, other: Channel) -> str:
        """What was seen, in words, from one line's side (``other`` is its partner)."""
        return (
            f"takes turns with {other.name!r}: never pulses while it runs "
            f"(switches {self.switches:,} times, always after a pause no shorter than the "
            "periods beside it), and no DIR line"
        )


def up_down(p: Pulses, q: Pulses, resolution: int) -> UpDownFit | None:
    """The fit of two pulse trains as an up/down pair, or None when they run at the same time
    (``resolution``: the capture's resolution in ticks)."""
    if p.count == 0 or q.count == 0 or p.level != q.level:
        return None
    wp, wq = float(np.median(p.widths)), float(np.median(q.widths))
    if max(wp, wq) > _SAME_WIDTH * min(wp, wq) + 2 * resolution:
        return None  # one step generator drives both lines: same pulse level and width
    slack = 2 * resolution
    if not (
        int(p.widths.min()) - slack <= wq <= int(p.widths.max()) + slack
        and int(q.widths.min()) - slack <= wp <= int(q.widths.max()) + slack
    ):
        return None  # each line's usual width is one the other makes too (latency varies both)
    s = np.concatenate([p.starts, q.starts])
    e = np.concatenate([p.ends, q.ends])
    lab = np.concatenate([np.zeros(p.count, np.int8), np.ones(q.count, np.int8)])
    o = np.argsort(s, kind="stable")
    s, e, lab = s[o], e[o], lab[o]
    sw = np.flatnonzero(lab[1:] != lab[:-1])
    if np.any(e[sw] > s[sw + 1]):
        return None  # pulses overlap
    per = (s[sw + 1] - s[sw]).astype(np.float64)
    m = len(s)
    prev_ok = (sw >= 1) & (lab[np.maximum(sw - 1, 0)] == lab[sw])
    prev = np.where(prev_ok, s[sw] - s[np.maximum(sw - 1, 0)], 0)
    nxt_ok = (sw + 2 < m) & (lab[np.minimum(sw + 2, m - 1)] == lab[sw + 1])
    nxt = np.where(nxt_ok, s[np.minimum(sw + 2, m - 1)] - s[sw + 1], 0)
    if np.any(per < _SWITCH_GAP * np.maximum(prev, nxt)):
        return None  # one line pulses within the other's run: they run together
    return UpDownFit(len(sw))
