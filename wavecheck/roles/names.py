"""What a channel's name says: a role keyword and an axis, when it has them.

Names only help: they break ties between waveform candidates and name the axes; the waveform
decides. Matching is case-insensitive on the name's words (split at anything not a letter or
digit, and between letters and digits):

- STEP: ``step``, ``stp``, ``pul``, ``pulse`` (not ``clk``: in a capture that is a clock far
  more often than a drive's CLK input);
  DIR: ``dir``, ``direction``; ``cw``/``ccw`` fit a DIR or, on pulse lines, UP/DOWN;
  UP/DOWN: ``up``, ``down``, ``dn``; ENABLE: ``en``, ``ena``, ``enable``, ``enbl``;
  phases: ``phase``/``ph`` followed by a letter A..E (``phase-A``, ``PHB``).
- Another function (``LED``, ``RST``, ``IRQ``, ``CS``, ``nWait``, ``DAV``, ``HALL``, ``TACH``;
  :data:`_OTHER`), in the last dotted part of a name without a role word: never a STEP on its
  waveform alone.
- The axis is a single letter X Y Z A B C U V W, or a number (LinuxCNC's ``stepgen.2.step`` →
  axis ``"2"``), written apart from the role word or glued to it (``X_STEP``, ``xstep``,
  ``STEP (Y axis)``, ``dirz``). A name gives an axis only together with a role word, so ``D3``,
  ``A0`` or ``ch3`` give neither.
"""

from __future__ import annotations

import re

from wavecheck.record import record

__all__ = ["NAMED_KINDS", "NameHint", "axes_by_scope", "leaf", "name_hint", "named_kind"]

_KEYWORDS: dict[str, frozenset[str]] = {
    **dict.fromkeys(("step", "stp", "pul", "pulse"), frozenset({"step"})),
    **dict.fromkeys(("dir", "direction"), frozenset({"dir"})),
    "cw": frozenset({"dir", "up"}),
    "ccw": frozenset({"dir", "down"}),
    "up": frozenset({"up"}),
    **dict.fromkeys(("down", "dn"), frozenset({"down"})),
    **dict.fromkeys(("en", "ena", "enable", "enbl"), frozenset({"enable"})),
}
#: Words that name another function (a reset, an interrupt, a bus or handshake line, an LED, a
#: sensor): a line so named is never taken as a STEP on its waveform (``clk`` is not here: a
#: drive's STEP input is called CLK too).
_OTHER = frozenset(
    "led rst reset nrst irq int intr cs ss ncs sck sclk mosi miso sda scl tx rx txd rxd wait "
    "nwait strobe str ack nack busy dav nrfd ndac eoi atn ifc srq ren sync pwm hall tach fg "
    "latch load".split()
)
_AXES = "xyzabcuvw"
_NOISE = {"axis", "stepgen", "joint", "motor", "out", "pin"}


@record(frozen=True)
class NameHint:
    """Roles a name fits (empty when it names none) and the axis it names (or None)."""

    roles: frozenset[str]
    axis: str | None
    other: bool = False
    """The name names no role but another function (``LED``, ``RST``, ``IRQ``, ``nWait``)."""

    def fits(self, role: str) -> bool:
        """True when the name names ``role``."""
        return role in self.roles

    @property
    def neutral(self) -> bool:
        """True when the name names no role and no other function."""
        return not self.roles and not self.other


def _words(name: str) -> list[str]:
    out: list[str] = []
    for word in re.split(r"[^0-9a-z]+", name.lower()):
        out += [w for w in re.findall(r"[a-z]+|[0-9]+", word) if w]
    return out


def name_hint(name: str) -> NameHint:
    """The roles and axis ``name`` gives (see the module docstring)."""
    words = _words(name)
    roles: set[str] = set()
    axes: list[str] = []
    i = 0
    while i < len(words):
        w = words[i]
        if w in ("phase", "ph") and i + 1 < len(words) and words[i + 1] in "abcde":
            roles.add(f"phase-{words[i + 1].upper()}")
            i += 2
            continue
        if len(w) == 3 and w.startswith("ph") and w[2] in "abcde":
            roles.add(f"phase-{w[2].upper()}")
        elif w in _KEYWORDS:
            roles |= _KEYWORDS[w]
        elif len(w) == 1 and w in _AXES or w.isdigit():
            axes.append(w)
        elif w not in _NOISE:
            for kw, fit in _KEYWORDS.items():  # xstep, stepx, ydir
                if len(kw) >= 2 and len(w) == len(kw) + 1 and kw in (w[1:], w[:-1]):
                    letter = w[0] if w[1:] == kw else w[-1]
                    if letter in _AXES:
                        roles |= fit
                        axes.append(letter)
                        break
        i += 1
    axis = axes[0] if roles and len(set(axes)) == 1 else None
    leaf_words = words if "." not in name else _words(name.rsplit(".", 1)[-1])
    other = not roles and any(w in _OTHER for w in leaf_words)
    return NameHint(frozenset(roles), axis, other)


def leaf(name: str) -> str:
    """The last dotted part of a channel name, stripped, lower case, ``_`` as ``-``
    (``"stepgen.0.phase_A"`` → ``"phase-a"``): what a channel named after its role is called."""
    return name.strip().rsplit(".", 1)[-1].strip().lower().replace("_", "-")


#: The roles of each kind of axis that a channel named after its role takes without ``--map``
#: (``check`` maps them by name, :func:`wavecheck.engine.planning.auto_map`): kind → (step type, roles).
#: A capture is named after its roles when a channel is called ``step``, ``up`` or ``phase-A``.
NAMED_KINDS: dict[str, tuple[int, tuple[str, ...]]] = {
    "step": (0, ("step", "dir", "enable")),
    "up": (1, ("up", "down", "enable")),
    "phase-a": (2, ("phase-A", "phase-B", "phase-C", "phase-D", "phase-E", "enable")),
}


def named_kind(names: list[str]) -> str | None:
    """``"step"``, ``"up"`` or ``"phase-a"`` when one of ``names`` is called after that role (the
    first in this order), else None: then ``check`` maps the channels by their names."""
    leaves = {leaf(n) for n in names}
    return next((k for k in NAMED_KINDS if k in leaves), None)


def axes_by_scope(names: list[str]) -> list[tuple[str, dict[str, str]]] | None:
    """Axes told by the scopes of hierarchical names, when several channels are named after the
    same pulse role (``top.axis_x.step``, ``top.axis_y.step``): one axis per scope holding one,
    named after the scope (its axis letter, ``axis_x`` → ``x``, else its last part), with the
    roles its channels are named after. None when the names do not settle it that way (one such
    channel, two in one scope, no scope, or two scopes that would give one name)."""
    kind = named_kind(names)
    if kind is None:
        return None
    pulse = [n for n in names if leaf(n) == kind]
    if len(pulse) < 2 or any("." not in n for n in pulse):
        return None
    scopes = [n.strip().rsplit(".", 1)[0] for n in pulse]
    if len(set(scopes)) != len(scopes):
        return None
    roles = NAMED_KINDS[kind][1]
    axes: list[tuple[str, dict[str, str]]] = []
    for scope in scopes:
        last = scope.rsplit(".", 1)[-1]
        words = [w for w in _words(last) if w not in _NOISE]
        hint = name_hint(last + ".step").axis
        name = hint if hint is not None and words == [hint] else last.strip().lower()
        mapping = {
            role: n
            for role in roles
            for n in names
            if "." in n and n.strip().rsplit(".", 1)[0] == scope and leaf(n) == role.lower()
        }
        axes.append((name, mapping))
    if len({a for a, _ in axes}) != len(axes):
        return None
    return axes
