"""Channels found by their waveforms: which channel is whose STEP, DIR, UP/DOWN, phase or ENABLE.

:func:`propose` looks at every channel of a capture and returns a :class:`Proposal`: the axes
(each a kind, a LinuxCNC step type and a role → channel mapping with the evidence in words), shared
lines, channels left unassigned with why, the conflicts the waveforms cannot settle, what each line
looks like, and the channels most like a STEP (for hints). No role is given that the waveform
contradicts. The rules:

- **names after roles** (:mod:`wavecheck.roles.named`): when a channel is called ``step``,
  ``up`` or ``phase-A`` (the end of a hierarchical name, any case), the axis is the one
  ``check`` maps by those names without ``--map``; what the waveforms say against it goes into
  its notes. A name is a hint, not evidence: a STEP, UP or DOWN so named whose waveform makes
  no step pulses (a bus's clock, data or gate, a free-running clock, not one whole pulse) is
  refused, with the reason and the lines most like a STEP (:func:`name_conflicts`, which
  ``check`` asks too).
- **STEP**: a step train: many pulses at one level with nearly constant width, no longer than
  the gaps, at a rate that changes as a motor's does (:mod:`wavecheck.roles.features`,
  :mod:`wavecheck.roles.periodic`). A clock (one period, about 50 % duty, no pause) and PWM (one
  period, varying width) never are; pulses at one period without a pause, bursts at one rate
  without speeding up or slowing down, and coded pulses (periods that jump between neighbours)
  are a STEP only when named so, and so are fewer than 9 pulses (too few to see a motor's rate:
  a reset or interrupt line pulses so too; such a line is a STEP with a DIR of its own) and
  pulses whose widths follow the period (a tachometer, a Hall sensor, a STEP toggled once a
  step). A clock never slows down, even once. Serial lines (UART, SWO) never are: their
  intervals are whole multiples of one bit time with runs of several bits at both levels. A
  line named DIR, ENABLE or another function (LED, RST, IRQ, nWait; not CLK, a drive's STEP
  input) is never a STEP on its waveform. Lines that may be STEPs without that evidence (a few
  pulses, coded pulses, a step train named otherwise) are a question when axes were found
  beside them: checking those axes alone would pass over them.
- **copies and step requests**: a line whose waveform is an earlier line's edge for edge (a
  simulator's port and the signal it drives) is looked at once; a pulse line after whose pulses
  a phase axis changes is that sequencer's step request or tick, no axis.
- **buses** (:mod:`wavecheck.roles.buses`): a line that changes in step with one edge of
  another, at most once a period, is data of that bus clock; neither is a STEP, the data no DIR.
  A line every change of a busier line falls inside, at one of its levels, gates it (an ENABLE,
  a chip select, a frame line): never a STEP; the lines a bus's chip select frames and the pulses
  that follow its bursts at one delay (a latch strobe) are that bus's.
- **DIR** of a STEP line (:mod:`wavecheck.roles.dirs`): changes only between its pulses (never
  inside one; at the tick a pulse starts is allowed: DIR setup 0), with at least one pulse after
  each change before the next, and pulses at both of its levels. Among several STEP lines it fits,
  only those are candidates at whose reversals it changes (the period across each change is 1.25×
  the periods beside it: slow-down, gap, speed-up; or the change is before the first / after the
  last pulse): a change in a STEP's steady running proves it is not that STEP's DIR, and that is
  all a change proves (a line that changes mostly while its STEP runs at full rate is no DIR).
  A name with the same axis narrows the candidates. A STEP has one DIR, so the DIRs are a
  matching of changing lines to distinct STEP lines; a line is given a STEP only when every
  such matching gives it that STEP. A change that falls where several candidates all
  pause fits each of them: however near it is to one of them, it is ambiguous, and so is every
  pulse line it fits and every line those take turns with. Two DIRs for one STEP are ambiguous
  unless exactly one is named DIR.
- **UP/DOWN**: two pulse lines without a DIR that never pulse together and take turns: at each
  switch the period is no shorter than the periods beside it (a line pulsing within the other's
  run is another axis), with the same pulse level and width (one step generator drives both).
  If two or more unchanging channels could be the DIRs of two step axes moving one after the
  other, that is a conflict (unless the names say up/down or step).
- **phases**: 2..5 channels whose combined state walks one of LinuxCNC's tables and reverses or
  changes rate (:mod:`wavecheck.roles.phases`); a walk at one rate (a divider's nets, a
  handshake's bursts) or three lines walking a three-wire table (also Hall sensors) only when
  named so.
- **ENABLE**: a leftover changing line (no bus clock or data) at one level of which no axis ever
  moves, while some axes move at the other, and that changes only where they stand still
  (before the first and after the last pulse, or in pauses), seen off on both sides of some
  motion unless named so (a strobe at start-up is none); serving several axes it is a shared
  line.
- a **DIR that never changes** has no waveform evidence: a channel named like the axis's DIR is
  taken by name; else, when every STEP without a DIR is followed by an unchanging, neutrally named
  channel, each such channel is taken as that STEP's DIR by layout (the Smoothieware capture:
  3/4 and 5/6), flagged ``basis="layout"``.
- **names** (:mod:`wavecheck.roles.names`) name the axes and break ties; the waveform decides,
  and the evidence says when a name disagreed.

- **no axis found** (:mod:`wavecheck.roles.result`): the proposal's ``suggested`` axes are
  what to check *if* the lines most like a STEP are STEPs (every line of a few pulses, else the
  best one), each with a DIR named like its axis's or the unchanging channel after it: the
  refusal's hint never drops a DIR the capture may have.

Axis names: the axis letter or number the channel names give (``X_STEP`` → ``x``,
``stepgen.2.step`` → ``2``), else ``a``, ``b`` … in channel order (skipping letters the names
took). The ``--map`` text is :meth:`Proposal.map_args`.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from wavecheck.roles.infer import PULSE_NAMES, best_channel, name_conflicts, propose
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

__all__ = [
    "PULSE_NAMES",
    "AxisProposal",
    "Basis",
    "Conflict",
    "LineLook",
    "NameRefused",
    "Proposal",
    "RoleChoice",
    "SharedLine",
    "Unassigned",
    "best_channel",
    "name_conflicts",
    "propose",
]

#: Where each name above lives. They load on first use, so that ``wavecheck.roles.names`` (what
#: a channel's name says: read by every check, for :func:`~wavecheck.roles.names.leaf`) loads
#: none of the inference (issue 38: ~12 ms at every ``check`` start).
_LAZY = {
    **dict.fromkeys(("PULSE_NAMES", "best_channel", "name_conflicts", "propose"), "infer"),
    **dict.fromkeys(
        ("AxisProposal", "Basis", "Conflict", "LineLook", "NameRefused", "Proposal",
         "RoleChoice", "SharedLine", "Unassigned"),
        "proposal",
    ),
}  # fmt: skip


def __getattr__(name: str) -> Any:
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'wavecheck.roles' has no attribute {name!r}")
    value = getattr(importlib.import_module(f"wavecheck.roles.{module}"), name)
    globals()[name] = value
    return value
