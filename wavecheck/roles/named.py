"""Channels named after their roles (``step``, ``up``, ``phase-A``): the axis ``check`` maps by
those names without ``--map`` (:func:`wavecheck.engine.planning.auto_map`), with what the waveforms say
of each line. A name is a hint, not evidence: a STEP, UP or DOWN whose waveform makes no step
pulses (a free-running clock, a bus's line, not one whole pulse) is refused with the
reason and the lines most like a STEP; pulses the waveform cannot tell from steps keep the name."""

from __future__ import annotations

import numpy as np

from wavecheck.capture.edges import Channel
from wavecheck.roles.dirs import dir_fit
from wavecheck.roles.names import NAMED_KINDS, leaf
from wavecheck.roles.phases import find_phase_groups
from wavecheck.roles.proposal import (
    Conflict,
    NameRefused,
)
from wavecheck.roles.state import FoundAxis, State

__all__ = ["PULSE_NAMES", "NamedAxis"]

#: Roles whose line must make pulses: a channel named so is refused when its waveform says it
#: makes none (:meth:`NamedAxis._no_pulse_line`).
PULSE_NAMES = ("step", "up", "down")
#: Other lines most like a STEP that a refused name's question offers.
_OTHER_CANDIDATES = 4


class NamedAxis(State):
    """The stage of a capture whose channels are named after their roles."""

    def _named(self, kind: str, chans: list[Channel]) -> bool:
        """The one axis ``check`` maps by channel names without ``--map`` (a channel called
        ``step``, ``up`` or ``phase-A``; :func:`wavecheck.engine.planning.auto_map`), with what the
        waveforms say of each line; False (nothing done) when the names give no unique channel
        for the first role."""
        number, roles = NAMED_KINDS[kind]
        found: list[tuple[str, Channel]] = []
        for role in roles:
            hits = [c for c in self.cap.channels if leaf(c.name) == role.lower()]
            if len(hits) == 1:
                found.append((role, hits[0]))
        if not found or found[0][0] != roles[0]:
            return False
        self._buses(chans)
        pulse_roles = [r for r, _ in found if r not in ("dir", "enable")]
        notes = []
        if kind == "phase-a":
            group = [c for r, c in found if r in pulse_roles]
            found_groups = find_phase_groups(group, self.res).all_groups
            fits = [g for g in found_groups if len(g.channels) == len(group)]
            number = fits[0].step_type if fits else 0
            if not fits:
                notes.append(
                    "the phase outputs walk no LinuxCNC table: give the step type (--type)"
                )
        refused = self._name_conflicts(found)
        if refused:  # a name is a hint: the waveform says this line is no such pulse line
            self.conflicts += [r.conflict for r in refused]
            for _, c in found:
                self.why.setdefault(c.index, "named after a role (see below)")
                self.taken.add(c.index)
            self.named = True
            return True
        choices = []
        for role, c in found:
            look = self.looks[c.index]
            against = self._against(c, role)
            evidence = f"named {c.name!r}; its waveform: {look.evidence}"
            if c.index in self.why:  # goes x/z: its unknown stretches are left out of the checks
                evidence += f"; {self.why.pop(c.index)}"
            step = self.looks[found[0][1].index].pulses
            if role == "dir" and step is not None:
                fit = dir_fit(c, found[0][1], step)
                evidence += f"; {fit.evidence()}" if fit is not None else ""
            if against:
                notes.append(
                    f"{role} {self.name_of(c)} is taken by its name, but its waveform says it is "
                    f"no {role.upper()} ({against}): check checks it as named; give --map to "
                    "check another line"
                )
            active = look.pulses.level if look.pulses is not None and role != "dir" else None
            choices.append(self.choice(role, c, evidence, "name", active))
        pulse = [c for r, c in found if r in pulse_roles]
        motion = np.sort(
            np.concatenate(
                [p.starts for p in (self.looks[c.index].pulses for c in pulse) if p is not None]
                or [np.zeros(0, np.int64)]
            )
        )
        axis_kind = {"step": "step-dir", "up": "up-down", "phase-a": "phases"}[kind]
        self.axes.append(FoundAxis(axis_kind, number, choices, pulse, motion, notes))
        self.named = True
        return True

    def _no_pulse_line(self, c: Channel) -> str:
        """What in the waveform of ``c`` says it is no STEP, UP or DOWN line whatever its name
        (empty when nothing does): a bus's clock, data or gate, a free-running clock, a line
        that never changes or never makes one whole pulse. Pulses the waveform cannot tell from
        steps (a few, at one rate, coded) do not contradict a name, and neither do PWM or a
        serial line's look: a base thread's step generator puts every edge on its period's
        lattice, and its latency varies the widths (``stepgen simulate`` is read so)."""
        no = self.bus.no_step(c.index)
        if no is not None:
            return no
        # a line that changes is a clock only at one rate: told without its whole look mostly
        if not len(c.edges) or (self.may_be_one_rate(c) and self.looks[c.index].kind == "clock"):
            return self.looks[c.index].evidence  # unchanging, or a clock
        if len(c.edges) < 2:
            return f"{self.looks[c.index].evidence}: not one whole pulse"
        return ""

    def _name_conflicts(self, found: list[tuple[str, Channel]]) -> list[NameRefused]:
        """The pulse roles (STEP, UP, DOWN) of ``found`` (role, channel named so) whose waveform
        says the line is none (:meth:`_no_pulse_line`), each with the reason and the other lines
        most like a STEP. Needs the bus findings of every line (:meth:`_buses`)."""
        out = []
        named = {c.index for _, c in found}
        for role, c in found:
            if role not in PULSE_NAMES or not (why := self._no_pulse_line(c)):
                continue
            others = [x for x in self._candidates() if x.index not in named][:_OTHER_CANDIDATES]
            conflict = Conflict(
                f"{self.name_of(c)} is named {role.upper()}, but its waveform is no "
                f"{role.upper()} line ({why}); a name is no evidence against the waveform",
                (
                    f"{role}={self.refs[c.index]}: named so; {self.looks[c.index].evidence}",
                    *(
                        f"{role}={self.refs[x.index]}: {self.looks[x.index].evidence}"
                        for x in others
                    ),
                ),
            )
            refs = tuple(self.refs[x.index] for x in others)
            out.append(NameRefused(role, self.refs[c.index], refs, conflict))
        return out

    def _against(self, c: Channel, role: str) -> str:
        """What in the waveform of ``c`` says it is no ``role`` (empty when nothing does)."""
        look = self.looks[c.index]
        if role in ("dir", "enable") or role.startswith("phase-"):
            return self.bus.data.get(c.index, "")
        no = self.bus.no_step(c.index)
        if no is not None:
            return no
        if look.kind in ("clock", "pwm", "serial", "constant"):
            return look.word
        if look.kind == "other":
            return "not a pulse train"
        return ""
