"""The proposal made of what the stages found: axis names, every channel's place (an axis role,
unassigned with why, or a conflict's candidate), what each line looks like, and, when no axis
is found, the axes to check if the lines most like a STEP are STEPs (never without a DIR the
capture may have)."""

from __future__ import annotations

import itertools

import numpy as np

from wavecheck.capture.edges import Channel
from wavecheck.roles.phases import BUDGET
from wavecheck.roles.proposal import (
    AxisProposal,
    Basis,
    LineLook,
    Proposal,
    RoleChoice,
    SharedLine,
    Unassigned,
)
from wavecheck.roles.state import FoundAxis, State

__all__ = ["Result"]

_AXIS_LETTERS = "abcdefghijklmnopqrstuvwxyz"


def _index(c: Channel) -> int:
    return c.index


class Result(State):
    """The last stage: the proposal."""

    def _axis_names(self, axes: list[FoundAxis]) -> list[str]:
        wanted: list[str | None] = []
        for a in axes:
            hints = {self.hints[c.index].axis for c in a.channels}
            name = hints.pop() if len(hints) == 1 else None
            if name is None:
                dir_role = next((r for r in a.roles if r.role == "dir"), None)
                if dir_role is not None:
                    name = self.hints[dir_role.index].axis
            wanted.append(name)
        dup = {n for n in wanted if n is not None and wanted.count(n) > 1}
        used = {n for n in wanted if n is not None and n not in dup}
        spare = itertools.chain(
            _AXIS_LETTERS, (a + b for a in _AXIS_LETTERS for b in _AXIS_LETTERS)
        )
        letters = (ch for ch in spare if ch not in used)
        return [n if n is not None and n not in dup else next(letters) for n in wanted]

    def _finish(self) -> Proposal:
        self.axes.sort(key=lambda a: min(c.index for c in a.channels))
        names = self._axis_names(self.axes)
        by_axis = {id(a): n for a, n in zip(self.axes, names, strict=True)}
        shared = tuple(
            SharedLine("enable", e.name, e.index, tuple(by_axis[id(a)] for a in axes), ev)
            for e, ev, axes in self.shared
        )
        axes = self._proposed(self.axes, names)
        suggested: tuple[AxisProposal, ...] = ()
        if not self.axes and not self.conflicts:
            maybe = self._suggested()
            suggested = self._proposed(maybe, self._axis_names(maybe))
        unassigned = []
        for c in self.cap.channels:
            if c.index in self.taken and c.index not in self.why:
                continue
            if c.index in self.why:
                why = self.why[c.index]
            elif c.index in self.bus.data:
                why = self.bus.data[c.index]
            elif self.bus.no_step(c.index) is not None:
                why = f"{self.bus.no_step(c.index)}: not a step signal"
            else:
                look = self.looks[c.index]
                why = look.evidence
                if look.kind == "other":
                    why += ": not a pulse train, and not a DIR or ENABLE of any pulse line"
                elif look.kind == "constant":
                    why += ": an unused probe, or a line that did not change while captured"
            if self.phase_cut and len(c.edges) >= 8:
                why += (
                    f"; whether it is a phase output was not established (the search for phase "
                    f"groups stopped after {BUDGET:,} groups of lines that change in turns)"
                )
            unassigned.append(Unassigned(c.name, c.index, why))
        return Proposal(
            axes,
            shared,
            tuple(unassigned),
            tuple(self.conflicts),
            tuple(self._looks()),
            tuple(self.refs[c.index] for c in self._candidates()),
            self.named,
            suggested,
        )

    @staticmethod
    def _proposed(axes: list[FoundAxis], names: list[str]) -> tuple[AxisProposal, ...]:
        return tuple(
            AxisProposal(
                name,
                "step-dir"
                if a.kind == "step-dir"
                else "up-down"
                if a.kind == "up-down"
                else "phases",
                a.step_type,
                tuple(a.roles),
                tuple(a.notes),
            )
            for a, name in zip(axes, names, strict=True)
        )

    def _suggested(self) -> list[FoundAxis]:
        """The axes to check *if* the lines most like a STEP are STEPs (no axis was found): every
        line of a few pulses (each may be a short move's STEP), else the best candidate; each
        with a DIR named like its axis's, else the unchanging, neutrally named channel right
        after it (by layout), so that no DIR the capture may have is dropped."""
        cands = self._candidates()
        few = sorted((c for c in cands if self.looks[c.index].kind == "few"), key=_index)
        steps = few or cands[:1]
        chosen = {c.index for c in steps}
        out = []
        for s in steps:
            look = self.looks[s.index]
            roles = [RoleChoice("step", s.name, s.index, self.refs[s.index], look.evidence)]
            d = self._still_dir(s, chosen)
            if d is not None:
                chosen.add(d[0].index)
                roles.append(
                    RoleChoice("dir", d[0].name, d[0].index, self.refs[d[0].index], d[1], d[2])
                )
            motion = look.pulses.starts if look.pulses is not None else np.zeros(0, np.int64)
            out.append(FoundAxis("step-dir", 0, roles, [s], motion, []))
        return out

    def _still_dir(self, s: Channel, taken: set[int]) -> tuple[Channel, str, Basis] | None:
        """An unchanging channel for the DIR of STEP ``s``: the one named like its axis's DIR,
        else the neutrally named one right after it; with its evidence and basis."""
        axis = self.hints[s.index].axis
        still = [
            c
            for c in self.cap.channels
            if self.looks[c.index].kind == "constant" and c.index not in taken
        ]
        named = [c for c in still if self.hints[c.index].fits("dir")]
        named = [c for c in named if axis is None or self.hints[c.index].axis == axis]
        if len(named) == 1:
            return named[0], f"{self.looks[named[0].index].evidence}; named like a DIR", "name"
        nxt = next((c for c in still if c.index == s.index + 1), None)
        if nxt is not None and self.hints[nxt.index].neutral:
            why = f"{self.looks[nxt.index].evidence}; the channel after {self.name_of(s)}"
            return nxt, why, "layout"
        return None

    def _looks(self) -> list[LineLook]:
        phase = {c.index for a in self.axes if a.kind == "phases" for c in a.channels}
        out = []
        for c in self.cap.channels:
            if len(c.xz_times):
                word = "unknown (x/z)"
            elif c.index in phase:
                word = "phase output"
            else:
                word = self.bus.words.get(c.index) or self.looks[c.index].word
            out.append(LineLook(c.name, c.index, word))
        return out
