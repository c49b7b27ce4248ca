"""Propose channel roles from the waveforms: the stages in order, and the front functions.

See :mod:`wavecheck.roles` for the rules. :class:`_Inference` is one capture's inference; its
stages live each in a module of its own, sharing :class:`~wavecheck.roles.state.State`:

- :mod:`~wavecheck.roles.named`: channels named after their roles (judged on their waveforms);
- :mod:`~wavecheck.roles.candidates`: copies, phase groups, step requests, and which line may be
  a STEP, a DIR or an ENABLE;
- :mod:`~wavecheck.roles.dir_choice`: changing DIRs (:mod:`wavecheck.roles.dirs` fits them);
- :mod:`~wavecheck.roles.pulse_axes`: step/dir axes and up/down pairs
  (:mod:`wavecheck.roles.updown` fits them);
- :mod:`~wavecheck.roles.still`: DIRs that never change, ENABLEs;
- :mod:`~wavecheck.roles.result`: the proposal.

Each relation is a few ``numpy`` passes over edge arrays (``searchsorted``, ``bincount``); nothing
loops over edges in Python.
"""

from __future__ import annotations

from collections.abc import Mapping

from wavecheck.capture.edges import Capture
from wavecheck.roles.candidates import Candidates
from wavecheck.roles.dir_choice import DirChoice
from wavecheck.roles.dirs import plural as _plural
from wavecheck.roles.named import PULSE_NAMES, NamedAxis
from wavecheck.roles.names import named_kind
from wavecheck.roles.phases import find_phase_groups
from wavecheck.roles.proposal import NameRefused, Proposal
from wavecheck.roles.pulse_axes import PulseAxes
from wavecheck.roles.result import Result
from wavecheck.roles.still import StillLines

__all__ = ["PULSE_NAMES", "best_channel", "name_conflicts", "propose"]


class _Inference(NamedAxis, Candidates, DirChoice, PulseAxes, StillLines, Result):
    """One capture's inference: the stages in :meth:`run`'s order (each in its module)."""

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


def propose(capture: Capture) -> Proposal:
    """Propose axes and roles for ``capture``'s channels from their waveforms.

    The proposal is :attr:`~wavecheck.roles.proposal.Proposal.unambiguous` when it may be used
    without asking; otherwise :attr:`~wavecheck.roles.proposal.Proposal.ambiguous` lists the
    conflicts.
    """
    return _Inference(capture).run()


def name_conflicts(capture: Capture, named: Mapping[str, int]) -> tuple[NameRefused, ...]:
    """The names a mapping by channel names must not follow: ``named`` is role → channel index
    (the lines :func:`wavecheck.engine.planning.auto_map` maps by their names); for each STEP, UP or DOWN
    whose waveform says it makes no step pulses (a free-running clock, a bus line, not one
    whole pulse), a :class:`~wavecheck.roles.proposal.NameRefused` with the reason and the lines
    most like a STEP. Empty when no name is contradicted. ``capture`` holds the edges (or its
    first part)."""
    inference = _Inference(capture)
    chans = [c for c in capture.channels if len(c.xz_times) == 0]
    found = [(role, capture.channels[index]) for role, index in named.items()]
    pulse = [c for role, c in found if role in PULSE_NAMES]
    # the question first, on the looks and bus findings of the named pulse lines only
    inference._buses(chans, asked=pulse)
    if not any(inference._no_pulse_line(c) for c in pulse):
        return ()
    inference._buses(chans)  # a refusal offers the lines most like a STEP: every line's findings
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
