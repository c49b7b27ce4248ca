"""Propose channel roles from the waveforms: the relations between channels, and the proposal.

See :mod:`wavecheck.roles` for the rules. The stages: phase groups, pulse lines, DIRs
(:mod:`wavecheck.roles.dirs` fits and assigns them), up/down pairs (:mod:`wavecheck.roles.updown`
fits them; which to propose is decided here), DIRs that never change, ENABLEs; then the proposal.
Each relation is a few ``numpy`` passes over edge arrays (``searchsorted``, ``bincount``); nothing
loops over edges in Python.
"""

from __future__ import annotations

import itertools
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from wavecheck.capture.edges import Capture, Channel
from wavecheck.roles.buses import BusFindings, find_buses
from wavecheck.roles.dirs import DirFit, assign, at_pauses, dir_fit
from wavecheck.roles.dirs import plural as _plural
from wavecheck.roles.features import ChannelLook, Pulses, look_at
from wavecheck.roles.motion import (
    REQUEST_SHARE,
    copies,
    max_steps_inside,
    off_around,
    steps_right_after,
)
from wavecheck.roles.names import NAMED_KINDS, NameHint, leaf, name_hint, named_kind
from wavecheck.roles.phases import BUDGET, PhaseGroup, find_phase_groups
from wavecheck.roles.proposal import (
    AxisProposal,
    Basis,
    Conflict,
    LineLook,
    NameRefused,
    Proposal,
    RoleChoice,
    SharedLine,
    Unassigned,
)
from wavecheck.roles.updown import UpDownFit, up_down

__all__ = ["PULSE_NAMES", "best_channel", "name_conflicts", "propose"]

_AXIS_LETTERS = "abcdefghijklmnopqrstuvwxyz"
#: Roles whose line must make pulses: a channel named so is refused when its waveform says it
#: makes none (:meth:`_Inference._no_pulse_line`).
PULSE_NAMES = ("step", "up", "down")
#: Other lines most like a STEP that a refused name's question offers.
_OTHER_CANDIDATES = 4

I64 = npt.NDArray[np.int64]


def _level_at(ch: Channel, times: I64) -> I64:
    """Level of ``ch`` just after each of ``times`` (an edge at that very tick counts)."""
    n = np.searchsorted(ch.edges, times, side="right")
    return (ch.initial ^ (n & 1)).astype(np.int64)


def _pulses_inside(d: Channel, dp: Pulses, s_starts: I64) -> int:
    """Number of ``s_starts`` that fall while ``d`` is at its pulse level."""
    return int(np.count_nonzero(_level_at(d, s_starts) == dp.level))


@dataclass(eq=False)
class _Axis:
    kind: str
    step_type: int
    roles: list[RoleChoice]
    channels: list[Channel]  # the pulse / phase channels
    motion: I64  # ticks at which the axis moves (pulse starts, phase changes)
    notes: list[str]


class _Inference:
    def __init__(self, cap: Capture) -> None:
        self.cap = cap
        self.looks: dict[int, ChannelLook] = {c.index: look_at(c, cap) for c in cap.channels}
        self.hints: dict[int, NameHint] = {c.index: name_hint(c.name) for c in cap.channels}
        self.refs = self._refs()
        self.taken: set[int] = set()
        self.axes: list[_Axis] = []
        self.shared: list[tuple[Channel, str, list[_Axis]]] = []
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

    # ---------------------------------------------------------------- stages
    def run(self) -> Proposal:
        chans = [c for c in self.cap.channels if len(c.xz_times) == 0]
        for c in self.cap.channels:
            if len(c.xz_times):
                self.why[c.index] = f"goes x/z {_plural(len(c.xz_times), 'time')}"
        kind = named_kind([c.name for c in self.cap.channels])
        if kind is not None and self._named(kind, chans):
            return self._finish()
        chans = self._without_copies(chans)
        # stepgen's phase outputs change only on its base period, so they can pass as serial
        search = find_phase_groups([c for c in chans if len(c.edges)], self.res)
        self.phase_cut = search.cut_short
        for g in search.groups:
            self._phase_axis(g)
        for g in search.steady + search.commutation + search.named_other:
            if g.named:
                self._phase_axis(g)
            else:
                self._phase_refused(
                    g,
                    "steady" if g in search.steady else "other" if g in search.named_other else "",
                )
        movers = [
            c
            for c in chans
            if self.looks[c.index].kind not in ("constant", "serial") and c.index not in self.taken
        ]
        self._buses(chans)
        pulse = [c for c in movers if self._step_candidate(c)]
        pulse = self._step_requests(self._demote(pulse))
        self.turns = self._takes_turns(pulse)
        in_pulse = {c.index for c in pulse}
        # lines of a few pulses: a STEP only with a DIR of their own; they may be DIRs as well
        few = [c for c in movers if c.index not in in_pulse and self._few_candidate(c)]
        # coded lines compete for DIRs too (a coded STEP's DIR is no other line's), but stay a
        # question whatever DIR they get
        coded = [c for c in movers if c.index not in in_pulse and self._coded_candidate(c)]
        others = [c for c in movers if c.index not in in_pulse and self._dir_candidate(c)]
        dirs = self._dirs(pulse + few + coded, others)
        as_dir = {f.d.index for f in dirs.values()}
        for c in few:
            if c.index in as_dir:
                dirs.pop(c.index, None)  # a DIR itself: its own "DIR" is none
        for c in coded:
            fit = dirs.pop(c.index, None)
            if fit is not None:
                self.why[fit.d.index] = f"fits as the DIR of {self.name_of(c)} (see below)"
                self.taken.add(fit.d.index)
        pulse += [c for c in few if c.index in dirs]
        self._pulse_axes(pulse, dirs)
        self._unsettled(
            [c for c in few if c.index not in dirs and not self._holds_steps(c)],
            "lines with too few pulses to tell a STEP of a short move from a reset, interrupt "
            "or handshake line",
            "too few pulses to tell (see below)",
        )
        self._unsettled(
            [c for c in movers if self._coded_candidate(c)],
            "pulse lines whose rate jumps as a code's does, beside step axes: a STEP of short, "
            "jerky moves, or a coded line?",
            "coded pulses, or a STEP (see below)",
        )
        self._constant_dirs([c for c in chans if self.looks[c.index].kind == "constant"])
        self._enables(
            [c for c in movers if c.index not in self.taken and self._enable_candidate(c)]
        )
        self._unsettled(
            [c for c in movers if self._named_against(c)],
            "lines that look like step trains but are named otherwise (a line named DIR, ENABLE "
            "or another function such as LED or IRQ is never taken as a STEP against its name)",
            "a step train named otherwise (see below)",
        )
        return self._finish()

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

    def _buses(self, chans: list[Channel]) -> None:
        """Bus clocks, data, strobes and gates among the changing lines not yet taken."""
        changing = [c for c in chans if len(c.edges) and c.index not in self.taken]
        clock_like = {c.index for c in changing if self.looks[c.index].clock_like}
        starts = {
            i: look.pulses.starts
            for i, look in self.looks.items()
            if look.pulses is not None and (look.is_step_like or look.step_by_name)
        }
        self.bus = find_buses(changing, max(self.cap.resolution_ticks, 0), clock_like, starts)

    def _named(self, kind: str, chans: list[Channel]) -> bool:
        """The one axis ``check`` maps by channel names without ``--map`` (a channel called
        ``step``, ``up`` or ``phase-A``; :func:`wavecheck.engine.auto_map`), with what the
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
        self.axes.append(_Axis(axis_kind, number, choices, pulse, motion, notes))
        self.named = True
        return True

    def _no_pulse_line(self, c: Channel) -> str:
        """What in the waveform of ``c`` says it is no STEP, UP or DOWN line whatever its name
        (empty when nothing does): a bus's clock, data or gate, a clock, PWM, a serial line, a
        line that never changes or never makes one whole pulse. Pulses the waveform cannot tell
        from steps (a few, at one rate, coded) do not contradict a name."""
        look = self.looks[c.index]
        no = self.bus.no_step(c.index)
        if no is not None:
            return no
        if look.kind in ("clock", "pwm", "serial", "constant"):
            return look.evidence
        if len(c.edges) < 2:
            return f"{look.evidence}: not one whole pulse"
        return ""

    def _name_conflicts(self, found: list[tuple[str, Channel]]) -> list[NameRefused]:
        """The pulse roles (STEP, UP, DOWN) of ``found`` (role, channel named so) whose waveform
        says the line is none (:meth:`_no_pulse_line`), each with the reason and the other lines
        most like a STEP. Needs the bus findings."""
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
        self.axes.append(_Axis("phases", g.step_type, roles, list(g.channels), g.times, notes))

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
                if _pulses_inside(d, dp, sp.starts) >= dp.count and dir_fit(d, s, sp):
                    demote = True
                    break
            if not demote:
                keep.append(d)
        return keep

    def _dirs(self, pulse: list[Channel], others: list[Channel]) -> dict[int, DirFit]:
        """DIR fits, STEP channel index → fit; conflicts recorded (see :mod:`wavecheck.roles.dirs`).

        A line's candidates are the STEP lines it fits consistently (every change at a reversal of
        their rate or outside their motion); a line that fits a single STEP line keeps it even
        when not consistent (it is that line's DIR or no DIR at all). A name with an axis narrows
        the candidates to the one with the same axis.
        """
        fits_of: dict[int, list[DirFit]] = {}
        cands: dict[int, list[DirFit]] = {}
        for d in others:
            fits = []
            for s in pulse:
                if s.index == d.index:
                    continue  # a line of a few pulses is a STEP candidate and a DIR candidate
                sp = self.looks[s.index].pulses
                assert sp is not None
                f = dir_fit(d, s, sp)
                if f is not None:
                    fits.append(f)
            if not fits:
                continue
            fits_of[d.index] = fits
            good = [f for f in fits if f.consistent] if len(fits) > 1 else fits
            axis = self.hints[d.index].axis
            # a DIR named with an axis (y_dir, "DIR (Y axis)") goes to the one STEP of that axis
            # when the waveform cannot tell its candidates apart
            by_name = self.hints[d.index].fits("dir") and axis is not None
            pool = good if good or not by_name else fits
            same = [f for f in pool if axis is not None and self.hints[f.s.index].axis == axis]
            if len(same) == 1:
                good = same
            if not good:
                self._dir_conflict(
                    f"{self.name_of(d)} fits as the DIR of several STEP lines, and changes while "
                    "each of them runs steadily",
                    [d.index],
                    fits,
                )
                continue
            cands[d.index] = good
        # two lines whose only candidate is one STEP: a DIR-named one takes it
        only: dict[int, list[DirFit]] = {}
        for fits in cands.values():
            if len(fits) == 1:
                only.setdefault(fits[0].s.index, []).append(fits[0])
        for fits in only.values():
            named = [f for f in fits if self.hints[f.d.index].fits("dir")]
            if len(fits) > 1 and len(named) == 1:
                for f in fits:
                    if f is not named[0]:
                        del cands[f.d.index]
                        self.why[f.d.index] = (
                            f"also fits as DIR of {self.name_of(f.s)}, whose DIR is "
                            f"{self.name_of(named[0].d)} by name"
                        )
        got = assign(cands)
        for lines in got.crowded:
            fits = [f for d in lines for f in cands[d]]
            steps = {f.s.index for f in fits}
            if len(steps) == 1:
                q = f"{_plural(len(lines), 'channel')} fit as the DIR of {self.name_of(fits[0].s)}"
            else:
                q = (
                    f"{_plural(len(lines), 'channel')} fit as DIRs of only "
                    f"{_plural(len(steps), 'STEP line')}: which is whose DIR?"
                )
            self._dir_conflict(q, list(lines), fits)
        for di, fits in got.undecided.items():
            self._dir_conflict(
                f"{self.name_of(fits[0].d)} fits as the DIR of several STEP lines", [di], fits
            )
        for f in got.chosen.values():
            notes = []
            for g in fits_of[f.d.index]:
                if g.s.index == f.s.index:
                    continue
                has = got.chosen.get(g.s.index)
                if has is not None:
                    notes.append(f"{self.name_of(g.s)} has DIR {self.name_of(has.d)}")
                elif not g.consistent:
                    notes.append(
                        f"{self.name_of(g.s)} runs steadily through "
                        f"{g.toggles - g.at_reversal - g.outside:,} of its changes"
                    )
                else:
                    notes.append(
                        f"{self.name_of(g.s)} cannot take it: another changing line would be "
                        "left without a STEP line it fits"
                    )
            if notes:
                self.dir_notes[f.d.index] = f" (it also fits other STEP lines: {'; '.join(notes)})"
        return got.chosen

    def _dir_conflict(self, question: str, lines: list[int], fits: list[DirFit]) -> None:
        """Refuse ``lines`` as DIRs: a conflict listing ``fits``; their STEPs become unsure."""
        self.conflicts.append(
            Conflict(
                question,
                tuple(
                    f"{self.name_of(f.d)} as DIR of {self.name_of(f.s)}: {f.evidence()}"
                    for f in fits
                ),
            )
        )
        for d in lines:
            self.why[d] = "ambiguous DIR (see below)"
            self.taken.add(d)
        self.unsure_steps |= {f.s.index for f in fits}

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
            self.axes.append(_Axis("up-down", 1, roles, [up, down], motion, notes))
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
            self.axes.append(_Axis("step-dir", 0, roles, [s], look.pulses.starts, []))

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

    def _constant_dirs(self, constants: list[Channel]) -> None:
        missing = [a for a in self.axes if a.kind == "step-dir" and len(a.roles) == 1]
        if not missing:
            return
        free = [c for c in constants if c.index not in self.taken]
        # by name: a DIR-named unchanging channel with the STEP's axis (or the only pair)
        for a in list(missing):
            axis = self.hints[a.channels[0].index].axis
            named = [
                c
                for c in free
                if self.hints[c.index].fits("dir")
                and (self.hints[c.index].axis == axis or (axis is None and len(missing) == 1))
            ]
            if len(named) == 1:
                c = named[0]
                a.roles.append(
                    self.choice(
                        "dir",
                        c,
                        f"{self.looks[c.index].evidence}: no waveform evidence; named like "
                        "the DIR of this axis",
                        "name",
                    )
                )
                free = [f for f in free if f.index != c.index]
                missing.remove(a)
        by_index = {c.index: c for c in free}
        nexts = [by_index.get(a.channels[0].index + 1) for a in missing]
        unsure = any("DIR" in c.question for c in self.conflicts)  # a changing DIR is unplaced
        if (
            missing
            and not unsure
            and all(c is not None and self.hints[c.index].neutral for c in nexts)
        ):
            for a, nxt in zip(missing, nexts, strict=True):
                assert nxt is not None
                step = a.channels[0]
                a.roles.append(
                    self.choice(
                        "dir",
                        nxt,
                        f"{self.looks[nxt.index].evidence}: no waveform evidence; taken as "
                        f"the DIR of {self.name_of(step)} because it is the next channel, as every "
                        "STEP without a changing DIR is followed by an unchanging one (check the "
                        "wiring)",
                        "layout",
                    )
                )
                a.notes.append(
                    "its DIR never changes: direction and final position rest on a guess"
                )
        for a in self.axes:
            if a.kind == "step-dir" and len(a.roles) == 1:
                a.notes.append("no DIR found: direction and final position are unknown")

    def _enables(self, cands: list[Channel]) -> None:
        moving = [a for a in self.axes if len(a.motion)]
        for e in cands:
            per_axis = []
            for a in moving:
                lv = _level_at(e, a.motion)
                per_axis.append((int(np.count_nonzero(lv == 0)), int(np.count_nonzero(lv == 1))))
            served: dict[int, list[int]] = {0: [], 1: []}
            for k, (lo, hi) in enumerate(per_axis):
                if lo and not hi:
                    served[0].append(k)
                elif hi and not lo:
                    served[1].append(k)
            mixed = [k for k, (lo, hi) in enumerate(per_axis) if lo and hi]
            if served[0] and served[1] or not (served[0] or served[1]):
                continue
            active = 0 if served[0] else 1
            axes = [moving[k] for k in served[active]]
            # an ENABLE changes where its axes stand still, never while one runs
            if any(sum(at_pauses(e.edges, a.motion)[:2]) < len(e.edges) for a in axes):
                continue
            motion = np.concatenate([a.motion for a in axes])
            if not self.hints[e.index].fits("enable") and not off_around(
                e, active, motion, self.cap.start
            ):
                continue  # never seen off between steps: no gating shown
            n_events = sum(per_axis[k][active] for k in served[active])
            ev = (
                f"changes {_plural(len(e.edges), 'time')}; all {n_events:,} steps of "
                f"{', '.join(self.name_of(a.channels[0]) for a in axes)} happen while it is "
                f"{'high' if active else 'low'}, none while it is {'low' if active else 'high'}"
            )
            if mixed:
                ev += f"; other axes move at both levels ({len(mixed)})"
            existing = [a for a in axes if any(r.role == "enable" for r in a.roles)]
            if existing:
                self.conflicts.append(
                    Conflict(
                        f"{self.name_of(e)} and another line both fit as ENABLE",
                        (f"ENABLE {self.name_of(e)}: {ev}",)
                        + tuple(
                            f"ENABLE {r.index}={r.channel!r}: {r.evidence}"
                            for a in existing
                            for r in a.roles
                            if r.role == "enable"
                        ),
                    )
                )
                self.why[e.index] = "ambiguous ENABLE (see below)"
                self.taken.add(e.index)
                continue
            for a in axes:
                a.roles.append(self.choice("enable", e, ev, active=active))
            if len(axes) > 1:
                self.shared.append((e, ev, axes))

    # ---------------------------------------------------------------- result
    def _axis_names(self, axes: list[_Axis]) -> list[str]:
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
    def _proposed(axes: list[_Axis], names: list[str]) -> tuple[AxisProposal, ...]:
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

    def _suggested(self) -> list[_Axis]:
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
            out.append(_Axis("step-dir", 0, roles, [s], motion, []))
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


def _index(c: Channel) -> int:
    return c.index


def propose(capture: Capture) -> Proposal:
    """Propose axes and roles for ``capture``'s channels from their waveforms.

    The proposal is :attr:`~wavecheck.roles.proposal.Proposal.unambiguous` when it may be used
    without asking; otherwise :attr:`~wavecheck.roles.proposal.Proposal.ambiguous` lists the
    conflicts.
    """
    return _Inference(capture).run()


def name_conflicts(capture: Capture, named: Mapping[str, int]) -> tuple[NameRefused, ...]:
    """The names a mapping by channel names must not follow: ``named`` is role → channel index
    (the lines :func:`wavecheck.engine.auto_map` maps by their names); for each STEP, UP or DOWN
    whose waveform says it makes no step pulses (a clock, a bus line, PWM, a serial line, no
    pulse at all), a :class:`~wavecheck.roles.proposal.NameRefused` with the reason and the lines
    most like a STEP. Empty when no name is contradicted. ``capture`` holds the edges (or its
    first part)."""
    inference = _Inference(capture)
    inference._buses([c for c in capture.channels if len(c.xz_times) == 0])
    found = [(role, capture.channels[index]) for role, index in named.items()]
    return tuple(inference._name_conflicts(found))


def best_channel(capture: Capture, role: str) -> str | None:
    """The ``--map`` reference of the channel most like ``role`` for a hint: the one channel
    whose name says ``role``, else for a pulse role the channel most like a STEP on its own
    waveform (no relations between lines are looked at); None when there is none."""
    inference = _Inference(capture)
    named = [c for c in capture.channels if inference.hints[c.index].fits(role)]
    if len(named) == 1:
        return inference.refs[named[0].index]
    if role in ("step", "up", "down"):
        best = inference._candidates()
        return inference.refs[best[0].index] if best else None
    return None
