"""Role inference over every capture of sigrok-dumps: ``python -m tools.roles_corpus [ROOT]``.

Each ``.sr``/``.vcd`` under ROOT (default ``../shared/captures/sigrok-dumps``) is read and given
to :func:`wavecheck.roles.propose` without any ``--map``; the axes it proposes are judged
against what the captures' READMEs say:

- ``stepper_motor/grbl_cnc``: probe 1 is the Y axis STEP, probe 0 its ENABLE; no DIR captured.
- ``stepper_motor/smoothieware`` and ``arm_trace/lpc1769/smoothieware.sr`` (the same machine's
  full capture): probes 3/4 are the Y axis STEP/DIR, 5/6 the X axis STEP/DIR.
- ``graycode`` (a rotary encoder's Gray code) and ``mouse_sensors`` (the ADNS-2051's XA/XB,
  YA/YB outputs) carry quadrature: phase axes of step type 2 are right there, nothing else.
- every other capture carries no step signal: any axis proposed is wrong.

A stepper capture's map (proposed, or suggested when nothing is) keeps every README DIR, or the
totals say how many do not (issue 33).

A stepper capture is ``right`` when its axes are the README's (an ENABLE only on the README's
ENABLE line), ``refused`` when nothing or only an ambiguity is proposed, else ``wrong``. One line
per capture, then the totals; exit 1 when anything is wrong.
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import dataclass
from pathlib import Path

from wavecheck.capture.open import open_capture
from wavecheck.errors import WavecheckError
from wavecheck.roles import Proposal, propose

ROOT = Path(__file__).resolve().parent.parent
DEFAULT = ROOT.parent / "shared" / "captures" / "sigrok-dumps"

_SMOOTHIE = ({"step": 3, "dir": 4}, {"step": 5, "dir": 6})
#: folder (or file) → the README's axes, each role → probe; ENABLE lines allowed per folder
STEPPERS: dict[str, tuple[tuple[dict[str, int], ...], frozenset[int]]] = {
    "stepper_motor/grbl_cnc/": (({"step": 1},), frozenset({0})),
    "stepper_motor/smoothieware/": (_SMOOTHIE, frozenset()),
    "arm_trace/lpc1769/smoothieware.sr": (_SMOOTHIE, frozenset()),
}
QUADRATURE = ("graycode/", "mouse_sensors/")


@dataclass(frozen=True)
class Row:
    """One capture: its path under the root, what it carries, the verdict and what was proposed."""

    path: str
    carries: str  # "steps", "quadrature" or "none"
    verdict: str  # "right", "refused", "wrong", "none" (nothing proposed, as it should), "unread"
    axes: int
    text: str
    dirs_kept: bool | None = None  # stepper captures: every README DIR in the (suggested) map


def _expected(rel: str) -> tuple[tuple[dict[str, int], ...], frozenset[int]] | None:
    return next((v for k, v in STEPPERS.items() if rel.startswith(k)), None)


def _describe(p: Proposal) -> str:
    axes = [
        f"{a.name}:{a.kind}[" + ",".join(f"{r.role}={r.index}" for r in a.roles) + "]"
        for a in p.axes
    ]
    out = " ".join(axes) if axes else "no axis"
    if p.ambiguous:
        out += f" ({len(p.ambiguous)} ambiguous)"
    if not p.axes and not p.ambiguous:
        out += f": {p.summary()}"
        if p.suggested:
            out += f"; suggested {p.suggested_map_args()}"
    return out


def dirs_kept(rel: str, p: Proposal) -> bool | None:
    """For a stepper capture: whether every README DIR is in the map proposed, or suggested
    when nothing is proposed (issue 33: a suggested map never drops a DIR); else None."""
    expected = _expected(rel)
    if expected is None:
        return None
    given = {(r.role, r.index) for a in (p.axes or p.suggested) for r in a.roles}
    return all(("dir", e["dir"]) in given for e in expected[0] if "dir" in e)


def judge(rel: str, p: Proposal) -> tuple[str, str]:
    """(what the capture carries, verdict) for proposal ``p`` of the capture at ``rel``."""
    expected = _expected(rel)
    if expected is not None:
        axes, enables = expected
        if not p.axes:
            return "steps", "refused"
        got = []
        for a in p.axes:
            roles = {r.role: r.index for r in a.roles if r.role != "enable"}
            if any(r.role == "enable" and r.index not in enables for r in a.roles):
                return "steps", "wrong"
            got.append(roles)
        ok = sorted(map(sorted, (g.items() for g in got))) == sorted(
            map(sorted, (e.items() for e in axes))
        )
        return "steps", ("right" if ok and not p.ambiguous else "wrong" if not ok else "refused")
    if rel.startswith(QUADRATURE):
        ok = all(a.kind == "phases" and a.step_type == 2 for a in p.axes)
        return "quadrature", ("right" if ok and p.axes else "wrong" if not ok else "refused")
    return "none", ("wrong" if p.axes else "none")


def evaluate(root: Path) -> list[Row]:
    """Every capture under ``root``, judged (see the module docstring)."""
    rows = []
    for path in sorted([*root.rglob("*.sr"), *root.rglob("*.vcd")]):
        rel = path.relative_to(root).as_posix()
        carries = (
            "steps" if _expected(rel) else "quadrature" if rel.startswith(QUADRATURE) else "none"
        )
        try:
            cap = open_capture(path)
        except WavecheckError as err:
            rows.append(Row(rel, carries, "unread", 0, str(err).split(": ", 1)[-1]))
            continue
        if not cap.time_known:
            rows.append(Row(rel, carries, "unread", 0, "no sample rate (times need one)"))
            continue
        p = propose(cap)
        carries, verdict = judge(rel, p)
        rows.append(Row(rel, carries, verdict, len(p.axes), _describe(p), dirs_kept(rel, p)))
    return rows


def totals(rows: list[Row]) -> str:
    """The figure: captures tried, read, stepper captures mapped right, axes proposed and wrong."""
    read = [r for r in rows if r.verdict != "unread"]
    steppers = [r for r in read if r.carries == "steps"]
    quad = [r for r in read if r.carries == "quadrature"]
    others = [r for r in read if r.carries == "none"]
    wrong = [r for r in read if r.verdict == "wrong"]
    return (
        f"{len(rows)} captures tried, {len(read)} read ({len(rows) - len(read)} unread); "
        f"stepper captures {len(steppers)}: {sum(r.verdict == 'right' for r in steppers)} right, "
        f"{sum(r.verdict == 'refused' for r in steppers)} refused; quadrature captures "
        f"{len(quad)}: {sum(r.verdict == 'right' for r in quad)} right; other captures "
        f"{len(others)}: axes proposed on {sum(r.axes > 0 for r in others)}; wrong {len(wrong)}; "
        f"stepper maps (proposed or suggested) keeping every README DIR: "
        f"{sum(bool(r.dirs_kept) for r in steppers)} of {len(steppers)}"
    )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m tools.roles_corpus", description=__doc__)
    parser.add_argument("root", nargs="?", default=str(DEFAULT), help="sigrok-dumps folder")
    args = parser.parse_args(argv)
    rows = evaluate(Path(args.root))
    width = max((len(r.path) for r in rows), default=10)
    for r in rows:
        print(f"{r.verdict:<8} {r.carries:<10} {r.path:<{width}}  {r.text}")
    print(totals(rows))
    return 1 if any(r.verdict == "wrong" for r in rows) else 0


if __name__ == "__main__":
    sys.exit(main())
