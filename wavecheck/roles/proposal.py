"""The proposal: axes with their role → channel mapping and the evidence, shared lines, leftovers
and conflicts; and the ``--map`` text that reproduces it.

``--map`` syntax (issue 13): one axis → ``--map step=5,dir=6``; several →
``--map x.step=5,x.dir=6 --map y.step=3,y.dir=4``. A shared line (one ENABLE for several axes)
appears in each axis it serves. A channel is written by name when its name finds it and nothing
else (``Capture.channel``), else by index; each ``--map`` value is shell-quoted when needed.
"""

from __future__ import annotations

import shlex
from dataclasses import dataclass, field
from typing import Any, Literal

from wavecheck.linuxcnc.steptypes import StepKind

__all__ = [
    "AxisProposal",
    "Basis",
    "Conflict",
    "Proposal",
    "RoleChoice",
    "SharedLine",
    "Unassigned",
]

Basis = Literal["waveform", "name", "layout"]
"""What decided a role: the waveform; the name (the waveform could not, e.g. a DIR that never
changes but is named ``Y_DIR``); or the layout (an unchanging channel right after a STEP, taken as
its DIR: no waveform evidence at all — check the wiring)."""


@dataclass(frozen=True)
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


@dataclass(frozen=True)
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


@dataclass(frozen=True)
class SharedLine:
    """A line that serves several axes (one ENABLE for all of them)."""

    role: str
    channel: str
    index: int
    axes: tuple[str, ...]
    evidence: str


@dataclass(frozen=True)
class Unassigned:
    """A channel given no role, and why."""

    channel: str
    index: int
    why: str


@dataclass(frozen=True)
class Conflict:
    """Something the waveform cannot decide: a question and the candidate answers."""

    question: str
    candidates: tuple[str, ...]


@dataclass(frozen=True)
class Proposal:
    """Roles proposed for a capture's channels (see :func:`wavecheck.roles.propose`).

    A channel appears in exactly one of: an axis role (possibly a shared line too), ``unassigned``,
    or a conflict's candidates (then it may also be left out of the axes).
    """

    axes: tuple[AxisProposal, ...]
    shared: tuple[SharedLine, ...] = ()
    unassigned: tuple[Unassigned, ...] = ()
    ambiguous: tuple[Conflict, ...] = field(default_factory=tuple)

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

    def map_args(self) -> str:
        """The ``--map`` options that give this mapping, ready to paste into a shell."""
        groups: list[tuple[str | None, AxisProposal]]
        if len(self.axes) == 1:
            groups = [(None, self.axes[0])]
        else:
            groups = [(a.name, a) for a in self.axes]
        out: list[str] = []
        for prefix, axis in groups:
            pre = f"{prefix}." if prefix is not None else ""
            value = ",".join(f"{pre}{r.role}={r.ref}" for r in axis.roles)
            out.append(f"--map {shlex.quote(value)}")
        return " ".join(out)

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
        evidence, basis}], notes}], ``shared``, ``unassigned``, ``ambiguous``, ``map_args``."""
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
            "map_args": self.map_args() if self.axes else None,
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
        if not lines:
            lines.append("no step signal found")
        return "\n".join(lines)
