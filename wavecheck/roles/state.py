"""The state the stages of role inference share (:mod:`wavecheck.roles.infer`): every line's
look and name hint, the axes found so far, the lines taken and why others were left out, the
bus findings; and the lines most like a STEP."""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from wavecheck.capture.edges import Capture, Channel
from wavecheck.record import record
from wavecheck.roles.buses import BusFindings, find_buses
from wavecheck.roles.features import ChannelLook, Pulses, look_at, may_be_one_rate
from wavecheck.roles.names import NameHint, name_hint
from wavecheck.roles.proposal import (
    Basis,
    Conflict,
    RoleChoice,
    Unassigned,
)

__all__ = ["FoundAxis", "I64", "Looks", "State", "level_at", "pulses_inside"]

I64 = npt.NDArray[np.int64]


def level_at(ch: Channel, times: I64) -> I64:
    """Level of ``ch`` just after each of ``times`` (an edge at that very tick counts)."""
    n = np.searchsorted(ch.edges, times, side="right")
    return (ch.initial ^ (n & 1)).astype(np.int64)


def pulses_inside(d: Channel, dp: Pulses, s_starts: I64) -> int:
    """Number of ``s_starts`` that fall while ``d`` is at its pulse level."""
    return int(np.count_nonzero(level_at(d, s_starts) == dp.level))


class Looks(dict[int, ChannelLook]):
    """Every line's look (channel index → :func:`~wavecheck.roles.features.look_at`), each
    computed when first asked for: judging a few lines' names costs their looks only."""

    def __init__(self, cap: Capture) -> None:
        super().__init__()
        self.cap = cap
        self.by_index = {c.index: c for c in cap.channels}

    def __missing__(self, index: int) -> ChannelLook:
        look = self[index] = look_at(self.by_index[index], self.cap)
        return look


@record(eq=False)
class FoundAxis:
    """An axis as the stages build it."""

    kind: str
    step_type: int
    roles: list[RoleChoice]
    channels: list[Channel]  # the pulse / phase channels
    motion: I64  # ticks at which the axis moves (pulse starts, phase changes)
    notes: list[str]


class State:
    """What the stages share; each stage is a mixin of this (:mod:`wavecheck.roles.infer`)."""

    def __init__(self, cap: Capture) -> None:
        self.cap = cap
        self.looks = Looks(cap)
        self._one_rate: dict[int, bool] = {}  # lines that may be at one rate, before a look
        self.hints: dict[int, NameHint] = {c.index: name_hint(c.name) for c in cap.channels}
        self.refs = self._refs()
        self.taken: set[int] = set()
        self.axes: list[FoundAxis] = []
        self.shared: list[tuple[Channel, str, list[FoundAxis]]] = []
        self.unassigned: list[Unassigned] = []
        self.conflicts: list[Conflict] = []
        self.why: dict[int, str] = {}  # reason for channels left out
        self.dir_notes: dict[int, str] = {}  # DIR index -> how elimination decided
        self.turns: dict[int, set[int]] = {}  # pulse line -> lines it takes turns with
        self.unsure_steps: set[int] = set()  # pulse lines named in a DIR conflict
        self.by_name: set[int] = set()  # pulse lines taken as STEP candidates by their names
        self.bus = BusFindings({}, {}, {}, {})
        self.named = False  # the axis is the one check maps by channel names
        self.res = max(cap.resolution_ticks, 0)
        self.phase_cut = False  # the phase-group search stopped at its budget

    def _refs(self) -> dict[int, str]:
        refs: dict[int, str] = {}
        for c in self.cap.channels:
            ok = bool(c.name) and "," not in c.name and "=" not in c.name
            ok = ok and c.name.strip() == c.name
            if ok:
                try:
                    ok = self.cap.channel(c.name).index == c.index
                except Exception:
                    ok = False
            refs[c.index] = c.name if ok else str(c.index)
        return refs

    def choice(
        self,
        role: str,
        ch: Channel,
        evidence: str,
        basis: Basis = "waveform",
        active: int | None = None,
    ) -> RoleChoice:
        hint = self.hints[ch.index]
        if basis == "waveform" and not hint.neutral and not hint.fits(role):
            said = "/".join(sorted(hint.roles)) or "another function"
            evidence += f" (its name suggests {said}; the waveform decides)"
        self.taken.add(ch.index)
        self.why.pop(ch.index, None)  # a reason it was left out earlier no longer holds
        return RoleChoice(role, ch.name, ch.index, self.refs[ch.index], evidence, basis, active)

    def name_of(self, c: Channel) -> str:
        return f"{c.index}={c.name!r}"

    def may_be_one_rate(self, c: Channel) -> bool:
        """False when ``c``'s look is surely none of the kinds at one rate (a clock, PWM,
        periodic pulses, bursts), told without its whole look while that is not made."""
        if c.index in self.looks:
            return True  # its look tells
        if c.index not in self._one_rate:
            self._one_rate[c.index] = may_be_one_rate(c, self.cap)
        return self._one_rate[c.index]

    def _buses(self, chans: list[Channel], asked: list[Channel] | None = None) -> None:
        """Bus clocks, data, strobes and gates among the changing lines not yet taken; with
        ``asked``, only the findings of those lines are sure (a strobe is looked for among
        them only, and only beside a bus clock), and the other lines' looks may stay unmade."""
        changing = [c for c in chans if len(c.edges) and c.index not in self.taken]
        # every line's findings: every line's look is made (the pre-test would be work twice)
        clock_like = {
            c.index
            for c in changing
            if (asked is None or self.may_be_one_rate(c)) and self.looks[c.index].clock_like
        }
        res = max(self.cap.resolution_ticks, 0)
        if asked is not None:
            self.bus = find_buses(changing, res, clock_like, {})
            if not self.bus.clocks:  # a strobe follows a bus clock: no strobe without one
                return
        starts = {
            c.index: look.pulses.starts
            for c in (self.cap.channels if asked is None else asked)
            if (look := self.looks[c.index]).pulses is not None
            and (look.is_step_like or look.step_by_name)
        }
        self.bus = find_buses(changing, res, clock_like, starts)

    def _candidates(self) -> list[Channel]:
        """The channels most like a STEP, best first: named so, then by how they look (a step
        train, then pulses at one rate, then coded pulses), then the most pulses; never a line
        the waveform rules out (a clock, PWM, a serial line, a bus's line, a gate)."""
        rank = {"pulses": 0, "periodic": 1, "bursts": 2, "coded": 3, "duty": 4, "few": 5}
        cands = [
            c
            for c in self.cap.channels
            if self.looks[c.index].kind in rank
            and self.bus.no_step(c.index) is None
            and not len(c.xz_times)
        ]

        def key(c: Channel) -> tuple[int, int, int]:
            look = self.looks[c.index]
            count = look.pulses.count if look.pulses is not None else 0
            return (0 if self.hints[c.index].fits("step") else 1, rank[look.kind], -count)

        return sorted(cands, key=key)
