"""Which lines may be what, on their own waveforms and the relations already found: STEP,
few-pulse and coded candidates, DIR and ENABLE candidates, copies of another line, a phase
sequencer's step request, pulse lines that are another's DIR, phase groups taken or refused,
and the lines left as a question beside the axes found."""

from __future__ import annotations

from wavecheck.capture.edges import Channel
from wavecheck.roles.dirs import dir_fit
from wavecheck.roles.motion import (
    REQUEST_SHARE,
    copies,
    max_steps_inside,
    steps_right_after,
)
from wavecheck.roles.phases import PhaseGroup
from wavecheck.roles.proposal import (
    Conflict,
)
from wavecheck.roles.state import FoundAxis, State, pulses_inside

__all__ = ["Candidates"]


class Candidates(State):
    """The stages that sort the lines into candidates."""

    def _without_copies(self, chans: list[Channel]) -> list[Channel]:
        """``chans`` without the lines that repeat an earlier one edge for edge
        (:func:`~wavecheck.roles.motion.copies`); each copy says of which line."""
        of = copies(chans)
        for i, original in of.items():
            self.why[i] = (
                f"the same waveform as {self.name_of(original)}, edge for edge (a copy: a port "
                "and the signal it drives); only that one is looked at"
            )
            self.taken.add(i)
        return [c for c in chans if c.index not in of]

    def _step_requests(self, pulse: list[Channel]) -> list[Channel]:
        """``pulse`` without the lines after whose pulses a phase axis changes (90 % of its
        changes within two pulse widths): the sequencer's step request or tick, not an axis of
        its own (a one-hot stepper's prescaler tick)."""
        phases = [a for a in self.axes if a.kind == "phases"]
        keep = []
        for c in pulse:
            p = self.looks[c.index].pulses
            assert p is not None
            for ph in phases:
                n = steps_right_after(p, ph.motion, self.res)
                if len(ph.motion) and n >= REQUEST_SHARE * len(ph.motion):
                    self.why[c.index] = (
                        f"{self.looks[c.index].evidence}; the phase outputs "
                        f"{', '.join(self.name_of(x) for x in ph.channels)} change right after "
                        f"{n:,} of its pulses (of {len(ph.motion):,} changes): their "
                        "sequencer's step request or tick, not an axis of its own"
                    )
                    self.taken.add(c.index)
                    break
            else:
                keep.append(c)
        return keep

    def _step_candidate(self, c: Channel) -> bool:
        """A STEP, UP or DOWN candidate: a step train, or pulses the waveform cannot tell from
        steps at one rate on a line named so; never a line the relations rule out."""
        look = self.looks[c.index]
        if self.bus.no_step(c.index) is not None:
            return False
        hint = self.hints[c.index]
        pulse_named = any(hint.fits(r) for r in ("step", "up", "down"))
        if not hint.neutral and not pulse_named:
            return False  # named DIR or ENABLE (x_dir): never taken against its name as a STEP
        if look.is_step_like:
            return True
        if look.step_by_name and pulse_named:
            self.by_name.add(c.index)
            return True
        return False

    def _few_candidate(self, c: Channel) -> bool:
        """A line with too few pulses to see a motor's rate in (:func:`look_at`'s ``few``),
        neither named otherwise nor ruled out by a relation: a STEP only with a DIR that changes
        between its pulses, with pulses at both of its levels."""
        hint = self.hints[c.index]
        return (
            self.looks[c.index].kind == "few"
            and self.bus.no_step(c.index) is None
            and (hint.neutral or hint.fits("step"))
        )

    def _coded_candidate(self, c: Channel) -> bool:
        """A neutrally named line of coded pulses that no relation rules out: a STEP of short,
        jerky moves or a coded line; asked about when axes are found beside it."""
        return (
            self.looks[c.index].kind == "coded"
            and self.bus.no_step(c.index) is None
            and self.hints[c.index].neutral
        )

    def _holds_steps(self, c: Channel) -> bool:
        """Whether a pulse of ``c`` lasts through two or more steps of a found axis: a level
        line (a DIR, an ENABLE, a mode), not a STEP of its own; said in its reason."""
        p = self.looks[c.index].pulses
        if p is None:
            return False
        for a in self.axes:
            n = max_steps_inside(p, a.motion)
            if n >= 2:
                self.why.setdefault(
                    c.index,
                    f"{self.looks[c.index].evidence}; a pulse of it lasts through {n:,} steps of "
                    f"{self.name_of(a.channels[0])}: a level line (a DIR, an ENABLE, a mode), "
                    "not a STEP of its own",
                )
                return True
        return False

    def _named_against(self, c: Channel) -> bool:
        """A step train whose name says DIR, ENABLE or another function, left out of the STEP
        candidates."""
        hint = self.hints[c.index]
        return (
            c.index not in self.taken
            and self.looks[c.index].is_step_like
            and self.bus.no_step(c.index) is None
            and not hint.neutral
            and not any(hint.fits(r) for r in ("step", "up", "down"))
        )

    def _unsettled(self, lines: list[Channel], question: str, why: str) -> None:
        """Lines that may be STEPs without the evidence to say so: when axes were found beside
        them, a question (checking the axes alone would pass over them silently); else they
        stay unassigned, named as candidates."""
        lines = [c for c in lines if c.index not in self.taken]
        if not lines or not (self.axes or self.conflicts):
            return
        self.conflicts.append(
            Conflict(
                question,
                tuple(f"{self.name_of(c)}: {self.looks[c.index].evidence}" for c in lines),
            )
        )
        for c in lines:
            self.why[c.index] = why
            self.taken.add(c.index)

    def _enable_candidate(self, c: Channel) -> bool:
        """An ENABLE candidate: a changing line that is no bus clock or data (a bus's chip
        select may be the ENABLE of an axis that moves while the bus idles)."""
        return c.index not in self.bus.clocks and c.index not in self.bus.data

    def _dir_candidate(self, c: Channel) -> bool:
        """A DIR candidate: a changing line that is no bus data (a line that gates another may
        still be the DIR of a third) and is not named after another function (an LED, a reset)."""
        return c.index not in self.bus.data and not self.hints[c.index].other

    def _phase_axis(self, g: PhaseGroup) -> None:
        roles = [
            self.choice(role, c, g.evidence() if k == 0 else f"phase {role[-1]} of that group")
            for k, (role, c) in enumerate(zip(g.roles, g.channels, strict=True))
        ]
        notes = []
        if not g.named:
            notes.append(
                "which output is phase-A is not told by the waveform (another order that fits "
                "runs the other way); the lowest channel fitting was taken"
            )
        self.axes.append(FoundAxis("phases", g.step_type, roles, list(g.channels), g.times, notes))

    def _phase_refused(self, g: PhaseGroup, why_kind: str) -> None:
        """Lines that walk a table without evidence of a motor: left out, with why."""
        if why_kind == "steady":
            why = (
                "at one rate, never speeding up or slowing down: a free-running divider or "
                "counter, or a handshake in bursts, as much as a motor at one constant speed (the "
                "waveform cannot tell; a phase axis only when named so, or with --map)"
            )
        elif why_kind == "other":
            why = (
                "a line of it is named after another function: a handshake's strobe and "
                "acknowledge walk quadrature too (a phase axis only when named so, or with --map)"
            )
        else:
            why = (
                "the states of a brushless motor's Hall sensors or commutation lines too (a "
                "phase axis only when named so, or with --map)"
            )
        names = ", ".join(self.name_of(c) for c in g.channels)
        for c in g.channels:
            self.why[c.index] = f"phase outputs? {names}: {g.evidence()}; {why}"
            self.taken.add(c.index)

    def _demote(self, pulse: list[Channel]) -> list[Channel]:
        """Drop pulse channels whose "pulses" are long enough to hold another line's pulses and
        that fit as that line's DIR (a DIR that changed a few times with similar levels)."""
        keep = []
        for d in pulse:
            dp = self.looks[d.index].pulses
            assert dp is not None
            demote = False
            for s in pulse:
                sp = self.looks[s.index].pulses
                assert sp is not None
                if s is d or sp.count <= dp.count:
                    continue
                if pulses_inside(d, dp, sp.starts) >= dp.count and dir_fit(d, s, sp):
                    demote = True
                    break
            if not demote:
                keep.append(d)
        return keep
