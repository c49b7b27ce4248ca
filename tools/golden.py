"""Golden VCDs made by ``stepgen simulate``: ``python -m tools.golden --write|--check``.

A development tool run from a source checkout (``make golden``, ``make golden-check``), not part
of the installed package. Each scenario in :data:`SCENARIOS` is a ``stepgen simulate`` command
line. ``--write`` regenerates ``NAME.vcd`` and ``NAME.toml`` in the golden folder (what the file
must show: steps, final counts, edges per pin, and the expected ``wavecheck check`` verdict
against a named drive, with the reason). ``--check`` regenerates into a temporary folder and
fails if any file differs byte for byte; then, if ``wavecheck check`` is available, runs it on
each golden VCD that names a drive and fails if its verdict differs from the expected one.

The golden folder is ``--golden-dir`` (default :data:`GOLDEN`, ``captures/golden`` of the
checkout this file is in); the scenarios' command files (``reversal-p20.csv`` …) are read from it.
"""

from __future__ import annotations

import argparse
import filecmp
import re
import subprocess
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

from stepgen.cli.simulate import build_config, build_motion, register
from stepgen.lateness import parse_latency
from stepgen.simulate import Trace, n_periods_for, simulate
from stepgen.vcdout import write_vcd
from wavecheck.units import time_ns
from wavecheck.verdict import verdict_of_exit

#: The source checkout this tool belongs to (tools/ is one level below it).
ROOT = Path(__file__).resolve().parent.parent
#: The golden folder unless ``--golden-dir`` names another.
GOLDEN = ROOT / "captures" / "golden"


@dataclass(frozen=True)
class Scenario:
    """One golden file: its command line, the drive to check against and the expected verdict."""

    name: str
    args: str
    drive: str = ""
    verdict: str = ""
    why: str = ""


SCENARIOS: tuple[Scenario, ...] = (
    Scenario(
        "stepgen0",
        "--base-period 100us --servo-period 100us --position-scale 32000 --maxvel 0.15 "
        "--maxaccel 2 --position 0.04 --periods 3500",
        "gecko-g202",
        "pass",
        "LinuxCNC tests/stepgen.0: 1280 single-period (100 us) pulses, no reversal",
    ),
    Scenario(
        "stepgen1-quadrature",
        "--type 2 --base-period 100us --servo-period 100us --position-scale 32000 --maxvel 0.15 "
        "--maxaccel 2 --position 0.04 --periods 3500",
        why="LinuxCNC tests/stepgen.1: quadrature decodes to counts at every period",
    ),
    Scenario(
        "g202-p20-worst-dirhold",
        "--base-period 20us --servo-period 1ms --mode velocity --steplen 20us --stepspace 20us "
        "--dirhold 20us --dirsetup 20us --command {golden}/reversal-p20.csv --duration 500ms "
        "--latency worst:11us:dir_hold --active-edge falling",
        "gecko-g202",
        "fail",
        "seed G202 story: DIR hold from the falling edge = dirhold*P - J = 20 - 11 = 9 us < 20 us",
    ),
    Scenario(
        "g202-p16-dirhold2-worst",
        "--base-period 16us --servo-period 1008us --mode velocity --steplen 16us --stepspace 16us "
        "--dirhold 32us --dirsetup 16us --command {golden}/reversal-p16.csv --duration 500ms "
        "--latency worst:11us:dir_hold --active-edge falling",
        "gecko-g202",
        "pass",
        "seed G202 story: dirhold 2 periods at 16 us: 2*16 - 11 = 21 us >= 20 us",
    ),
    Scenario(
        "xylotex-dirsetup-zero",
        "--base-period 25us --servo-period 1ms --mode velocity --steplen 25us --stepspace 25us "
        "--dirhold 25us --dirsetup 25us --command {golden}/reversal-p25.csv --duration 1010ms",
        "xylotex",
        "fail",
        "reference 2.4 case 1 (LinuxCNC #2332): DIR flips and STEP rises in the same period, setup 0 < 200 ns",
    ),
    Scenario(
        "a4988-spike",
        "--base-period 25us --servo-period 1ms --mode velocity --position-scale 1000 --velocity 4 "
        "--duration 200ms --latency spike:300us@50ms",
        "a4988",
        "",
        "seed: every 64 s a 300 us latency (here every 50 ms); overdue invocations catch up 1 us apart",
    ),
    Scenario(
        "updown-uniform",
        "--type 1 --base-period 25us --servo-period 1ms --position-scale 1000 --maxvel 8 --maxaccel 400 "
        "--move '0.05, pause 10ms, 0' --latency uniform:8us --seed 7",
        why="up/down pulses with a reversal under random latency",
    ),
    Scenario(
        "user-type15-velocity",
        "--type 15 --user-step-type 1,3,2,6,4,5 --base-period 50us --servo-period 1ms --mode velocity "
        "--position-scale 200 --maxaccel 50 --velocity 10 --duration 300ms",
        why="user step table (3-phase half step) in velocity mode",
    ),
)


def command_files() -> list[str]:
    """The files the scenarios read from the golden folder (``{golden}/NAME``)."""
    return sorted({m for sc in SCENARIOS for m in re.findall(r"\{golden\}/(\S+)", sc.args)})


def _parse(args: str, golden: Path) -> argparse.Namespace:
    import shlex

    parser = argparse.ArgumentParser(prog="stepgen")
    sub = parser.add_subparsers()
    register(sub)
    return parser.parse_args(
        ["simulate", *shlex.split(args.format(golden=golden)), "-o", "x.vcd", "-q"]
    )


def _trace(args: argparse.Namespace) -> Trace:
    """Simulate what the parsed ``stepgen simulate`` command line asks for."""
    cfg = build_config(args)
    motion = build_motion(args, cfg)
    if args.periods is not None:
        n = args.periods
    elif args.duration is not None:
        n = n_periods_for(cfg, int(time_ns(args.duration, default_unit="ns")))
    else:
        dur = motion.natural_duration_s
        assert dur is not None
        n = n_periods_for(cfg, round(dur * 1e9))
    return simulate(
        cfg,
        motion,
        parse_latency(args.latency),
        n_periods=n,
        seed=args.seed,
        active_edge=args.active_edge,
        catchup_ns=int(time_ns(args.catchup, default_unit="ns")),
    )


def _expectations(sc: Scenario, trace: Trace) -> str:
    """``NAME.toml``: the command, why, what the trace shows and the expected verdict."""
    command = f"stepgen simulate {sc.args.format(golden='captures/golden')} -o {sc.name}.vcd"
    lines = [
        "# golden stepgen trace; regenerate with: make golden (python -m tools.golden --write)",
        f'command = "{command}"',
        f'why = "{sc.why}"',
        "",
        "[expect]",
        f"periods = {trace.n_periods}",
        f"steps = {trace.steps}",
        f"final_counts = {trace.final_counts}",
        f"end_ns = {trace.end_ns}",
    ]
    lines += [f'edges."{pin}" = {len(trace.edges[pin])}' for pin in trace.pins]
    if sc.drive:
        lines += ["", "[wavecheck]", f'drive = "{sc.drive}"', f'verdict = "{sc.verdict or "pass"}"']
    return "\n".join(lines) + "\n"


def generate(sc: Scenario, folder: Path, golden: Path = GOLDEN) -> None:
    """Write ``NAME.vcd`` and ``NAME.toml`` for one scenario into ``folder``; the scenario's
    command files are read from ``golden``."""
    trace = _trace(_parse(sc.args, golden))
    write_vcd(trace, folder / f"{sc.name}.vcd")
    (folder / f"{sc.name}.toml").write_text(_expectations(sc, trace), encoding="utf-8")


def wavecheck_verdict(vcd: Path, drive: str) -> str | None:
    """Run ``wavecheck check`` on ``vcd``; its verdict, or None if the checker is not available."""
    proc = subprocess.run(
        [sys.executable, "-m", "wavecheck", "check", str(vcd), "--drive", drive],
        capture_output=True,
        text=True,
        check=False,
    )
    if proc.returncode == 2 and "invalid choice" in proc.stderr:
        return None
    verdict = verdict_of_exit(proc.returncode)
    return verdict or f"error (exit {proc.returncode}: {proc.stderr.strip()[:200]})"


def write(golden: Path) -> None:
    """Regenerate every scenario into ``golden``."""
    golden.mkdir(parents=True, exist_ok=True)
    for sc in SCENARIOS:
        generate(sc, golden, golden)
        print(f"wrote {golden / sc.name}.vcd")


def differences(golden: Path) -> list[str]:
    """Regenerate every scenario into a temporary folder; the golden files that differ."""
    problems = []
    with tempfile.TemporaryDirectory() as tmp:
        for sc in SCENARIOS:
            generate(sc, Path(tmp), golden)
            for ext in ("vcd", "toml"):
                ref = golden / f"{sc.name}.{ext}"
                fresh = Path(tmp) / f"{sc.name}.{ext}"
                if not ref.exists() or not filecmp.cmp(ref, fresh, shallow=False):
                    problems.append(
                        f"{ref}: differs from a fresh run (run make golden and review the diff)"
                    )
    return problems


def verdict_problems(golden: Path) -> list[str]:
    """Run ``wavecheck check`` on every golden VCD that names a drive; the unexpected verdicts."""
    problems = []
    for sc in SCENARIOS:
        if not sc.drive:
            continue
        expected = sc.verdict or "pass"
        got = wavecheck_verdict(golden / f"{sc.name}.vcd", sc.drive)
        if got is None:
            print(
                f"{sc.name}: wavecheck check not available; expected verdict {expected} not verified"
            )
        elif got != expected:
            problems.append(
                f"{sc.name}.vcd: wavecheck check --drive {sc.drive} says {got}, expected {expected} ({sc.why})"
            )
        else:
            print(f"{sc.name}: wavecheck check --drive {sc.drive}: {got} as expected")
    return problems


def main(argv: list[str] | None = None) -> int:
    """``--write`` regenerates the golden folder; ``--check`` compares and runs wavecheck."""
    ap = argparse.ArgumentParser(prog="python -m tools.golden", description=__doc__)
    g = ap.add_mutually_exclusive_group(required=True)
    g.add_argument("--write", action="store_true")
    g.add_argument("--check", action="store_true")
    ap.add_argument(
        "--golden-dir",
        type=Path,
        default=GOLDEN,
        metavar="DIR",
        help=f"the golden traces (default {GOLDEN})",
    )
    args = ap.parse_args(argv)
    golden: Path = args.golden_dir.resolve()
    missing = [f for f in command_files() if not (golden / f).is_file()]
    if missing:
        print(f"golden: {golden} lacks the command files {', '.join(missing)}", file=sys.stderr)
        return 2
    if args.write:
        write(golden)
        problems = []
    else:
        problems = differences(golden)
    problems += verdict_problems(golden)
    for p in problems:
        print(f"golden: {p}", file=sys.stderr)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
