"""The proposal: axes with their role → channel mapping and the evidence, shared lines, leftovers
and conflicts; and the ``--map`` text that reproduces it.

``--map`` syntax (issue 13): one axis → ``--map step=5,dir=6``; several →
``--map x.step=5,x.dir=6 --map y.step=3,y.dir=4``. A shared line (one ENABLE for several axes)
appears in each axis it serves. A channel is written by name when its name finds it and nothing
else (``Capture.channel``), else by index; each ``--map`` value is shell-quoted when needed.
"""

from __future__ import annotations

import shlex
from typing import Any, Literal

from wavecheck.record import field, record
from wavecheck.steptypes import StepKind

__all__ = [
    "AxisProposal",
    "Basis",
    "Conflict",
    "LineLook",
    "Proposal",
    "RoleChoice",
    "SharedLine",
    "Unassigned",
]

Basis = Literal["waveform", "name", "layout"]
"""What decided a role: the waveform; the name (the waveform could not, e.g. a DIR that never
changes but is named ``Y_DIR``); or the layout (an unchanging channel right after a STEP, taken as
its DIR: no waveform evidence at all — check the wiring)."""


@record(frozen=True)
class RoleChoice:
    """One role of one axis: the channel, how to write it in ``--map``, and why.

    Attributes:
        role: ``step``, ``dir``, ``up``, ``down``, ``phase-A`` … ``phase-E`` or ``enable``.
        channel: the channel's name as in the capture.
        index: the channel's index.
        ref: how ``--map`` names it (the name, or the index when the name is not unique).
        evidence: what was seen, in words.
        basis: what decided.
        active_level: for ``enable``, the level at which pulses happen (0 → ``--invert enable``);
            for pulse roles, the pulse level; None for ``dir``.
    """

    role: str
    channel: str
    index: int
    ref: str
    evidence: str
    basis: Basis = "waveform"
    active_level: int | None = None


@record(frozen=True)
class AxisProposal:
    """One axis.

    Attributes:
        name: the axis letter or number its channels' names give (``x``, ``2``), else ``a``,
            ``b`` … in channel order.
        kind: ``step-dir``, ``up-down`` or ``phases``.
        step_type: LinuxCNC step type: 0, 1, or the table number 2..14 for phases (a type 15
            user table equal to one of those is reported as that type).
        roles: the roles, pulse roles first.
        notes: remarks (a missing DIR, a guess to check).
    """

    name: str
    kind: StepKind
    step_type: int
    roles: tuple[RoleChoice, ...]
    notes: tuple[str, ...] = ()

    @property
    def mapping(self) -> dict[str, str]:
        """role → channel reference for ``--map``/``build_interface``."""
        return {r.role: r.ref for r in self.roles}

    def role(self, role: str) -> RoleChoice | None:
        """The choice for ``role``, or None."""
        return next((r for r in self.roles if r.role == role), None)

    @property
    def inverted(self) -> tuple[str, ...]:
        """Roles to pass to ``--invert`` (an ENABLE that is active low)."""
        return tuple(r.role for r in self.roles if r.role == "enable" and r.active_level == 0)


@record(frozen=True)
class SharedLine:
    """A line that serves several axes (one ENABLE for all of them)."""

    role: str
    channel: str
    index: int
    axes: tuple[str, ...]
    evidence: str


@record(frozen=True)
class Unassigned:
    """A channel given no role, and why."""

    channel: str
    index: int
    why: str


@record(frozen=True)
class Conflict:
    """Something the waveform cannot decide: a question and the candidate answers."""

    question: str
    candidates: tuple[str, ...]


@record(frozen=True)
class NameRefused:
    """A channel named after a pulse role whose waveform says it is none (a name is a hint).

    Attributes:
        role: the role it is named after (``"step"``, ``"up"``, ``"down"``).
        ref: its ``--map`` reference.
        others: ``--map`` references of the other lines most like a STEP, best first.
        conflict: the question, with the line and those others as candidates.
    """

    role: str
    ref: str
    others: tuple[str, ...]
    conflict: Conflict


@record(frozen=True)
class LineLook:
    """What one channel looks like, in a word or two (``"clock"``, ``"bus data"``)."""

    channel: str
    index: int
    word: str


#: How the lines of a capture without step signals are summed up: the words of
#: :class:`LineLook` gathered under one heading each, in this order.
_SUMMARY: tuple[tuple[str, tuple[str, ...]], ...] = (
    ("clock", ("clock",)),
    (
        "SPI-like bus",
        ("bus clock", "bus data", "chip select", "bus strobe"),
    ),
    ("serial line", ("serial line",)),
    ("PWM", ("PWM",)),
    ("periodic pulses", ("periodic pulses",)),
    ("bursts at one rate", ("bursts at one rate",)),
    ("coded pulses", ("coded pulses",)),
    ("pulses at one duty", ("pulses at one duty",)),
    ("a few pulses", ("a few pulses",)),
    ("pulse train", ("pulse train",)),
    ("enable/select", ("enable/select",)),
    ("phase output", ("phase output",)),
    ("other", ("other",)),
    ("unknown (x/z)", ("unknown (x/z)",)),
    ("unchanging", ("unchanging",)),
)


def axes_map_args(axes: tuple[AxisProposal, ...]) -> str:
    """The ``--map`` options that give ``axes``, ready to paste into a shell (one axis unnamed)."""
    groups: list[tuple[str | None, AxisProposal]]
    if len(axes) == 1:
        groups = [(None, axes[0])]
    else:
        groups = [(a.name, a) for a in axes]
    out: list[str] = []
    for prefix, axis in groups:
        pre = f"{prefix}." if prefix is not None else ""
        value = ",".join(f"{pre}{r.role}={r.ref}" for r in axis.roles)
        out.append(f"--map {shlex.quote(value)}")
    return " ".join(out)


@record(frozen=True)
class Proposal:
    """Roles proposed for a capture's channels (see :func:`wavecheck.roles.propose`).

    A channel appears in exactly one of: an axis role (possibly a shared line too), ``unassigned``,
    or a conflict's candidates (then it may also be left out of the axes).
    """

    axes: tuple[AxisProposal, ...]
    shared: tuple[SharedLine, ...] = ()
    unassigned: tuple[Unassigned, ...] = ()
    ambiguous: tuple[Conflict, ...] = field(default_factory=tuple)
    looks: tuple[LineLook, ...] = ()
    """What every channel looks like (for the summary of a capture without step signals)."""
    candidates: tuple[str, ...] = ()
    """``--map`` references of the channels most like a STEP, best first (for the hint of an
    error: a line named so, a step train, then pulses the waveform cannot tell from steps)."""
    named: bool = False
    """The channels are named after their roles (``step``, ``up``, ``phase-A``): the axis is the
    one ``check`` maps by those names without ``--map``, with what the waveforms say of it."""
    suggested: tuple[AxisProposal, ...] = ()
    """When no axis is found: the axes to check *if* the lines most like a STEP are STEPs (every
    line of a few pulses, else the best one), each with the DIR a name or the layout gives it
    (never one dropped); a hint for the refusal, not a finding."""

    @property
    def unambiguous(self) -> bool:
        """True when there is at least one axis and nothing is ambiguous: safe to use unasked."""
        return bool(self.axes) and not self.ambiguous

    def axis(self, name: str) -> AxisProposal:
        """The axis called ``name``.

        Raises:
            KeyError: no such axis.
        """
        for a in self.axes:
            if a.name == name:
                return a
        raise KeyError(name)

    def summary(self) -> str:
        """What the lines look like, in one line: ``clock (clk); serial line (TX, RX); …``."""
        by_word: dict[str, list[str]] = {}
        for look in self.looks:
            by_word.setdefault(look.word, []).append(look.channel)
        parts = []
        for heading, words in _SUMMARY:
            if heading == "SPI-like bus":
                roles = [(w, by_word.get(w, [])) for w in words]
                if any(names for _, names in roles):
                    inner = "; ".join(
                        f"{w.removeprefix('bus ')} {', '.join(names)}"
                        for w, names in roles
                        if names
                    )
                    parts.append(f"{heading} ({inner})")
                continue
            names = [n for w in words for n in by_word.get(w, [])]
            if names:
                parts.append(f"{heading} ({', '.join(names)})")
        return "; ".join(parts)

    def map_args(self) -> str:
        """The ``--map`` options that give this mapping, ready to paste into a shell."""
        return axes_map_args(self.axes)

    def suggested_map_args(self) -> str:
        """The ``--map`` options of :attr:`suggested` (empty when none)."""
        return axes_map_args(self.suggested) if self.suggested else ""

    def hint(self) -> str:
        """What a refusal without axes says of the lines most like a STEP (:attr:`suggested`):
        which they are, what is missing, and the ``--map`` that checks them anyway with every
        DIR; empty when there is none."""
        if not self.suggested:
            return ""
        steps = [a.roles[0] for a in self.suggested]
        lines = ", ".join(f"{r.index}={r.channel!r} ({r.evidence.split(',')[0]})" for r in steps)
        layout = any(r.basis == "layout" for a in self.suggested for r in a.roles)
        words = (
            "; the DIR of each is the unchanging channel after it (layout only)" if layout else ""
        )
        return (
            f"the lines most like a STEP are no step train on their waveform: {lines}, and no "
            "line changes between their pulses as a DIR would; to check them anyway: "
            f"{self.suggested_map_args()}{words}"
        )

    def type_args(self) -> str:
        """``--type`` options for axes that are not step/dir (``--type 2``; with several axes
        ``--type a=2``, in the form the issue gives ``--drive``); empty when none."""
        multi = len(self.axes) > 1
        return " ".join(
            f"--type {a.name}={a.step_type}" if multi else f"--type {a.step_type}"
            for a in self.axes
            if a.step_type != 0
        )

    def as_dict(self) -> dict[str, Any]:
        """JSON form: ``axes`` [{name, kind, step_type, map, roles [{role, channel, index,
        evidence, basis}], notes}], ``shared``, ``unassigned``, ``ambiguous``, ``lines``
        [{channel, index, look}], ``candidates`` and ``map_args``."""
        return {
            "axes": [
                {
                    "name": a.name,
                    "kind": a.kind,
                    "step_type": a.step_type,
                    "map": a.mapping,
                    "invert": list(a.inverted),
                    "roles": [
                        {
                            "role": r.role,
                            "channel": r.channel,
                            "index": r.index,
                            "evidence": r.evidence,
                            "basis": r.basis,
                        }
                        for r in a.roles
                    ],
                    "notes": list(a.notes),
                }
                for a in self.axes
            ],
            "shared": [
                {
                    "role": s.role,
                    "channel": s.channel,
                    "index": s.index,
                    "axes": list(s.axes),
                    "evidence": s.evidence,
                }
                for s in self.shared
            ],
            "unassigned": [
                {"channel": u.channel, "index": u.index, "why": u.why} for u in self.unassigned
            ],
            "ambiguous": [
                {"question": c.question, "candidates": list(c.candidates)} for c in self.ambiguous
            ],
            "lines": [{"channel": k.channel, "index": k.index, "look": k.word} for k in self.looks],
            "candidates": list(self.candidates),
            "map_args": self.map_args() if self.axes else None,
            "suggested_map_args": self.suggested_map_args() or None,
        }

    def text(self) -> str:
        """Human-readable form, for ``wavecheck info``."""
        lines: list[str] = []
        for a in self.axes:
            kind = a.kind if a.kind != "phases" else f"phases, step type {a.step_type}"
            lines.append(f"axis {a.name} ({kind})")
            width = max(len(r.role) for r in a.roles)
            for r in a.roles:
                how = "" if r.basis == "waveform" else f" [by {r.basis}]"
                lines.append(f"  {r.role:<{width}}  {r.index}={r.channel!r}{how}: {r.evidence}")
            lines += [f"  note: {n}" for n in a.notes]
        for s in self.shared:
            lines.append(f"shared {s.role} {s.index}={s.channel!r} for axes {', '.join(s.axes)}")
        for u in self.unassigned:
            lines.append(f"unassigned {u.index}={u.channel!r}: {u.why}")
        for c in self.ambiguous:
            lines.append(f"ambiguous: {c.question}")
            lines += [f"  - {cand}" for cand in c.candidates]
        if self.axes:
            lines.append(
                f"map: {self.map_args()}" + (f" {self.type_args()}" if self.type_args() else "")
            )
        if not self.axes and not self.ambiguous:
            lines.append(f"no step signal found: the lines look like {self.summary()}")
            if self.suggested:
                lines.append(self.hint())
        return "\n".join(lines)
