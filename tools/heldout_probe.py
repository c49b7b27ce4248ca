"""Run ``wavecheck config`` over a folder of unseen firmware configurations and tabulate.

    .venv/bin/python -m tools.heldout_probe /tmp/heldout                 # the table
    .venv/bin/python -m tools.heldout_probe /tmp/heldout --list          # one line per case too
    .venv/bin/python -m tools.heldout_probe DIR --drive drv8825 --drive tmc2209

The folder has one sub-folder per family, laid out like ``../shared/firmware-corpus`` (the cases
are found with :data:`tools.firmware_corpus.FAMILIES`). Unlike ``tools.firmware_corpus`` this runs
the installed command line, one process per case and drive, as a user would: a case is *read*
(exit 0, 1, 3 or 4 with a JSON report), *refused* (exit 2 with one ``wavecheck: error:`` line,
grouped by its reason without paths and numbers), *crashed* (a traceback or any other exit) or
*hung* (no answer within ``--timeout`` seconds). Exit 1 when a case crashed or hung.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
from collections import Counter
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

from tools.firmware_corpus import FAMILIES, reason

WAVECHECK = Path(sys.executable).with_name("wavecheck")
#: As :data:`tools.firmware_corpus.FAMILIES`, and FluidNC's ``.yml`` files too.
PATTERNS = {**FAMILIES, "fluidnc": "**/*.y*ml"}


def cases(folder: Path) -> Iterator[tuple[str, Path]]:
    """(family, file) of every case under ``folder``, in a stable order."""
    for family, pattern in PATTERNS.items():
        if (folder / family).is_dir():
            for path in sorted((folder / family).glob(pattern)):
                if path.is_file():
                    yield family, path


@dataclass
class Outcome:
    """What one run of ``config`` gave."""

    kind: str
    """``read``, ``refused``, ``crashed`` or ``hung``."""
    detail: str


@dataclass
class Tally:
    """One family's counts for one drive."""

    cases: int = 0
    kinds: Counter[str] = field(default_factory=Counter)
    refused: Counter[str] = field(default_factory=Counter)
    verdicts: Counter[str] = field(default_factory=Counter)
    bad: list[str] = field(default_factory=list)


def run_config(path: Path, drive: str, timeout: float, command: list[str]) -> Outcome:
    """One ``wavecheck config PATH --drive DRIVE --format json`` run, classified."""
    cmd = [*command, "config", str(path), "--drive", drive, "--format", "json"]
    try:
        done = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, check=False)
    except subprocess.TimeoutExpired:
        return Outcome("hung", f"no answer in {timeout:g} s")
    err = done.stderr.strip()
    if "Traceback" in err:
        return Outcome("crashed", err.splitlines()[-1])
    if done.returncode == 2 and err.startswith("wavecheck: error:") and len(err.splitlines()) == 1:
        return Outcome("refused", err.removeprefix("wavecheck: error:").strip())
    if done.returncode in (0, 1, 3, 4):
        try:
            report = json.loads(done.stdout)
        except json.JSONDecodeError:
            return Outcome("crashed", f"exit {done.returncode} without a JSON report")
        axes = ",".join(a["axis"] for a in report["axes"])
        return Outcome("read", f"{report['firmware']} [{axes}] {report['verdict']}")
    return Outcome("crashed", f"exit {done.returncode}: {err[:200]}")


def main(argv: list[str] | None = None) -> int:
    """Print the table (see the module doc)."""
    parser = argparse.ArgumentParser(prog="python -m tools.heldout_probe", description=__doc__)
    parser.add_argument("folder", type=Path, help="one sub-folder per family (klipper, marlin, …)")
    parser.add_argument("--drive", action="append", help="drive ids (default drv8825, tmc2209)")
    parser.add_argument("--timeout", type=float, default=60.0, help="seconds before 'hung'")
    parser.add_argument("--list", action="store_true", help="one line per case and drive too")
    parser.add_argument(
        "--command",
        default=str(WAVECHECK),
        help="the wavecheck to run, split at spaces (default: this venv's; e.g. "
        "'python -m wavecheck' with PYTHONPATH set to an older checkout)",
    )
    args = parser.parse_args(argv)
    drives = args.drive or ["drv8825", "tmc2209"]
    tallies: dict[tuple[str, str], Tally] = {}
    for family, path in cases(args.folder):
        for drive in drives:
            t = tallies.setdefault((family, drive), Tally())
            out = run_config(path, drive, args.timeout, args.command.split())
            t.cases += 1
            t.kinds[out.kind] += 1
            if out.kind == "refused":
                t.refused[reason(out.detail)] += 1
            elif out.kind == "read":
                t.verdicts[out.detail.rsplit(" ", 1)[-1]] += 1
            else:
                t.bad.append(f"{path}: {out.detail}")
            if args.list:
                print(
                    f"{family:9} {drive:8} {path.relative_to(args.folder)}: {out.kind} {out.detail}"
                )
    print(f"{'family':9} {'drive':8} {'cases':>5} {'read':>5} {'refused':>7} {'crashed':>7} "
          f"{'hung':>4}  read by verdict")  # fmt: skip
    for (family, drive), t in tallies.items():
        verdicts = ", ".join(f"{v} {n}" for v, n in sorted(t.verdicts.items()))
        print(f"{family:9} {drive:8} {t.cases:5} {t.kinds['read']:5} {t.kinds['refused']:7} "
              f"{t.kinds['crashed']:7} {t.kinds['hung']:4}  {verdicts}")  # fmt: skip
    for (family, drive), t in tallies.items():
        for why, n in t.refused.most_common():
            print(f"  refused {family} {drive}: {n} x {why}")
        for line in t.bad:
            print(f"  {family} {drive}: {line}")
    return 1 if any(t.bad for t in tallies.values()) else 0


if __name__ == "__main__":
    sys.exit(main())
