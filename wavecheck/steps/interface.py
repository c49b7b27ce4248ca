"""Channel roles: which capture channel is the drive's STEP, DIR, UP, DOWN, phase-A … E, ENABLE.

``--map step=STEP,dir=3`` names channels as written in the file (or by index);
``--invert ROLE`` flips a role so that every level is the level at the drive's input.
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Mapping

import numpy as np

from wavecheck.capture.edges import Capture, Channel, EdgeArray
from wavecheck.errors import UsageError
from wavecheck.record import field, record
from wavecheck.roles.names import leaf as leaf_name

__all__ = [
    "ROLES",
    "RoleSignal",
    "StepInterface",
    "build_interface",
    "find_channel",
    "leaf_name",
    "mapped_channel_names",
    "parse_map",
    "role_name",
    "split_pairs",
]

ROLES: tuple[str, ...] = (
    "step",
    "dir",
    "up",
    "down",
    "phase-A",
    "phase-B",
    "phase-C",
    "phase-D",
    "phase-E",
    "enable",
)
_ROLE_BY_KEY = {r.lower().replace("_", "-"): r for r in ROLES}


def role_name(name: str) -> str:
    """The role ``name`` means (``STEP``, ``Phase_a``, ``a`` → ``step``, ``phase-A``, ``phase-A``)."""
    key = name.strip().lower().replace("_", "-")
    if key in _ROLE_BY_KEY:
        return _ROLE_BY_KEY[key]
    if key in ("a", "b", "c", "d", "e"):
        return f"phase-{key.upper()}"
    raise UsageError(f"unknown role {name!r} (roles: {', '.join(ROLES)})")


def split_pairs(item: str) -> list[str]:
    """``"x.step=5,x.dir=A,B"`` → pairs; a comma separates pairs only before ``role=``."""
    parts: list[str] = []
    for chunk in item.split(","):
        if parts and "=" not in chunk:
            parts[-1] += "," + chunk
        else:
            parts.append(chunk)
    return parts


def parse_map(items: Iterable[str], option: str = "--map") -> dict[str, str]:
    """Parse ``--map`` values (``"step=STEP (Y axis),dir=3"``, repeatable) into role → channel.

    A comma separates pairs only where it is followed by ``role=``, so channel names may
    contain commas and spaces.

    Raises:
        UsageError: not ``ROLE=CHANNEL``, an unknown role, a role given twice (in one value or
            across repeated options) or one channel written for two roles. A check covers one
            step interface for now, so a repeated role has no meaning yet (it would silently
            check another axis than the user meant).
    """
    mapping: dict[str, str] = {}
    written: dict[str, str] = {}  # role -> its pair as written
    for item in items:
        for part in split_pairs(item):
            if "=" not in part:
                raise UsageError(
                    f"{option} {part!r} is not ROLE=CHANNEL (e.g. {option} step=STEP,dir=3)"
                )
            role_text, channel = part.split("=", 1)
            if not channel:
                raise UsageError(f"{option} {part!r} names no channel (e.g. {option} step=STEP)")
            role = role_name(role_text)
            if role in mapping:
                raise UsageError(
                    f"{option}: role {role} is mapped twice ({written[role]} and {part.strip()}); "
                    "one axis takes one channel per role (several axes are named: "
                    f"{option} x.step=5,x.dir=6 {option} y.step=3,y.dir=4)"
                )
            for other, ch in mapping.items():
                if ch.strip() == channel.strip():
                    raise UsageError(
                        f"{option}: channel {channel.strip()!r} is mapped as both {other} and "
                        f"{role}; one channel can have one role"
                    )
            mapping[role] = channel
            written[role] = part.strip()
    return mapping


def _what(ref: str, role: str | None) -> str:
    return f"--map {role}={ref}" if role else f"channel {ref!r}"


def _ambiguous_name(capture: Capture, ref: str, hits: list[Channel], role: str | None) -> str:
    what = _what(ref, role)
    indices = [str(c.index) for c in hits]
    listed = ", ".join(indices[:-1]) + f" and {indices[-1]}"
    return (
        f"{capture.path}: {what} is ambiguous: indices {listed} are both {hits[0].name!r}; "
        f"map by index (e.g. --map {role or 'step'}={hits[0].index})"
    )


def _hierarchical(channels: list[Channel], ref: str) -> list[Channel]:
    """Channels whose dotted name ends with ``ref`` (``s2.step`` → ``tb.s2.step``): exact case
    first, else any case."""
    hits = [c for c in channels if c.name.strip().endswith("." + ref)]
    if not hits:
        low = "." + ref.lower()
        hits = [c for c in channels if c.name.strip().lower().endswith(low)]
    return hits


#: A bit of a vector: Verilog's ``stout[3]`` or VHDL's ``pins(2)``.
_BIT = re.compile(r"^(.+?)\s*(?:\[\s*(\d+)\s*\]|\(\s*(\d+)\s*\))$")


def find_channel(capture: Capture, ref: str | int, role: str | None = None) -> Channel:
    """The channel ``ref`` names: its exact name, else the one channel so named in any case
    (``STEP`` for ``step``), else its index (``"3"``), else another name the file gives it, else
    the unique channel whose hierarchical name ends with ``ref``
    (``s2.step`` for ``tb.s2.step``; any case if no exact-case one), else bit ``i`` of a
    vector for ``name[i]`` or VHDL's ``name(i)`` (:meth:`Capture.bit`: ``stout[3]``,
    ``tb.dut.stout[3]``, ``pins(2)``).

    Raises:
        UsageError: no such channel (the channels are listed); a name two channels share
            ("ambiguous: indices 2 and 5 are both 'STEP'; map by index"); a partial name that
            several channels end with ("ambiguous: candidates …").
    """
    if isinstance(ref, int):
        return capture.channel(ref)
    hits = [c for c in capture.channels if c.name == ref]
    if not hits:
        hits = [c for c in capture.channels if c.name.strip() == ref.strip()]
    if not hits:  # any case, when one channel only is so named (step=STEP on a channel step)
        hits = [c for c in capture.channels if c.name.strip().casefold() == ref.strip().casefold()]
        if len(hits) > 1:
            names = ", ".join(f"{c.index}={c.name!r}" for c in hits)
            raise UsageError(
                f"{capture.path}: {_what(ref, role)} is ambiguous: it names {names} in other "
                "cases; map by the exact name or by index"
            )
    if len(hits) > 1:
        raise UsageError(_ambiguous_name(capture, ref, hits, role))
    if hits:
        return hits[0]
    stripped = ref.strip()
    known = stripped.isdigit() or ref in capture.aliases or stripped in capture.aliases
    if stripped and not known and ref not in capture.skipped and stripped not in capture.skipped:
        cands = _hierarchical(capture.channels, stripped)
        if not cands:  # another name of a channel (a port of a submodule) may end with it
            tails = {t for a, t in capture.aliases.items() if a.endswith("." + stripped)}
            cands = [c for c in capture.channels if c.name in tails]
        if len(cands) == 1:
            return cands[0]
        if len(cands) > 1:
            what = _what(ref, role)
            names = ", ".join(f"{c.index}={c.name!r}" for c in cands[:8])
            more = f" and {len(cands) - 8} more" if len(cands) > 8 else ""
            raise UsageError(
                f"{capture.path}: {what} is ambiguous: candidates {names}{more}; "
                "map by the full name or by index"
            )
    bit = _BIT.match(stripped)
    if bit and capture.vectors:
        return capture.bit(bit.group(1), int(bit.group(2) or bit.group(3)))
    if not known and ref not in capture.skipped and stripped not in capture.skipped:
        raise UsageError(_not_found(capture, ref, role))
    return capture.channel(ref)


def _not_found(capture: Capture, ref: str, role: str | None) -> str:
    """No channel is ``ref``: the channels, and the one most like ``role`` to map instead."""
    import shlex

    from wavecheck.roles import best_channel

    available = ", ".join(f"{c.index}={c.name!r}" for c in capture.channels) or "none"
    best = best_channel(capture, role or "step") if capture.channels else None
    pair = f"{role or 'step'}={best}"
    hint = f", e.g. --map {shlex.quote(pair)}" if best is not None else ""
    return f"{capture.path}: no channel {ref!r} (channels: {available}; map by name or index{hint})"


def mapped_channel_names(capture: Capture, mapping: Mapping[str, str]) -> set[str]:
    """The names of the channels ``mapping`` (role → channel name or index) resolves to."""
    return {find_channel(capture, ref, role).name for role, ref in mapping.items()}


def _no_stretches() -> tuple[EdgeArray, EdgeArray]:
    return np.zeros(0, np.int64), np.zeros(0, np.int64)


@record
class RoleSignal:
    """One role's signal at the drive's input (after any inversion)."""

    role: str
    channel: str
    initial: int
    edges: EdgeArray
    known_from: int
    inverted: bool
    unknown: tuple[EdgeArray, EdgeArray] = field(default_factory=_no_stretches)
    """Closed tick ranges where the level is not known (:meth:`Channel.unknown_stretches`)."""
    index: int = -1
    """The channel's index in the capture (−1: not from a capture)."""


@record
class StepInterface:
    """The mapped signals of one step interface, on the capture's time base."""

    capture: Capture
    signals: dict[str, RoleSignal]

    def get(self, role: str) -> RoleSignal | None:
        """The signal of ``role``, or None when it is not mapped."""
        return self.signals.get(role)

    def unknown_until(self, roles: Iterable[str]) -> int | None:
        """The latest :attr:`RoleSignal.known_from` among the mapped ``roles`` that is later than
        the capture's start, or None when each was known from the start.

        Up to and including that tick an edge of one of them may be hidden (the x → level change
        itself may be one), so an interval or state change involving them must start after it.
        """
        start = self.capture.start
        late = [
            s.known_from
            for s in (self.signals.get(r) for r in roles)
            if s is not None and s.known_from > start
        ]
        return max(late) if late else None

    def require(self, role: str) -> RoleSignal:
        """The signal of ``role``; a clear error when it is not mapped."""
        sig = self.signals.get(role)
        if sig is None:
            import shlex

            from wavecheck.roles import best_channel

            best = best_channel(self.capture, role) if self.capture.channels else None
            pair = shlex.quote(f"{role}={best if best is not None else 'CHANNEL'}")
            raise UsageError(
                f"{self.capture.path}: role {role!r} is not mapped (add --map {pair}; channels: "
                f"{', '.join(repr(c.name) for c in self.capture.channels)})"
            )
        return sig


def build_interface(
    capture: Capture, mapping: Mapping[str, str], invert: Iterable[str] = ()
) -> StepInterface:
    """Resolve ``mapping`` (role → channel name or index) against ``capture``.

    Raises:
        UsageError: unknown role or channel, an ambiguous channel name (see
            :func:`find_channel`), one channel mapped to two roles, an inverted role that is
            not mapped. A channel that goes ``x``/``z`` is mapped: its unknown stretches
            (:attr:`RoleSignal.unknown`) are left out of the checks.
    """
    inverted = {role_name(r) for r in invert}
    for role in inverted:
        if role not in mapping:
            raise UsageError(
                f"--invert {role}: role {role!r} is not mapped (add --map {role}=CHANNEL)"
            )
    signals: dict[str, RoleSignal] = {}
    roles_of: dict[int, str] = {}  # channel index -> the role it has
    for role, ref in mapping.items():
        ch = find_channel(capture, ref, role)
        if ch.index in roles_of:
            raise UsageError(
                f"{capture.path}: channel {ch.index} {ch.name!r} is mapped as both "
                f"{roles_of[ch.index]} and {role}; one channel can have one role"
            )
        roles_of[ch.index] = role
        flip = role in inverted
        signals[role] = RoleSignal(
            role=role,
            channel=ch.name,
            initial=ch.initial ^ int(flip),
            edges=ch.edges,
            known_from=ch.known_from,
            inverted=flip,
            unknown=ch.unknown_stretches(capture.start),
            index=ch.index,
        )
    return StepInterface(capture=capture, signals=signals)
