"""Verdicts, what a verdict claims, and the exit codes they give, in one place.

A rule is ``pass``, ``fail``, ``indeterminate`` (the sample rate, or the configuration, cannot
decide it) or ``unchecked`` (no interval of its kind in the capture, no channel for it, no figure
to check it against). Exit codes of both command-line tools: 0 pass, 1 a rule failed, 2 unusable
input or usage, 3 only indeterminate or unchecked results, 4 a rule the run requires
(``--require``) was not decided: unchecked or indeterminate (no rule failed).

A verdict line never hides a rule that was not checked: :func:`qualified_verdict` names them,
grouped by why (``PASS (dir_setup, dir_hold not checked: no DIR channel)``). ``check`` and
``config`` (and every entry point) describe their rules as :class:`RuleStatus` rows and use the
same functions: :func:`unchecked_by_reason` for the verdict line, :func:`unmet_requirements` and
:func:`required_exit_code` for ``--require``.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from typing import Literal

from wavecheck.errors import UsageError
from wavecheck.record import record

__all__ = [
    "EXIT_FAIL",
    "EXIT_INDETERMINATE",
    "EXIT_PASS",
    "EXIT_REQUIRED",
    "EXIT_USAGE",
    "REQUIRE_ALL",
    "RuleStatus",
    "Unmet",
    "Verdict",
    "check_require",
    "exit_code",
    "overall_verdict",
    "qualified_verdict",
    "require_list",
    "required_exit_code",
    "required_line",
    "unchecked_by_reason",
    "unchecked_phrase",
    "unmet_requirements",
    "verdict_of_exit",
    "worst_exit_code",
]

Verdict = Literal["pass", "fail", "indeterminate", "unchecked"]

EXIT_PASS = 0
EXIT_FAIL = 1
EXIT_USAGE = 2
EXIT_INDETERMINATE = 3
#: A rule the run requires (``--require``) is unchecked or indeterminate, and no rule failed.
EXIT_REQUIRED = 4

_EXIT: dict[str, int] = {
    "pass": EXIT_PASS,
    "fail": EXIT_FAIL,
    "indeterminate": EXIT_INDETERMINATE,
    "unchecked": EXIT_INDETERMINATE,
}
#: How bad an exit code is when several runs are summed up:
#: usage > fail > a required rule not decided > indeterminate > pass.
_SEVERITY = {EXIT_PASS: 0, EXIT_INDETERMINATE: 1, EXIT_REQUIRED: 2, EXIT_FAIL: 3, EXIT_USAGE: 4}


def overall_verdict(verdicts: Iterable[Verdict | str]) -> Verdict:
    """fail if any is fail, else indeterminate if any is, else pass if any is, else unchecked
    (``unchecked`` rules never turn a pass into a fail)."""
    seen = set(verdicts)
    for v in ("fail", "indeterminate", "pass"):
        if v in seen:
            return v  # type: ignore[return-value]
    return "unchecked"


def exit_code(verdict: Verdict | str) -> int:
    """The exit code of an overall verdict: 0 pass, 1 fail, 3 indeterminate or unchecked."""
    return _EXIT[verdict]


def verdict_of_exit(code: int) -> Verdict | None:
    """The verdict an exit code stands for (3 → indeterminate), None for 2 (unusable input) and
    4 (a required rule not decided: the rules' own verdict may be pass or indeterminate)."""
    return {EXIT_PASS: "pass", EXIT_FAIL: "fail", EXIT_INDETERMINATE: "indeterminate"}.get(code)  # type: ignore[return-value]


def worst_exit_code(codes: Iterable[int]) -> int:
    """The worst of several exit codes: 2 > 1 > 4 > 3 > 0."""
    return max(codes, key=lambda c: _SEVERITY.get(c, 3), default=EXIT_PASS)


def qualified_verdict(
    verdict: Verdict | str, unchecked: Mapping[str, Sequence[str]], lead: str = ""
) -> str:
    """The verdict as a report's verdict line says it: upper case, followed by the rules that
    were not checked grouped by why (``unchecked``: reason → rule ids, as
    :func:`unchecked_by_reason` gives them), so a PASS never hides an unchecked rule:
    ``PASS (dir_setup, dir_hold not checked: no DIR channel)``. ``lead`` opens the parenthesis
    (``FAIL (2 axes; y.dir_hold not checked: no DIR channel)``)."""
    said = "; ".join(x for x in (lead, unchecked_phrase(unchecked)) if x)
    return verdict.upper() + (f" ({said})" if said else "")


def unchecked_phrase(unchecked: Mapping[str, Sequence[str]]) -> str:
    """``dir_setup, dir_hold not checked: no DIR channel; …`` ("" when every rule was checked)."""
    return "; ".join(
        f"{', '.join(rules)} not checked: {why}" for why, rules in unchecked.items() if rules
    )


@record(frozen=True)
class RuleStatus:
    """One rule of one axis as a verdict line and ``--require`` read it.

    Attributes:
        rule: the rule id.
        verdict: its verdict (``unchecked`` for a rule the drive states no figure for, too).
        why: for ``unchecked``, why it was not checked (``no DIR channel``, ``drive tb6600
            states no figure``); for ``indeterminate``, why it was not decided.
        axis: the axis (None: the only one).
        stated: the drive gives the rule a figure (``--require all`` requires exactly those).
    """

    rule: str
    verdict: Verdict
    why: str = ""
    axis: str | None = None
    stated: bool = True


def _axes(statuses: Sequence[RuleStatus]) -> list[str | None]:
    return list(dict.fromkeys(s.axis for s in statuses))


def _label(rule: str, axis: str | None) -> str:
    return rule if axis is None else f"{axis}.{rule}"


def _named(on: dict[str, list[str | None]], axes: int) -> tuple[str, ...]:
    """Rule → the axes it is on, as names: the rule alone when it is on every one of ``axes``
    axes, else ``AXIS.RULE`` for each."""
    names: list[str] = []
    for rule, where in on.items():
        every = axes == 1 or len(set(where)) == axes
        names += [rule] if every else [_label(rule, a) for a in where]
    return tuple(names)


def unchecked_by_reason(statuses: Iterable[RuleStatus]) -> dict[str, tuple[str, ...]]:
    """Why → the rules not checked for that reason, in the order first seen. Over several axes a
    rule not checked for the same reason on every axis is named alone, else as ``AXIS.RULE``."""
    rows = list(statuses)
    where: dict[str, dict[str, list[str | None]]] = {}
    for s in rows:
        if s.verdict == "unchecked":
            on = where.setdefault(s.why or "no interval of its kind", {}).setdefault(s.rule, [])
            on.append(s.axis)
    axes = len(_axes(rows))
    return {why: _named(on, axes) for why, on in where.items()}


#: ``--require all``: every rule the drive gives a figure for.
REQUIRE_ALL = "all"


def require_list(value: str | Iterable[str] | None) -> tuple[str, ...]:
    """``--require`` values (``"dir_setup,dir_hold"``, ``["all"]``, repeatable) as one tuple of
    names, in order, each once (not yet checked against the rule ids: :func:`check_require`)."""
    if value is None:
        return ()
    texts = [value] if isinstance(value, str) else list(value)
    names = [n.strip() for text in texts for n in str(text).split(",")]
    return tuple(dict.fromkeys(n for n in names if n))


def check_require(require: Sequence[str], rule_ids: Sequence[str]) -> None:
    """Raise :class:`~wavecheck.errors.UsageError` unless each name is a rule id or ``all``."""
    for name in require:
        if name != REQUIRE_ALL and name not in rule_ids:
            raise UsageError(
                f"--require {name!r} is not a rule (give rule ids, comma-separated, or "
                f"{REQUIRE_ALL}: {', '.join(rule_ids)})"
            )


@record(frozen=True)
class Unmet:
    """A required rule that was not decided: its verdict (unchecked or indeterminate) and why."""

    rule: str
    verdict: Verdict
    why: str
    axis: str | None = None

    @property
    def said(self) -> str:
        """``not checked`` or ``indeterminate``, as the reports say it."""
        return "not checked" if self.verdict == "unchecked" else "indeterminate"


def unmet_requirements(statuses: Sequence[RuleStatus], require: Sequence[str]) -> tuple[Unmet, ...]:
    """The required rules (``require``: rule ids and/or ``all``) of each axis that are unchecked
    or indeterminate. ``all`` requires every rule the drive gives a figure for; a named rule is
    required even when the drive states none (or the step type has no such rule)."""
    if not require:
        return ()
    named = [r for r in require if r != REQUIRE_ALL]
    out: list[Unmet] = []
    for axis in _axes(statuses) or [None]:
        mine = {s.rule: s for s in statuses if s.axis == axis}
        wanted = [r for r, s in mine.items() if s.stated] if REQUIRE_ALL in require else []
        for rule in dict.fromkeys([*wanted, *named]):
            s = mine.get(rule)
            if s is None:
                out.append(Unmet(rule, "unchecked", "not a rule of this step type", axis))
            elif s.verdict in ("unchecked", "indeterminate"):
                out.append(Unmet(rule, s.verdict, s.why or s.verdict, axis))
    return tuple(out)


def required_line(unmet: Sequence[Unmet], statuses: Sequence[RuleStatus] = ()) -> str:
    """One line saying which required rules were not decided and why, grouped by why: ``required
    but not decided: dir_setup, dir_hold not checked: no DIR channel``; empty when none (the run
    exits 4 unless a rule failed: :func:`required_exit_code`).
    A rule not decided on every axis of ``statuses`` for one reason is named alone."""
    if not unmet:
        return ""
    groups: dict[tuple[str, str], dict[str, list[str | None]]] = {}
    for u in unmet:
        groups.setdefault((u.said, u.why), {}).setdefault(u.rule, []).append(u.axis)
    axes = len(_axes(statuses)) if statuses else 0
    parts = [f"{', '.join(_named(on, axes))} {said}: {why}" for (said, why), on in groups.items()]
    return f"required but not decided: {'; '.join(parts)}"


def required_exit_code(code: int, unmet: Sequence[Unmet]) -> int:
    """``code`` (of the rules' verdict), or :data:`EXIT_REQUIRED` when a required rule was not
    decided and nothing worse happened (a failed rule keeps 1, unusable input 2)."""
    if unmet and code in (EXIT_PASS, EXIT_INDETERMINATE):
        return EXIT_REQUIRED
    return code
