"""Several axes in one run: the ``AXIS.ROLE=CH`` mapping syntax and per-axis options.

``--map x.step=5,x.dir=6 --map y.step=3,y.dir=4`` maps two axes; a role written without an axis
in such a run (``--map enable=EN``) is shared by every axis (one ENABLE line for the machine). The
single-axis form ``--map step=5,dir=6`` keeps its meaning. Per-axis options take ``AXIS=VALUE``
(``--drive x=gecko-g202 --drive y=leadshine-dm542``, ``--type y=1``, ``--dir-forward x=high``)
or a bare value for every axis; ``--invert`` takes ``AXIS.ROLE`` or a bare role (every axis).
Axis names are letters, digits, ``_`` and ``-`` (``x``, ``2``, ``left-z``).
"""

from __future__ import annotations

import re
from collections.abc import Callable, Iterable, Mapping, Sequence

from wavecheck.errors import UsageError
from wavecheck.record import field, record
from wavecheck.steps.interface import parse_map, role_name, split_pairs

__all__ = [
    "AxisMap",
    "axes_from_tables",
    "check_axis_names",
    "parse_axes",
    "per_axis",
    "split_invert",
    "split_per_axis",
]

_AXIS = re.compile(r"^[A-Za-z0-9_-]+$")
#: Roles one line may serve for several axes.
SHAREABLE = frozenset({"enable"})


@record(frozen=True)
class AxisMap:
    """One axis: its name (None for the unnamed single axis) and role → channel as written."""

    name: str | None
    roles: dict[str, str] = field(default_factory=dict)
    step_type: int | None = None
    """The step type found with the roles (inferred mappings), None: the options' or drive's."""
    invert: tuple[str, ...] = ()
    """Roles found inverted with the roles (an active-low ENABLE of an inferred mapping)."""


def parse_axes(items: Iterable[str], option: str = "--map") -> list[AxisMap]:
    """Parse ``--map`` values into axes, in the order their names first appear.

    Without any ``AXIS.`` prefix this is one unnamed axis (:func:`wavecheck.steps.interface.parse_map`'s
    rules: a role once, a channel in one role). With prefixes, every prefixed role belongs to its
    axis and every unprefixed one is shared by all axes (only ENABLE may be shared).

    Raises:
        UsageError: a malformed pair or axis name, a role twice in one axis, one channel in two
            roles of an axis or in two axes (other than a shared ENABLE).
    """
    items = list(items)
    per_axis: dict[str, list[str]] = {}
    shared: list[str] = []
    for item in items:
        for part in split_pairs(item):
            role_text = part.split("=", 1)[0]
            if "." in role_text:
                axis, rest = role_text.split(".", 1)
                if not _AXIS.match(axis):
                    raise UsageError(
                        f"{option} {part!r}: axis name {axis!r} may use letters, digits, _ and - "
                        f"(e.g. {option} x.step=5,x.dir=6)"
                    )
                per_axis.setdefault(axis, []).append(rest + part[len(role_text) :])
            else:
                shared.append(part)
    if not per_axis:
        return [AxisMap(None, parse_map(items, option))]
    common = parse_map([",".join(shared)], option) if shared else {}
    named = {
        name: parse_map([",".join(pairs)], f"{option} (axis {name})")
        for name, pairs in per_axis.items()
    }
    return _assemble(named, common, option, lambda role, ch: f"(e.g. {option} x.{role}={ch})")


def _assemble(
    named: Mapping[str, dict[str, str]],
    common: Mapping[str, str],
    option: str,
    example: Callable[[str, str], str],
) -> list[AxisMap]:
    """Named axes' roles (each already checked on its own) plus the shared roles → the axes.

    ``example(role, channel)`` words the fix for a shared role that must name its axis.

    Raises:
        UsageError: a shared role other than enable, one channel in two axes.
    """
    for role in common:
        if role not in SHAREABLE:
            raise UsageError(
                f"{option} {role}={common[role]}: with several axes every role but enable names "
                f"its axis {example(role, common[role])}"
            )
    axes = []
    owner: dict[str, str] = {}  # channel as written -> "axis.role"
    for name, given in named.items():
        roles = dict(given)
        for role, ch in roles.items():
            key = ch.strip()
            if key in owner and role not in SHAREABLE:
                raise UsageError(
                    f"{option}: channel {key!r} is mapped as {owner[key]} and {name}.{role}; "
                    "one channel has one role on one axis (only enable may be shared)"
                )
            owner[key] = f"{name}.{role}"
        for role, ch in common.items():
            roles.setdefault(role, ch)
        axes.append(AxisMap(name, roles))
    return axes


def axes_from_tables(
    axes: Mapping[str, Mapping[str, str]],
    shared: Mapping[str, str] | None = None,
    where: str = "map",
) -> list[AxisMap]:
    """Axes given as tables (axis → role → channel, e.g. from a ``wavecheck.toml`` or the Python
    API), with ``shared`` roles for every axis (only enable), checked as :func:`parse_axes` checks
    ``--map``; roles are spelt as there (``STEP``, ``phase_a``, ``a``).

    Raises:
        UsageError: a bad axis name, an unknown role, a role twice or a channel in two roles of
            one axis, a channel in two axes, a shared role other than enable, no axis.
    """
    if not axes:
        raise UsageError(f"{where}: no axis given")
    named: dict[str, dict[str, str]] = {}
    for name, table in axes.items():
        if not _AXIS.match(str(name)):
            raise UsageError(f"{where}: axis name {name!r} may use letters, digits, _ and -")
        named[str(name)] = _table_roles(table, f"{where} (axis {name})")
    common = _table_roles(shared or {}, where)
    return _assemble(named, common, where, lambda role, ch: f"(give {role} in each axis)")


def _table_roles(table: Mapping[str, str], where: str) -> dict[str, str]:
    """role → channel of one table, roles normalised; a role or a channel once."""
    roles: dict[str, str] = {}
    for key, ch in table.items():
        role = role_name(str(key))
        channel = str(ch)
        if not channel.strip():
            raise UsageError(f"{where}: {key} names no channel")
        if role in roles:
            raise UsageError(f"{where}: role {role} is mapped twice")
        for other, seen in roles.items():
            if seen.strip() == channel.strip():
                raise UsageError(
                    f"{where}: channel {channel.strip()!r} is mapped as both {other} and {role}; "
                    "one channel can have one role"
                )
        roles[role] = channel
    return roles


def per_axis(
    values: Sequence[str] | str | None, option: str, axes: Sequence[str | None]
) -> dict[str | None, str]:
    """``--drive ID`` / ``--drive x=ID`` values → axis → value (a bare value serves every axis
    not named; the last bare value wins over an earlier one, as argparse's usual repeat).

    Raises:
        UsageError: an ``AXIS=`` naming no mapped axis, or an axis left without a value.
    """
    if values is None:
        return {}
    if isinstance(values, str):
        values = [values]
    bare: str | None = None
    named: dict[str, str] = {}
    known = {a for a in axes if a is not None}
    for v in values:
        axis, sep, rest = v.partition("=")
        if sep and _AXIS.match(axis) and axis in known:
            named[axis] = rest
        elif sep and _AXIS.match(axis) and "/" not in axis and "." not in axis:
            raise UsageError(
                f"{option} {v}: no axis {axis!r} is mapped (axes: {', '.join(sorted(known)) or 'none'})"
            )
        else:
            bare = v
    out: dict[str | None, str] = {}
    for a in axes:
        value = named.get(a, bare) if a is not None else bare
        if value is not None:
            out[a] = value
    return out


def split_per_axis(values: Sequence[str] | str | None, option: str) -> dict[str | None, str]:
    """``--drive ID`` / ``--drive x=ID`` values → axis (None: every axis not named) → value, by
    their syntax alone (the axes are checked when they are known: :func:`check_axis_names`);
    a later value for the same axis wins, as argparse's usual repeat."""
    if values is None:
        return {}
    if isinstance(values, str):
        values = [values]
    out: dict[str | None, str] = {}
    for v in values:
        axis, sep, rest = v.partition("=")
        if sep and _AXIS.match(axis):
            if not rest:
                raise UsageError(f"{option} {v}: give a value after {axis}=")
            out[axis] = rest
        else:
            out[None] = v
    return out


def check_axis_names(given: Mapping[str, Iterable[str | None]], axes: Sequence[str | None]) -> None:
    """Refuse a per-axis value for an axis that is not mapped (``given``: option → the axes it
    names).

    Raises:
        UsageError: ``--drive z=…`` where no axis z is mapped.
    """
    known = {a for a in axes if a is not None}
    for option, names in given.items():
        for name in names:
            if name is not None and name not in known:
                raise UsageError(
                    f"{option} {name}=…: no axis {name!r} is mapped "
                    f"(axes: {', '.join(sorted(known)) or 'none'})"
                )


def split_invert(roles: Iterable[str], axes: Sequence[str | None]) -> dict[str | None, list[str]]:
    """``--invert x.step`` / ``--invert enable`` → axis → roles to invert (bare: every axis)."""
    out: dict[str | None, list[str]] = {a: [] for a in axes}
    known = {a for a in axes if a is not None}
    for text in roles:
        if "." in text:
            axis, role = text.split(".", 1)
            if axis not in known:
                raise UsageError(
                    f"--invert {text}: no axis {axis!r} is mapped (axes: "
                    f"{', '.join(sorted(known)) or 'none'})"
                )
            out[axis].append(role_name(role))
        else:
            for a in axes:
                out[a].append(text)
    return out
