"""Each interval judged at the sample that decides it: the rule table, edge by edge.

libsigrokdecode hands a decoder its samples one ``wait()`` at a time, and nothing tells it that
the capture has ended: PulseView 0.4.2 keeps the decoder waiting after the last sample, and
libsigrokdecode 0.5.3 has no end-of-input call (sigrok-cli's only chance is the exception
``wait()`` raises when the library shuts down). So each interval is measured, judged and shown
at the sample of its later event — the edge that closes it — instead of in blocks afterwards.

This module restates, one edge at a time, how the engine turns events into intervals
(:mod:`wavecheck.engine.intervals`, :mod:`wavecheck.steps.primitives`) and edges into steps
(:mod:`wavecheck.steps.decode`), for each kind of check the rule table uses; the limits and the exact
pass/fail thresholds come from the engine (:class:`~wavecheck.sigrok.adapter.RuleSpec`).
``tests/wavecheck/sigrok/test_judge.py`` holds every interval, outcome and step equal to the
engine's. Same-sample events follow the engine: a reference event counts for the data event of
its own sample (a DIR change and an active edge at one sample are a 0 setup and a 0 hold); an
ENABLE that goes inactive at a step's sample does not enable it. Plain Python, no numpy: it runs
once per edge.
"""

from __future__ import annotations

from collections.abc import Sequence

from wavecheck.sigrok.adapter import Plan

__all__ = ["INTERVAL", "SEQUENCE", "STEP", "Judge"]

#: Kinds of output: ``(INTERVAL, rule index, start, end, outcome)``, ``(STEP, sample,
#: direction, position)``, ``(SEQUENCE, rule index, sample, state before, state after)``.
INTERVAL, STEP, SEQUENCE = 0, 1, 2

Out = tuple[int, int, int, int, int]


#: Events of the rule table (:mod:`wavecheck.rules`) as bits, so a sample's events are one int.
EVENTS = {"active": 1, "step": 2, "dir": 4, "enable": 8, "state": 16}


class Judge:
    """The intervals, steps and verdicts of one step interface, one edge at a time."""

    def __init__(self, plan: Plan) -> None:
        self.plan = plan
        roles = [r for r in plan.roles if r is not None]
        line = {r: k for k, r in enumerate(roles)}
        self.flip = [int(r in plan.inverted) for r in roles]
        st = plan.step_type
        self.kind = st.kind
        self.pulse = [line[r] for r in (("step",) if st.kind == "step-dir" else st.outputs)]
        self.dir = line.get("dir") if st.kind == "step-dir" else None
        self.enable = line.get("enable")
        self.edge = plan.active_edge
        self.forward = plan.forward_level
        self.lookup = {v: i for i, v in enumerate(st.states)}
        self.cycle = st.cycle
        # rules by what builds their intervals (the rule table's check, ref and data)
        self.width: dict[int, int] = {}
        self.periods: list[tuple[int, int]] = []
        self.setups: list[tuple[int, int, int]] = []
        self.holds: list[tuple[int, int, int]] = []
        self.switch: int | None = None
        self.sequence: int | None = None
        for k, spec in enumerate(plan.rules):
            r = spec.rule
            ref, data = EVENTS.get(r.ref, 0), EVENTS.get(r.data, 0)
            if r.check == "width" and r.level is not None:
                self.width[r.level] = k
            elif r.check == "period":
                self.periods.append((k, ref))
            elif r.check == "setup":
                self.setups.append((k, ref, data))
            elif r.check == "hold":
                self.holds.append((k, ref, data))
            elif r.check == "switch":
                self.switch = k
            elif r.check == "sequence":
                self.sequence = k
            else:
                raise ValueError(f"rule {r.id!r}: no per-edge measurement for {r.check!r}")
        self.ruled = 0  # the events some setup, hold or period rule listens to
        for _, ref, data in self.setups + self.holds:
            self.ruled |= ref | data
        for _, ref in self.periods:
            self.ruled |= ref
        self.specs = plan.rules
        self.levels: list[int] = []
        self.changed: list[int] = []
        self.last_edge: list[int | None] = []
        self.last: dict[int, int] = {}  # event bit → its last sample (period, hold references)
        self.pending: dict[int, list[int]] = {}  # setup rule → references waiting for data
        self.position = 0
        self.state = 0
        # up/down line switches: the open pulse of each line ([end, waiting switch sample]) and
        # the last pulse (its line and [end, waiting switch sample]); -1: not yet
        self.open: dict[int, list[int]] = {}
        self.last_pulse: tuple[int, list[int]] | None = None
        self.ends_at_active = plan.active_edge != "both" and plan.pulse_level != (
            plan.active_edge == "rising"
        )

    def start(self, raw: Sequence[int]) -> None:
        """The raw level of each mapped channel at the first sample."""
        self.levels = [v ^ f for v, f in zip(raw, self.flip, strict=True)]
        self.last_edge = [None] * len(self.levels)
        self.state = sum(self.levels[p] << bit for bit, p in enumerate(self.pulse))

    def _active(self, new: int) -> bool:
        return self.edge == "both" or (new == 1) == (self.edge == "rising")

    def at(self, t: int, raw: Sequence[int]) -> list[Out]:
        """Everything sample ``t`` decides, given the raw level of each mapped channel there
        (:attr:`changed`: the channels that changed, by index)."""
        old = self.levels
        new = [v ^ f for v, f in zip(raw, self.flip, strict=True)]
        self.levels = new
        self.changed = changed = [k for k in range(len(new)) if new[k] != old[k]]
        out: list[Out] = []
        events = 0
        for k in changed:
            if k in self.pulse:
                self._width(t, k, old[k], out)
            elif k == self.dir:
                events |= 4
            elif k == self.enable:
                if new[k]:
                    events |= 8
                else:  # a step only counts while ENABLE stays active
                    for rule, ref, _data in self.setups:
                        if ref == 8:
                            self.pending.pop(rule, None)
        step, events = self._decode(t, changed, old, new, events, out)
        if step is not None:
            events |= 2
            out.append((STEP, t, step, self.position, 0))
        if events & self.ruled:
            self._rules(t, events, out)
        return out

    def _width(self, t: int, k: int, level: int, out: list[Out]) -> None:
        """The stretch that edge ``t`` of pulse line ``k`` ends (at ``level``)."""
        began = self.last_edge[k]
        self.last_edge[k] = t
        rule = self.width.get(level)
        if began is not None and rule is not None:
            out.append((INTERVAL, rule, began, t, self.specs[rule].outcome(t - began)))

    def _decode(
        self,
        t: int,
        changed: list[int],
        old: list[int],
        new: list[int],
        events: int,
        out: list[Out],
    ) -> tuple[int | None, int]:
        """The step at ``t`` (its direction: +1, −1, 0 unknown) or None, and the events."""
        if self.kind == "step-dir":
            p = self.pulse[0]
            if p not in changed or not self._active(new[p]):
                return None, events
            d = self.dir
            if d is None or new[d] != old[d]:
                return self._moved(0), events | 1
            return self._moved(1 if old[d] == self.forward else -1), events | 1
        if self.kind == "up-down":
            up, down = (p in changed and self._active(new[p]) for p in self.pulse)
            self._switches(t, changed, up, down, out)
            if not (up or down):
                return None, events
            return self._moved(0 if up and down else 1 if up else -1), events
        if not any(p in changed for p in self.pulse):
            return None, events
        return self._phases(t, new, out), events | 16

    def _moved(self, direction: int) -> int:
        self.position += direction
        return direction

    def _phases(self, t: int, new: list[int], out: list[Out]) -> int | None:
        """A change of the phase state: a step to a neighbour, or a sequence error."""
        before, self.state = self.state, sum(new[p] << bit for bit, p in enumerate(self.pulse))
        a, b = self.lookup.get(before, -1), self.lookup.get(self.state, -1)
        if b < 0 or a < 0:
            if b < 0 and self.sequence is not None:
                out.append((SEQUENCE, self.sequence, t, before, self.state))
            return None  # a move out of the table; a move back into it re-synchronises
        delta = (b - a) % self.cycle
        if delta == 1:
            return self._moved(0 if self.cycle == 2 else 1)
        if delta == self.cycle - 1:
            return self._moved(-1)
        if self.sequence is not None:
            out.append((SEQUENCE, self.sequence, t, before, self.state))
        return None

    def _switches(self, t: int, changed: list[int], up: bool, down: bool, out: list[Out]) -> None:
        """``dir_delay``: the end of the last pulse on one line → the first on the other."""
        if self.switch is None:
            return
        for line, p in enumerate(self.pulse):  # edges that end an open pulse
            pulse = self.open.pop(line, None) if p in changed else None
            if pulse is not None:
                pulse[0] = t
                if pulse[1] >= 0:  # a pulse on the other line began before this one ended
                    self._switch(t, pulse[1], out)
        for line, began in enumerate((up, down)):
            if not began:
                continue
            pulse = [t if self.ends_at_active else -1, -1]
            if self.last_pulse is not None and self.last_pulse[0] != line:
                prev = self.last_pulse[1]
                if prev[0] >= 0:
                    self._switch(prev[0], t, out)
                else:
                    prev[1] = t
            if not self.ends_at_active:
                self.open[line] = pulse
            self.last_pulse = (line, pulse)

    def _switch(self, start: int, end: int, out: list[Out]) -> None:
        assert self.switch is not None
        out.append(
            (INTERVAL, self.switch, start, end, self.specs[self.switch].outcome(end - start))
        )

    def _rules(self, t: int, events: int, out: list[Out]) -> None:
        """Setups, holds and periods whose events happen at ``t`` (references first)."""
        specs, last = self.specs, self.last
        for k, ref, data in self.setups:
            if events & ref:
                self.pending.setdefault(k, []).append(t)
            if events & data and k in self.pending:
                for began in self.pending.pop(k):
                    out.append((INTERVAL, k, began, t, specs[k].outcome(t - began)))
        for k, ref, data in self.holds:
            if events & data and (events & ref or ref in last):
                began = t if events & ref else last[ref]
                out.append((INTERVAL, k, began, t, specs[k].outcome(t - began)))
        for k, ref in self.periods:
            if events & ref and ref in last:
                began = last[ref]
                out.append((INTERVAL, k, began, t, specs[k].outcome(t - began)))
        for bit in (1, 2, 4, 8, 16):
            if events & bit:
                last[bit] = t
