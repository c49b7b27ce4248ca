"""The axes of pulse lines: step/dir axes, up/down pairs (lines that take turns), and the lines
left to the user when a pulse line may be a STEP or one half of an up/down pair."""

from __future__ import annotations

import numpy as np

from wavecheck.capture.edges import Channel
from wavecheck.roles.dirs import DirFit
from wavecheck.roles.proposal import (
    Basis,
    Conflict,
)
from wavecheck.roles.state import FoundAxis, State
from wavecheck.roles.updown import UpDownFit, up_down

__all__ = ["PulseAxes"]


class PulseAxes(State):
    """The stage that makes step/dir and up/down axes of the pulse lines."""

    def _takes_turns(self, pulse: list[Channel]) -> dict[int, set[int]]:
        """Pulse line → the lines it takes turns with (up/down candidates, before any DIR)."""
        out: dict[int, set[int]] = {c.index: set() for c in pulse}
        for i, p in enumerate(pulse):
            for q in pulse[i + 1 :]:
                pp, qp = self.looks[p.index].pulses, self.looks[q.index].pulses
                assert pp is not None and qp is not None
                if up_down(pp, qp, self.cap.resolution_ticks) is not None:
                    out[p.index].add(q.index)
                    out[q.index].add(p.index)
        return out

    def _pulse_axes(self, pulse: list[Channel], dirs: dict[int, DirFit]) -> None:
        # a line named in a DIR conflict may be a STEP (with that DIR) or an up/down line; so
        # may every line it takes turns with, and theirs: leave them all to the user
        unsure = set(self.unsure_steps)
        todo = list(unsure)
        while todo:
            for j in self.turns.get(todo.pop(), ()):
                if j not in unsure and j not in dirs:
                    unsure.add(j)
                    todo.append(j)
        unsure = {i for i in unsure if i not in dirs and self.turns.get(i)}
        if unsure:
            lines = [c for c in pulse if c.index in unsure]
            self.conflicts.append(
                Conflict(
                    "pulse lines that may be STEPs of the ambiguous DIRs or up/down lines",
                    tuple(f"{self.name_of(c)}: {self.looks[c.index].evidence}" for c in lines),
                )
            )
            for c in lines:
                self.why[c.index] = "a STEP or an up/down line (see below)"
                self.taken.add(c.index)
        free = [s for s in pulse if s.index not in dirs and s.index not in unsure]
        pairs = self._up_down_pairs(free)
        paired = {c.index for pr in pairs for c in pr[:2]}
        for up, down, ud in pairs:
            upl, downl = self.looks[up.index], self.looks[down.index]
            assert upl.pulses is not None and downl.pulses is not None
            roles = [
                self.choice(
                    "up", up, f"{upl.evidence}; {ud.evidence(down)}", active=upl.pulses.level
                ),
                self.choice(
                    "down", down, f"{downl.evidence}; {ud.evidence(up)}", active=downl.pulses.level
                ),
            ]
            notes = []
            if not (self.hints[up.index].fits("up") and self.hints[down.index].fits("down")):
                notes.append(
                    "which line is UP is not told by the waveform; the lower channel was taken "
                    "(swap them if the axis runs backwards)"
                )
            motion = np.sort(np.concatenate([upl.pulses.starts, downl.pulses.starts]))
            self.axes.append(FoundAxis("up-down", 1, roles, [up, down], motion, notes))
        in_pulse = {p.index for p in pulse}
        rejected = [
            c
            for c in self.cap.channels
            if c.index not in self.taken
            and c.index not in in_pulse
            and self.looks[c.index].pulses is not None
            and not self.hints[c.index].fits("step")
        ]
        for s in pulse:
            if s.index in paired or s.index in self.taken:
                continue
            if s.index not in dirs and self._half_of_a_pair(s, rejected):
                continue
            look = self.looks[s.index]
            assert look.pulses is not None
            basis: Basis = "name" if s.index in self.by_name else "waveform"
            roles = [self.choice("step", s, look.evidence, basis, active=look.pulses.level)]
            fit = dirs.get(s.index)
            if fit is not None:
                note = self.dir_notes.get(fit.d.index, "")
                roles.append(self.choice("dir", fit.d, fit.evidence() + note))
            self.axes.append(FoundAxis("step-dir", 0, roles, [s], look.pulses.starts, []))

    def _half_of_a_pair(self, s: Channel, rejected: list[Channel]) -> bool:
        """Whether ``s``, a STEP without DIR, takes turns with a pulse line judged no STEP (a
        coded or periodic line): then it may be one half of an up/down pair, and is left to the
        user with that line (a conflict) rather than checked as a STEP alone."""
        if self.hints[s.index].fits("step"):
            return False  # named STEP: an axis of its own
        sp = self.looks[s.index].pulses
        assert sp is not None
        for r in rejected:
            rp = self.looks[r.index].pulses
            assert rp is not None
            if up_down(sp, rp, self.cap.resolution_ticks) is not None:
                self.conflicts.append(
                    Conflict(
                        f"{self.name_of(s)} takes turns with {self.name_of(r)}, judged no STEP: "
                        "a STEP without DIR, or an up/down pair?",
                        (
                            f"{self.name_of(s)}: {self.looks[s.index].evidence}",
                            f"{self.name_of(r)}: {self.why.get(r.index) or self.looks[r.index].evidence}",
                        ),
                    )
                )
                for c in (s, r):
                    self.why[c.index] = "a STEP or an up/down line (see below)"
                    self.taken.add(c.index)
                return True
        return False

    def _up_down_pairs(self, free: list[Channel]) -> list[tuple[Channel, Channel, UpDownFit]]:
        partners: dict[int, list[tuple[Channel, UpDownFit]]] = {c.index: [] for c in free}
        for i, p in enumerate(free):
            for q in free[i + 1 :]:
                hp, hq = self.hints[p.index], self.hints[q.index]
                if hp.fits("step") or hq.fits("step"):
                    continue  # named STEP: an axis of its own
                pp, qp = self.looks[p.index].pulses, self.looks[q.index].pulses
                assert pp is not None and qp is not None
                fit = up_down(pp, qp, self.cap.resolution_ticks)
                if fit is not None:
                    partners[p.index].append((q, fit))
                    partners[q.index].append((p, fit))
        spare = [
            c
            for c in self.cap.channels
            if self.looks[c.index].kind == "constant"
            and (self.hints[c.index].neutral or self.hints[c.index].fits("dir"))
        ]
        pairs: list[tuple[Channel, Channel, UpDownFit]] = []
        done: set[int] = set()
        for p in free:
            if p.index in done or not partners[p.index]:
                continue
            cands = partners[p.index]
            q, fit = cands[0]
            named = all(
                self.hints[c.index].fits("up") or self.hints[c.index].fits("down") for c in (p, q)
            )
            if len(cands) > 1 or len(partners[q.index]) > 1:
                group = {p.index, *(c.index for c, _ in cands)}
                for c, _ in cands:
                    group |= {x.index for x, _ in partners[c.index]}
                members = [c for c in free if c.index in group]
                self.conflicts.append(
                    Conflict(
                        "several pulse lines take turns with each other: which are up/down pairs?",
                        tuple(self.name_of(c) for c in members),
                    )
                )
                done |= group
                for c in members:
                    self.why[c.index] = "ambiguous up/down pairing (see below)"
                    self.taken.add(c.index)
                continue
            done |= {p.index, q.index}
            if len(spare) >= 2 and not named:  # two DIRs that never changed?
                for c in (p, q):
                    self.why[c.index] = "up/down or a step axis of its own (see below)"
                    self.taken.add(c.index)
                self.conflicts.append(
                    Conflict(
                        f"{self.name_of(p)} and {self.name_of(q)} take turns and neither has a "
                        "DIR that changes",
                        (
                            f"an up/down pair: up={self.name_of(p)}, down={self.name_of(q)}",
                            "two step/dir axes moving one after the other, whose DIR never "
                            "changed (unchanging channels: "
                            + ", ".join(self.name_of(c) for c in spare)
                            + ")",
                        ),
                    )
                )
                continue
            up, down = (
                (q, p)
                if self.hints[q.index].fits("up") or self.hints[p.index].fits("down")
                else (p, q)
            )
            pairs.append((up, down, fit))
        return pairs
