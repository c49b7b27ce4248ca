"""Which changing line is whose DIR: the fits of :mod:`wavecheck.roles.dirs` narrowed by the
reversals and names, matched to distinct STEP lines; what no matching settles is a conflict."""

from __future__ import annotations

from wavecheck.capture.edges import Channel
from wavecheck.roles.dirs import DirFit, assign, dir_fit
from wavecheck.roles.dirs import plural as _plural
from wavecheck.roles.proposal import (
    Conflict,
)
from wavecheck.roles.state import State

__all__ = ["DirChoice"]


class DirChoice(State):
    """The stage that gives the STEP lines their changing DIRs."""

    def _dirs(self, pulse: list[Channel], others: list[Channel]) -> dict[int, DirFit]:
        """DIR fits, STEP channel index → fit; conflicts recorded (see :mod:`wavecheck.roles.dirs`).

        A line's candidates are the STEP lines it fits consistently (every change at a reversal of
        their rate or outside their motion); a line that fits a single STEP line keeps it even
        when not consistent (it is that line's DIR or no DIR at all). A name with an axis narrows
        the candidates to the one with the same axis.
        """
        fits_of: dict[int, list[DirFit]] = {}
        cands: dict[int, list[DirFit]] = {}
        for d in others:
            fits = []
            for s in pulse:
                if s.index == d.index:
                    continue  # a line of a few pulses is a STEP candidate and a DIR candidate
                sp = self.looks[s.index].pulses
                assert sp is not None
                f = dir_fit(d, s, sp)
                if f is not None:
                    fits.append(f)
            if not fits:
                continue
            fits_of[d.index] = fits
            good = [f for f in fits if f.consistent] if len(fits) > 1 else fits
            axis = self.hints[d.index].axis
            # a DIR named with an axis (y_dir, "DIR (Y axis)") goes to the one STEP of that axis
            # when the waveform cannot tell its candidates apart
            by_name = self.hints[d.index].fits("dir") and axis is not None
            pool = good if good or not by_name else fits
            same = [f for f in pool if axis is not None and self.hints[f.s.index].axis == axis]
            if len(same) == 1:
                good = same
            if not good:
                self._dir_conflict(
                    f"{self.name_of(d)} fits as the DIR of several STEP lines, and changes while "
                    "each of them runs steadily",
                    [d.index],
                    fits,
                )
                continue
            cands[d.index] = good
        # two lines whose only candidate is one STEP: a DIR-named one takes it
        only: dict[int, list[DirFit]] = {}
        for fits in cands.values():
            if len(fits) == 1:
                only.setdefault(fits[0].s.index, []).append(fits[0])
        for fits in only.values():
            named = [f for f in fits if self.hints[f.d.index].fits("dir")]
            if len(fits) > 1 and len(named) == 1:
                for f in fits:
                    if f is not named[0]:
                        del cands[f.d.index]
                        self.why[f.d.index] = (
                            f"also fits as DIR of {self.name_of(f.s)}, whose DIR is "
                            f"{self.name_of(named[0].d)} by name"
                        )
        got = assign(cands)
        for lines in got.crowded:
            fits = [f for d in lines for f in cands[d]]
            steps = {f.s.index for f in fits}
            if len(steps) == 1:
                q = f"{_plural(len(lines), 'channel')} fit as the DIR of {self.name_of(fits[0].s)}"
            else:
                q = (
                    f"{_plural(len(lines), 'channel')} fit as DIRs of only "
                    f"{_plural(len(steps), 'STEP line')}: which is whose DIR?"
                )
            self._dir_conflict(q, list(lines), fits)
        for di, fits in got.undecided.items():
            self._dir_conflict(
                f"{self.name_of(fits[0].d)} fits as the DIR of several STEP lines", [di], fits
            )
        for f in got.chosen.values():
            notes = []
            for g in fits_of[f.d.index]:
                if g.s.index == f.s.index:
                    continue
                has = got.chosen.get(g.s.index)
                if has is not None:
                    notes.append(f"{self.name_of(g.s)} has DIR {self.name_of(has.d)}")
                elif not g.consistent:
                    notes.append(
                        f"{self.name_of(g.s)} runs steadily through "
                        f"{g.toggles - g.at_reversal - g.outside:,} of its changes"
                    )
                else:
                    notes.append(
                        f"{self.name_of(g.s)} cannot take it: another changing line would be "
                        "left without a STEP line it fits"
                    )
            if notes:
                self.dir_notes[f.d.index] = f" (it also fits other STEP lines: {'; '.join(notes)})"
        return got.chosen

    def _dir_conflict(self, question: str, lines: list[int], fits: list[DirFit]) -> None:
        """Refuse ``lines`` as DIRs: a conflict listing ``fits``; their STEPs become unsure."""
        self.conflicts.append(
            Conflict(
                question,
                tuple(
                    f"{self.name_of(f.d)} as DIR of {self.name_of(f.s)}: {f.evidence()}"
                    for f in fits
                ),
            )
        )
        for d in lines:
            self.why[d] = "ambiguous DIR (see below)"
            self.taken.add(d)
        self.unsure_steps |= {f.s.index for f in fits}
