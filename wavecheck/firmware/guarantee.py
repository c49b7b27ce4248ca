"""What a step generator guarantees on the wire, per axis, and where each figure came from.

Every firmware reader (:mod:`wavecheck.firmware.grbl`, ``klipper``, ``marlin``, ``rrf``,
``smoothie``, ``hm2``, ``linuxcnc``) turns a configuration file into one
:class:`FirmwareConfig`: a :class:`GeneratorGuarantee` per axis, each figure a
:class:`Guaranteed` lower bound with the setting, the file and line, and the unit it was written
in. Times are exact ns, rates exact Hz (:class:`~fractions.Fraction`). A figure the configuration
cannot prove is ``None`` with a note saying why ("measure it"), never a guess; one the firmware
aims at but may miss carries the band it may fall short by (:attr:`Guaranteed.short_by`).

Levels are the generator's *output pin*, after the firmware's own pin inversion: ``pulse`` is the
level the firmware drives for a step (high unless inverted), ``idle`` the time between pulses.
DIR setup and hold count from the pulse's *leading* edge (the edge the firmware writes as its
step); :attr:`GeneratorGuarantee.dir_hold_trailing`, when known, counts from its trailing edge.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from fractions import Fraction
from functools import cached_property
from typing import Literal

from wavecheck.drives.datasheet import ActiveEdge
from wavecheck.errors import ConfigError
from wavecheck.firmware import FIRMWARES
from wavecheck.units import format_ns, format_rate

__all__ = [
    "FIRMWARES",
    "FixRole",
    "Fixer",
    "FirmwareConfig",
    "GStatus",
    "MAX_AXES",
    "GeneratorGuarantee",
    "Guaranteed",
    "Role",
    "MEASURE_HOW",
    "at_least",
    "at_most",
    "ceil_to",
    "not_enforced",
    "uncertain",
    "unknown",
]


#: More step generators than any machine has: a file naming more is refused (bounded time).
MAX_AXES = 256

Role = Literal["pulse", "idle", "setup", "hold", "max_rate"]
"""A generator figure: pulse width, time between pulses, DIR setup/hold, max step rate."""

GStatus = Literal["set", "default", "derived", "uncertain", "not_enforced", "unknown"]
"""``set`` = written in the file; ``default`` = the firmware's default (the file says nothing);
``derived`` = computed from settings (rounding, rate → low time); ``uncertain`` = the firmware
aims at it but does not keep it exactly (timer rounding, a counter's phase, a clock not known):
:attr:`Guaranteed.short_by` says by how much the wire figure may miss it, and why;
``not_enforced`` = no code of the firmware keeps it (the value, if any, is what the setting asks
for: a rule it passes is indeterminate, one it fails still fails); ``unknown`` = no bound can be
read from the configuration."""

#: How to measure a figure the configuration cannot decide.
MEASURE_HOW = "capture STEP and DIR, then `wavecheck check --firmware FILE`"


@dataclass(frozen=True)
class Guaranteed:
    """One lower bound (upper bound for ``max_rate``) and where it comes from.

    The band: an ``uncertain`` figure (or a ``default`` one the firmware times the same way) is
    what the firmware aims at; the wire figure may fall up
    to :attr:`short_by` below :attr:`value` (for ``max_rate``: the real rate may exceed it by
    up to that many Hz, the direction that hurts), for the reason :attr:`short_why` gives with
    the firmware line that makes it so. The firmware may also overshoot its aim (interrupts
    lengthen a busy-wait), but nothing bounds that, so no verdict counts on it: a rule passes
    only if ``value - short_by`` meets the limit, fails only if ``value`` itself misses it, and
    is indeterminate in between (:func:`wavecheck.firmware.evaluate.evaluate_pair`).
    ``short_by`` None: no bound could be derived from the source, so the figure is never a PASS.
    """

    value: Fraction | None
    """ns (Hz for ``max_rate``); None when the configuration cannot prove any bound."""
    setting: str
    """The setting's own name (``$0``, ``MINIMUM_STEPPER_PULSE_NS``, ``step_pulse_duration``)."""
    where: str
    """``file:line``, or ``"firmware default"``."""
    unit: str = ""
    """The unit the setting is written in (``us``, ``ns``, ``s``, ``Hz``, ``mm/min`` …)."""
    status: GStatus = "set"
    note: str = ""
    disputed: Fraction | None = None
    """Where the sources disagree (hm2: the man page and the VHDL) or the figure depends on
    something no configuration states (Marlin: whether an axis reaches multi-stepping), the
    bound under the other reading; :attr:`note` names both, and a rule whose verdict differs
    under it is indeterminate."""
    short_by: Fraction | None = Fraction(0)
    """How far the wire figure may fall below :attr:`value` (ns; Hz above it for ``max_rate``);
    0 = kept exactly, None = no bound derived (never a PASS). See the class doc."""
    short_why: str = ""
    """Why it may fall short, with the firmware's file:line (``½ tick of the 2 MHz pulse timer,
    …``): the note of a verdict the band decides."""

    def __post_init__(self) -> None:
        if self.short_by is not None and self.short_by < 0:
            raise ValueError(f"{self.setting}: short_by {self.short_by} < 0")
        if self.status == "uncertain" and not self.short_why:
            raise ValueError(f"{self.setting}: an uncertain figure must say why (short_why)")

    @property
    def known(self) -> bool:
        """True when a bound is known."""
        return self.value is not None

    @property
    def banded(self) -> bool:
        """The wire figure may fall short of :attr:`value` (a non-zero or unbounded band)."""
        return self.short_by is None or self.short_by > 0

    def band_text(self, rate: bool = False) -> str:
        """``the firmware may make it up to 750 ns short (why)``, or ``""`` for an exact figure
        (``rate``: the band is Hz over the value)."""
        if not self.banded:
            return ""
        if self.short_by is None:
            return f"the firmware may miss it by an amount no source bounds ({self.short_why})"
        amount = (
            f"{format_rate(self.short_by)} over" if rate else f"{format_ns(self.short_by)} short"
        )
        return f"the firmware may make it up to {amount} ({self.short_why})"


def unknown(setting: str, note: str, where: str = "") -> Guaranteed:
    """A figure the configuration cannot prove (``value`` None, status ``unknown``)."""
    return Guaranteed(None, setting, where, "", "unknown", note)


def not_enforced(
    setting: str, why: str, where: str = "", value: Fraction | None = None, unit: str = ""
) -> Guaranteed:
    """A figure no code of the firmware keeps (``why`` names the code, file:line): never a
    PASS. ``value``: what the setting asks for, when it has one (a FAIL under it stands)."""
    note = f"not enforced by the firmware: measure it ({MEASURE_HOW}); {why}"
    return Guaranteed(value, setting, where, unit, "not_enforced", note)


def uncertain(
    value: Fraction | None,
    setting: str,
    where: str,
    unit: str,
    short_by: Fraction | None,
    why: str,
    note: str = "",
) -> Guaranteed:
    """A figure the firmware aims at but may miss by up to ``short_by`` (None: unbounded), for
    the reason ``why`` (with the firmware's file:line)."""
    return Guaranteed(value, setting, where, unit, "uncertain", note, short_by=short_by,
                      short_why=why)  # fmt: skip


@dataclass(frozen=True)
class GeneratorGuarantee:
    """What one axis's step generator guarantees at its output pins.

    Attributes:
        axis: the firmware's axis or stepper name (``X``, ``stepper_x``, ``joint 0``).
        pulse: the minimum pulse width (ns).
        idle: the minimum time between pulses (ns).
        dir_setup: DIR change → the pulse's leading edge (ns).
        dir_hold: the pulse's leading edge → a DIR change (ns).
        max_rate: the highest step rate this axis is configured to reach (Hz).
        pulse_level: 1 when a pulse is high at the pin, 0 when low (firmware inversion applied).
        both_edges: every STEP edge is a step (TMC ``dedge``: Klipper, Marlin ``EDGE_STEPPING``).
        dir_hold_trailing: DIR hold counted from the pulse's trailing edge, when known.
        dir_setup_trailing: DIR change → the pulse's trailing edge, when DIR may change during
            the pulse (hm2 with dirhold < steplen): less than ``dir_setup`` + ``pulse``.
        dir_inverted: the firmware inverts this axis's DIR pin (information only).
        info: further settings read (steps/unit, max speed …), name → text with source.
        notes: what the user should know about this axis.
        aliases: other names the axis is known by (``x`` for Klipper's ``stepper_x``, the
            joint's axis letter for a LinuxCNC stepgen): ``check --firmware`` pairs a capture
            axis with the firmware axis of the same name or alias.
    """

    axis: str
    pulse: Guaranteed
    idle: Guaranteed
    dir_setup: Guaranteed
    dir_hold: Guaranteed
    max_rate: Guaranteed
    pulse_level: int = 1
    both_edges: bool = False
    dir_hold_trailing: Guaranteed | None = None
    dir_setup_trailing: Guaranteed | None = None
    dir_inverted: bool = False
    info: Mapping[str, str] = field(default_factory=dict)
    notes: tuple[str, ...] = ()
    aliases: tuple[str, ...] = ()

    @property
    def names(self) -> tuple[str, ...]:
        """The axis name and its aliases."""
        return (self.axis, *self.aliases)

    @property
    def leading_edge(self) -> ActiveEdge:
        """The edge that starts a pulse: ``rising`` for high pulses, ``falling`` for low ones."""
        return "rising" if self.pulse_level else "falling"

    @property
    def active_edge(self) -> ActiveEdge:
        """The edge(s) the generator means as a step: ``both`` in both-edge mode."""
        return "both" if self.both_edges else self.leading_edge

    @property
    def step_high(self) -> Guaranteed:
        """The minimum high time (the pulse when pulses are high, else the idle time)."""
        return self.pulse if self.pulse_level else self.idle

    @property
    def step_low(self) -> Guaranteed:
        """The minimum low time."""
        return self.idle if self.pulse_level else self.pulse

    def figure(self, role: Role) -> Guaranteed:
        """The figure of ``role`` (``setup``: the DIR delay before a pulse, ``hold``: DIR held
        after it, from the leading edge)."""
        figure: Guaranteed = getattr(self, _FIELDS[role])
        return figure


_FIELDS: dict[str, str] = {
    "pulse": "pulse", "idle": "idle", "setup": "dir_setup", "hold": "dir_hold",
    "max_rate": "max_rate",
}  # fmt: skip

FixRole = Literal["pulse", "idle", "setup", "hold", "trailing_hold", "trailing_setup", "max_rate"]
"""What a fix must reach: a :data:`Role`, or ``trailing_hold`` / ``trailing_setup`` (DIR hold
after, setup before the pulse's trailing edge, the drive's active edge)."""

Fixer = Callable[[GeneratorGuarantee, FixRole, Fraction], str]
"""(axis, role, value needed: ns, or Hz for ``max_rate``) → the setting to change, in the
firmware's own words, the value in backticks as it is written in the file (``set `$0=5```):
applied as written, it makes that rule pass."""


def _no_fix(axis: GeneratorGuarantee, role: FixRole, need: Fraction) -> str:
    return ""


def _digits(value: Fraction, up: bool, digits: int = 6) -> str:
    if value <= 0:
        return "0"
    scale = Fraction(10) ** (digits - len(str(int(value))) if value >= 1 else digits)
    scaled = value * scale
    whole = (
        -(-scaled.numerator // scaled.denominator) if up else scaled.numerator // scaled.denominator
    )
    text = str(float(Fraction(whole) / scale))  # a 6-digit decimal prints exactly
    return text[:-2] if text.endswith(".0") else text


def at_least(value: Fraction, digits: int = 6) -> str:
    """``value`` as decimal text rounded *up* to ``digits`` significant digits (a bound a fix
    must not fall short of)."""
    return _digits(value, True, digits)


def at_most(value: Fraction, digits: int = 6) -> str:
    """``value`` as decimal text rounded *down* to ``digits`` significant digits."""
    return _digits(value, False, digits)


@dataclass(frozen=True)
class FirmwareConfig:
    """One configuration file read: its firmware and one guarantee per axis.

    Attributes:
        firmware: one of :data:`FIRMWARES`.
        path: the file read (the main one).
        axes: one guarantee per axis, in the file's order.
        files: every file read (Marlin's pair, LinuxCNC's INI and HAL files).
        unsupported: settings the file sets that wavecheck does not model, one line each with
            its place (named, not guessed).
        notes: global notes (scope of settings, rounding, defaults used).
        fixer: how to say which setting to change (see :data:`Fixer`).
        unchecked_axes: why → the axes the file names but gives nothing to check (no figure
            bounds their rate or timing); the verdict line names them, so a PASS does not
            read as the whole machine's.
    """

    firmware: str
    path: str
    axes: tuple[GeneratorGuarantee, ...]
    files: tuple[str, ...] = ()
    unsupported: tuple[str, ...] = ()
    notes: tuple[str, ...] = ()
    fixer: Fixer = _no_fix
    unchecked_axes: tuple[tuple[str, tuple[str, ...]], ...] = ()

    def __post_init__(self) -> None:
        if len(self.axes) > MAX_AXES:
            raise ConfigError(
                f"{self.path}: {len(self.axes)} step generators, more than any machine has "
                f"(at most {MAX_AXES} are read)"
            )

    @cached_property
    def _by_name(self) -> dict[str, GeneratorGuarantee]:
        by_alias = {n.lower(): a for a in reversed(self.axes) for n in a.aliases}
        return by_alias | {a.axis.lower(): a for a in reversed(self.axes)}

    def axis(self, name: str) -> GeneratorGuarantee:
        """The axis called ``name`` or known by that alias (case-insensitive; KeyError lists the
        axes)."""
        found = self._by_name.get(name.lower())
        if found is None:
            raise KeyError(f"no axis {name!r} in {self.path} (axes: {', '.join(self.axis_names)})")
        return found

    def find(self, name: str) -> GeneratorGuarantee | None:
        """The axis called ``name`` or known by that alias, None if there is none."""
        return self._by_name.get(name.lower())

    @property
    def axis_names(self) -> tuple[str, ...]:
        """The axis names, in order."""
        return tuple(a.axis for a in self.axes)

    def fix(self, axis: GeneratorGuarantee, role: FixRole, need: Fraction) -> str:
        """The setting to change so that ``role`` reaches ``need``."""
        return self.fixer(axis, role, need)


def ceil_to(value: Fraction, step: Fraction) -> Fraction:
    """``value`` rounded up to a whole multiple of ``step``."""
    return -(-value // step) * step
