"""The judge fed as libsigrokdecode feeds the decoder, and the engine's answer for the same capture.

:func:`replay` walks a capture sample by sample where a mapped channel changes (what ``wait()``
on an edge of any channel returns) and collects what :class:`~wavecheck.sigrok.judge.Judge`
decides; :func:`engine_view` runs ``wavecheck check``'s engine on the same capture and options.
Both give intervals per rule as sorted ``(start, end, outcome)``, steps as ``(tick, direction,
position)`` and sequence errors as ``(tick, before, after)``.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from fractions import Fraction

import numpy as np

from tests.engine_probe import decoded, every_interval, run_check
from wavecheck.capture.edges import Capture
from wavecheck.drives.datasheet import Drive
from wavecheck.sigrok.adapter import CHANNEL_ROLES, MEASURED, Plan, open_check
from wavecheck.sigrok.judge import INTERVAL, SEQUENCE, STEP, Judge

Interval = tuple[int, int, int]


@dataclass
class View:
    """What one side found."""

    intervals: dict[str, list[Interval]] = field(default_factory=dict)
    steps: list[tuple[int, int, int]] = field(default_factory=list)
    sequence: list[tuple[int, int, int]] = field(default_factory=list)


def _kind(step_type: int) -> str:
    return "step-dir" if step_type == 0 else "up-down" if step_type == 1 else "phases"


def replay(
    capture: Capture, roles: Mapping[str, str], options: Mapping[str, object], step_type: int
) -> tuple[Plan, View]:
    """The judge's view of ``capture`` with ``roles`` (role → channel name) mapped to the
    decoder's channels, the decoder ``options`` (``type`` set to ``step_type``)."""
    layout = CHANNEL_ROLES[_kind(step_type)]  # type: ignore[index]
    assigned = [r is not None and r in roles for r in layout]
    rate = 1 / capture.timebase.tick_s
    check = open_check({**options, "type": str(step_type)}, rate, assigned)  # type: ignore[arg-type]
    plan = check.plan
    by_name = {c.name: c for c in capture.channels}
    chans = [by_name[roles[r]] for r in plan.roles if r is not None]
    judge = Judge(plan)
    judge.start([c.initial for c in chans])
    ticks = np.unique(np.concatenate([c.edges for c in chans] or [np.zeros(0, np.int64)]))
    levels = [
        (c.initial ^ (np.searchsorted(c.edges, ticks, side="right") & 1)).tolist() for c in chans
    ]
    view = View({s.rule.id: [] for s in plan.rules})
    for i, t in enumerate(ticks.tolist()):
        for out in judge.at(t, [lv[i] for lv in levels]):
            if out[0] == INTERVAL:
                view.intervals[plan.rules[out[1]].rule.id].append((out[2], out[3], out[4]))
            elif out[0] == STEP:
                view.steps.append((out[1], out[2], out[3]))
            elif out[0] == SEQUENCE:
                view.sequence.append((out[2], out[3], out[4]))
    for v in view.intervals.values():
        v.sort()
    return plan, view


def engine_view(
    capture: Capture,
    roles: Mapping[str, str],
    drive: Drive,
    plan: Plan,
    resolution: Fraction | None,
) -> View:
    """The engine's view of the same check (``plan`` gives the step type, edge and levels)."""
    st = plan.step_type
    report = run_check(
        capture,
        drive,
        dict(roles),
        sorted(plan.inverted),
        st.number,
        resolution,
        forward_level=plan.forward_level,
        active_edge=plan.active_edge,
        user_table=st.states if st.number == 15 else None,
        pulse_level=plan.pulse_level ^ any(r in plan.inverted for r in st.pulse_roles),
    )
    view = View()
    judged = {r.rule: report.rule(r.rule) for r in report.rules}
    measured = every_interval(
        capture,
        mapping=dict(roles),
        invert=sorted(plan.inverted),
        step_type_number=st.number,
        forward_level=plan.forward_level,
        active_edge=plan.active_edge,
        user_table=st.states if st.number == 15 else None,
        pulse_level=plan.pulse_level ^ any(r in plan.inverted for r in st.pulse_roles),
    )
    for spec in plan.rules:
        rid = spec.rule.id
        if spec.rule.check == "sequence":
            continue
        if rid in judged:
            r = judged[rid]
            got = zip(
                r.intervals.start.tolist(),
                r.intervals.end.tolist(),
                r.outcome.tolist(),
                strict=True,
            )
        else:
            iv = measured[rid]
            got = (
                (a, b, MEASURED) for a, b in zip(iv.start.tolist(), iv.end.tolist(), strict=True)
            )
        view.intervals[rid] = sorted(got)
    s = decoded(capture, report)
    view.steps = list(zip(s.ticks.tolist(), s.direction.tolist(), s.position.tolist(), strict=True))
    view.sequence = list(
        zip(
            s.sequence_errors.tolist(),
            s.sequence_from.tolist(),
            s.sequence_to.tolist(),
            strict=True,
        )
    )
    return view
