"""Every configuration of a firmware corpus read: ``python -m tools.firmware_corpus``.

    .venv/bin/python -m tools.firmware_corpus                       # ../shared/firmware-corpus
    .venv/bin/python -m tools.firmware_corpus --corpus DIR --list   # one line per case too

A *case* is what a user gives ``wavecheck config``: a Klipper ``.cfg``, a Marlin folder's
``Configuration.h``, a LinuxCNC ``.ini``, a Smoothieware ``config``, a grbl dump, an RRF
``config.g``, a FluidNC ``.yaml``. Each is read with :func:`wavecheck.firmware.read_firmware` and
judged against a drive (``leadshine-dm542``); the table gives per family the cases read (by
verdict, and the indeterminate rules by reason), those refused (grouped by the reason, without
paths and numbers) and the ones whose figures differ from
the hand-read table ``tests/wavecheck/firmware/corpus_figures.toml`` (*wrong*; the table's own
entries are the only ones a figure can be wrong against), and the slowest case. Any exception
other than the one-line :class:`~wavecheck.errors.WavecheckError` is a *crash*. Exit 1 when a
case crashed, was wrong or took more than ``--max-seconds``.
"""

from __future__ import annotations

import argparse
import re
import sys
import time
import tomllib
from collections import Counter
from collections.abc import Iterator
from dataclasses import dataclass, field
from fractions import Fraction
from pathlib import Path
from typing import Any

from wavecheck.errors import WavecheckError

ROOT = Path(__file__).resolve().parent.parent
CORPUS = ROOT.parent / "shared" / "firmware-corpus"
TABLE = ROOT / "tests" / "wavecheck" / "firmware" / "corpus_figures.toml"
#: Family folder → how its cases are found.
FAMILIES: dict[str, str] = {
    "klipper": "*.cfg",
    "marlin": "**/Configuration.h",
    "linuxcnc": "**/*.ini",
    "smoothie": "**/*config*",
    "grbl": "**/*",
    "rrf": "**/config.g",
    "fluidnc": "**/*.yaml",
}
FIGURES = ("pulse_ns", "idle_ns", "dir_setup_ns", "dir_hold_ns", "dir_hold_trailing_ns",
           "max_rate_hz")  # fmt: skip


def cases(corpus: Path) -> Iterator[tuple[str, Path]]:
    """(family, file) of every case under ``corpus``, in a stable order."""
    for family, pattern in FAMILIES.items():
        folder = corpus / family
        if folder.is_dir():
            for path in sorted(folder.glob(pattern)):
                if path.is_file():
                    yield family, path


def reason(message: str) -> str:
    """A refusal's reason without its place, paths and numbers (to group refusals)."""
    text = re.sub(r"^\S+?:(\d+:)?\s*", "", message)
    text = re.sub(r"(/[\w.+\-]+)+/?", "…", text)
    text = re.sub(r"\d+(\.\d+)?", "N", text)
    text = re.sub(r"\(([^()]|\([^()]*\))*\)", "(…)", text)
    return text[:90]


def _why(note: str) -> str:
    """An indeterminate rule's reason, short: what decides it (grouping key)."""
    if "not enforced by the firmware" in note:
        return "not enforced: " + reason(note.split("); ", 1)[-1])[:60]
    return reason(note)[:70]


def _value(fig: Any) -> Fraction | None:
    return None if fig is None else fig.value


def actual(cfg: Any, axis: str) -> dict[str, object]:
    """The figures of ``axis`` as the table names them."""
    g = cfg.axis(axis)
    return {
        "pulse_ns": _value(g.pulse),
        "idle_ns": _value(g.idle),
        "dir_setup_ns": _value(g.dir_setup),
        "dir_hold_ns": _value(g.dir_hold),
        "dir_hold_trailing_ns": _value(g.dir_hold_trailing),
        "max_rate_hz": _value(g.max_rate),
        "pulse_level": g.pulse_level,
        "both_edges": g.both_edges,
        "dir_inverted": g.dir_inverted,
    }


def expected_value(text: object) -> object:
    """A table value: ``"unknown"`` → None, ``"375/4"`` → Fraction, others as written."""
    if text == "unknown":
        return None
    if isinstance(text, str):
        return Fraction(text)
    return text


def load_table(path: Path = TABLE) -> list[dict[str, Any]]:
    """The hand-read expectations (see ``corpus_figures.toml``)."""
    with path.open("rb") as fh:
        cases_: list[dict[str, Any]] = tomllib.load(fh)["case"]
    return cases_


def differences(case: dict[str, Any], corpus: Path) -> list[str]:
    """What differs between the table's ``case`` and what wavecheck reads (empty: right)."""
    from wavecheck.firmware import read_firmware

    path = corpus / case["file"]
    try:
        cfg = read_firmware(path)
    except WavecheckError as err:
        if "refused" in case and case["refused"] in str(err):
            return []
        return [f"refused: {err}"]
    if "refused" in case:
        return [f"read, but the table expects a refusal containing {case['refused']!r}"]
    out = []
    if "firmware" in case and cfg.firmware != case["firmware"]:
        out.append(f"firmware {cfg.firmware} != {case['firmware']}")
    if "axes" in case and list(cfg.axis_names) != case["axes"]:
        out.append(f"axes {list(cfg.axis_names)} != {case['axes']}")
    for axis, want in case.get("figures", {}).items():
        try:
            got = actual(cfg, axis)
        except KeyError as err:
            out.append(str(err))
            continue
        for key, text in want.items():
            if got[key] != expected_value(text):
                out.append(f"{axis} {key}: read {got[key]}, expected {text}")
    return out


@dataclass
class Tally:
    """One family's counts."""

    cases: int = 0
    read: int = 0
    refused: Counter[str] = field(default_factory=Counter)
    crashed: list[str] = field(default_factory=list)
    checked: int = 0
    wrong: list[str] = field(default_factory=list)
    verdicts: Counter[str] = field(default_factory=Counter)
    """Cases per overall verdict against the drive."""
    indeterminate: Counter[str] = field(default_factory=Counter)
    """Indeterminate rules (axis x rule) by reason, without paths and numbers."""
    slowest: tuple[float, str] = (0.0, "")


def run(corpus: Path, listing: bool = False) -> dict[str, Tally]:
    """Read every case; the tallies per family."""
    from wavecheck.drives.library import load_drive
    from wavecheck.firmware import read_firmware
    from wavecheck.firmware.evaluate import evaluate_config

    drive = load_drive("leadshine-dm542")
    tallies: dict[str, Tally] = {}
    for family, path in cases(corpus):
        t = tallies.setdefault(family, Tally())
        t.cases += 1
        start = time.monotonic()
        try:
            cfg = read_firmware(path)
            result = evaluate_config(cfg, [(a, drive) for a in cfg.axes])
            t.read += 1
            t.verdicts[result.verdict] += 1
            for pair in result.pairs:
                for row in pair.rows:
                    if row.verdict == "indeterminate":
                        t.indeterminate[_why(row.note)] += 1
            line = f"read {cfg.firmware}, {len(cfg.axes)} axes, {result.verdict}"
        except WavecheckError as err:
            t.refused[reason(str(err))] += 1
            line = f"refused: {err}"
        except Exception as err:  # noqa: BLE001 - the point is to count them
            t.crashed.append(f"{path}: {type(err).__name__}: {err}")
            line = f"CRASH {type(err).__name__}: {err}"
        took = time.monotonic() - start
        if took > t.slowest[0]:
            t.slowest = (took, str(path.relative_to(corpus)))
        if listing:
            print(f"{family:9} {path.relative_to(corpus)}  {took:.2f}s  {line}")
    if TABLE.is_file():
        for case in load_table():
            family = case["file"].split("/")[0]
            if family not in tallies:
                continue
            t = tallies[family]
            t.checked += 1
            wrong = differences(case, corpus)
            if wrong:
                t.wrong.append(f"{case['file']}: {'; '.join(wrong)}")
    return tallies


def main(argv: list[str] | None = None) -> int:
    """Print the table (see the module doc)."""
    parser = argparse.ArgumentParser(prog="python -m tools.firmware_corpus", description=__doc__)
    parser.add_argument("--corpus", type=Path, default=CORPUS, help="the corpus folder")
    parser.add_argument("--list", action="store_true", help="one line per case too")
    parser.add_argument("--max-seconds", type=float, default=5.0, help="slowest case allowed")
    args = parser.parse_args(argv)
    tallies = run(args.corpus, args.list)
    head = (
        f"{'family':9} {'cases':>5} {'read':>5} {'refused':>7} {'crashed':>7} {'wrong':>9}  slowest"
    )
    print(head)
    bad = False
    for family, t in tallies.items():
        refused = sum(t.refused.values())
        print(f"{family:9} {t.cases:5} {t.read:5} {refused:7} {len(t.crashed):7} "
              f"{len(t.wrong):3} of {t.checked:3}  {t.slowest[0]:.2f} s {t.slowest[1]}")  # fmt: skip
        bad |= bool(t.crashed or t.wrong) or t.slowest[0] > args.max_seconds
    total = sum(t.cases for t in tallies.values())
    print(f"{'total':9} {total:5} {sum(t.read for t in tallies.values()):5} "
          f"{sum(sum(t.refused.values()) for t in tallies.values()):7} "
          f"{sum(len(t.crashed) for t in tallies.values()):7} "
          f"{sum(len(t.wrong) for t in tallies.values()):3} of "
          f"{sum(t.checked for t in tallies.values()):3}")  # fmt: skip
    for family, t in tallies.items():
        right = t.checked - len(t.wrong)
        verdicts = ", ".join(f"{v} {n}" for v, n in sorted(t.verdicts.items()))
        print(f"  {family}: table cases right {right} of {t.checked}; read cases by verdict: "
              f"{verdicts}")  # fmt: skip
        for why, n in t.indeterminate.most_common(6):
            print(f"    indeterminate rules {n} x {why}")
    for family, t in tallies.items():
        for why, n in t.refused.most_common():
            print(f"  refused {family}: {n} x {why}")
        for line in t.crashed + t.wrong:
            print(f"  {family}: {line}")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
