"""Channel roles: which capture channel is the drive's STEP, DIR, UP, DOWN, phase-A … E, ENABLE.

``--map step=STEP,dir=3`` names channels as written in the file (or by index);
``--invert ROLE`` flips a role so that every level is the level at the drive's input.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass

from wavecheck.capture.model import Capture, EdgeArray
from wavecheck.errors import UsageError

__all__ = ["ROLES", "RoleSignal", "StepInterface", "build_interface", "parse_map"]

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


def _role(name: str) -> str:
    key = name.strip().lower().replace("_", "-")
    if key in _ROLE_BY_KEY:
        return _ROLE_BY_KEY[key]
    if key in ("a", "b", "c", "d", "e"):
        return f"phase-{key.upper()}"
    raise UsageError(f"unknown role {name!r} (roles: {', '.join(ROLES)})")


def parse_map(items: Iterable[str]) -> dict[str, str]:
    """Parse ``--map`` values (``"step=STEP (Y axis),dir=3"``, repeatable) into role → channel.

    A comma separates pairs only where it is followed by ``role=``, so channel names may
    contain commas and spaces.
    """
    mapping: dict[str, str] = {}
    for item in items:
        parts: list[str] = []
        for chunk in item.split(","):
            if parts and "=" not in chunk:
                parts[-1] += "," + chunk
            else:
                parts.append(chunk)
        for part in parts:
            if "=" not in part:
                raise UsageError(f"--map {part!r} is not ROLE=CHANNEL (e.g. --map step=STEP,dir=3)")
            role, channel = part.split("=", 1)
            if not channel:
                raise UsageError(f"--map {part!r} names no channel (e.g. --map step=STEP)")
            mapping[_role(role)] = channel
    return mapping


@dataclass
class RoleSignal:
    """One role's signal at the drive's input (after any inversion)."""

    role: str
    channel: str
    initial: int
    edges: EdgeArray
    known_from: int
    inverted: bool


@dataclass
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
            raise UsageError(
                f"{self.capture.path}: role {role!r} is not mapped "
                f"(add --map {role}=CHANNEL; channels: "
                f"{', '.join(repr(c.name) for c in self.capture.channels)})"
            )
        return sig


def build_interface(
    capture: Capture, mapping: Mapping[str, str], invert: Iterable[str] = ()
) -> StepInterface:
    """Resolve ``mapping`` (role → channel name or index) against ``capture``.

    Raises:
        UsageError: unknown role or channel, an inverted role that is not mapped, or a mapped
            channel that goes ``x``/``z`` in the middle of the capture.
    """
    inverted = {_role(r) for r in invert}
    for role in inverted:
        if role not in mapping:
            raise UsageError(f"--invert {role}: role {role!r} is not mapped (add --map {role}=CHANNEL)")
    signals: dict[str, RoleSignal] = {}
    for role, ref in mapping.items():
        ch = capture.channel(ref)
        if len(ch.xz_times):
            t = capture.timebase.seconds(int(ch.xz_times[0]))
            raise UsageError(
                f"{capture.path}: channel {ch.name!r} (mapped as {role}) is x/z at "
                f"{float(t):.9g} s (and {len(ch.xz_times) - 1} more times); an unknown level "
                "cannot be checked"
            )
        flip = role in inverted
        signals[role] = RoleSignal(
            role=role,
            channel=ch.name,
            initial=ch.initial ^ int(flip),
            edges=ch.edges,
            known_from=ch.known_from,
            inverted=flip,
        )
    return StepInterface(capture=capture, signals=signals)
