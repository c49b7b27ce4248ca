"""Lines that hold still while the axes move: DIRs that never change (taken by name or by
layout) and ENABLEs (a level at which no axis moves, changed only where the axes stand still)."""

from __future__ import annotations

import numpy as np

from wavecheck.capture.edges import Channel
from wavecheck.roles.dirs import at_pauses
from wavecheck.roles.dirs import plural as _plural
from wavecheck.roles.motion import (
    off_around,
)
from wavecheck.roles.proposal import (
    Conflict,
)
from wavecheck.roles.state import State, level_at

__all__ = ["StillLines"]


class StillLines(State):
    """The stages of the DIRs that never change and of the ENABLEs."""

    def _constant_dirs(self, constants: list[Channel]) -> None:
        missing = [a for a in self.axes if a.kind == "step-dir" and len(a.roles) == 1]
        if not missing:
            return
        free = [c for c in constants if c.index not in self.taken]
        # by name: a DIR-named unchanging channel with the STEP's axis (or the only pair)
        for a in list(missing):
            axis = self.hints[a.channels[0].index].axis
            named = [
                c
                for c in free
                if self.hints[c.index].fits("dir")
                and (self.hints[c.index].axis == axis or (axis is None and len(missing) == 1))
            ]
            if len(named) == 1:
                c = named[0]
                a.roles.append(
                    self.choice(
                        "dir",
                        c,
                        f"{self.looks[c.index].evidence}: no waveform evidence; named like "
                        "the DIR of this axis",
                        "name",
                    )
                )
                free = [f for f in free if f.index != c.index]
                missing.remove(a)
        by_index = {c.index: c for c in free}
        nexts = [by_index.get(a.channels[0].index + 1) for a in missing]
        unsure = any("DIR" in c.question for c in self.conflicts)  # a changing DIR is unplaced
        if (
            missing
            and not unsure
            and all(c is not None and self.hints[c.index].neutral for c in nexts)
        ):
            for a, nxt in zip(missing, nexts, strict=True):
                assert nxt is not None
                step = a.channels[0]
                a.roles.append(
                    self.choice(
                        "dir",
                        nxt,
                        f"{self.looks[nxt.index].evidence}: no waveform evidence; taken as "
                        f"the DIR of {self.name_of(step)} because it is the next channel, as every "
                        "STEP without a changing DIR is followed by an unchanging one (check the "
                        "wiring)",
                        "layout",
                    )
                )
                a.notes.append(
                    "its DIR never changes: direction and final position rest on a guess"
                )
        for a in self.axes:
            if a.kind == "step-dir" and len(a.roles) == 1:
                a.notes.append("no DIR found: direction and final position are unknown")

    def _enables(self, cands: list[Channel]) -> None:
        moving = [a for a in self.axes if len(a.motion)]
        for e in cands:
            per_axis = []
            for a in moving:
                lv = level_at(e, a.motion)
                per_axis.append((int(np.count_nonzero(lv == 0)), int(np.count_nonzero(lv == 1))))
            served: dict[int, list[int]] = {0: [], 1: []}
            for k, (lo, hi) in enumerate(per_axis):
                if lo and not hi:
                    served[0].append(k)
                elif hi and not lo:
                    served[1].append(k)
            mixed = [k for k, (lo, hi) in enumerate(per_axis) if lo and hi]
            if served[0] and served[1] or not (served[0] or served[1]):
                continue
            active = 0 if served[0] else 1
            axes = [moving[k] for k in served[active]]
            # an ENABLE changes where its axes stand still, never while one runs
            if any(sum(at_pauses(e.edges, a.motion)[:2]) < len(e.edges) for a in axes):
                continue
            motion = np.concatenate([a.motion for a in axes])
            if not self.hints[e.index].fits("enable") and not off_around(
                e, active, motion, self.cap.start
            ):
                continue  # never seen off between steps: no gating shown
            n_events = sum(per_axis[k][active] for k in served[active])
            ev = (
                f"changes {_plural(len(e.edges), 'time')}; all {n_events:,} steps of "
                f"{', '.join(self.name_of(a.channels[0]) for a in axes)} happen while it is "
                f"{'high' if active else 'low'}, none while it is {'low' if active else 'high'}"
            )
            if mixed:
                ev += f"; other axes move at both levels ({len(mixed)})"
            existing = [a for a in axes if any(r.role == "enable" for r in a.roles)]
            if existing:
                self.conflicts.append(
                    Conflict(
                        f"{self.name_of(e)} and another line both fit as ENABLE",
                        (f"ENABLE {self.name_of(e)}: {ev}",)
                        + tuple(
                            f"ENABLE {r.index}={r.channel!r}: {r.evidence}"
                            for a in existing
                            for r in a.roles
                            if r.role == "enable"
                        ),
                    )
                )
                self.why[e.index] = "ambiguous ENABLE (see below)"
                self.taken.add(e.index)
                continue
            for a in axes:
                a.roles.append(self.choice("enable", e, ev, active=active))
            if len(axes) > 1:
                self.shared.append((e, ev, axes))
