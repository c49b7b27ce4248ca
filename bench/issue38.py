"""Issue 38's rows of ``make bench`` (sections ``stepgen120``, ``plot``, ``fst``; the others of the
issue are rows of sections ``stepgen``, ``startup``, ``sr`` and ``vcd``). Each command runs in its
own process under ``/usr/bin/time -v``, interleaved with its peer; CPU is user + sys (children
included), best of the runs (the least disturbed by other users of the 2 CPUs).

- ``stepgen120``: ``stepgen simulate --command sine_120s.csv … --duration 120s -o OUT.vcd``
  against real time [≥ 100×];
- ``plot``: ``check tiny.vcd --plot OUT.png`` less the same ``check`` without ``--plot``, against
  ``python -c "import matplotlib.pyplot"`` [CPU added ≤ 1.5×];
- ``fst``: ``check`` of an FST written by Icarus Verilog against ``check`` of the VCD the same
  simulation wrote (``bench/fst_read.py``'s test bench), same steps and verdict [CPU ≤ 1.0×].
"""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

from bench.gen import ensure  # noqa: E402
from bench.harness import _cpu, figure, load1, sh, timed  # noqa: E402

PY = sys.executable
WAVECHECK = str(Path(PY).with_name("wavecheck"))
STEPGEN = str(Path(PY).with_name("stepgen"))
TINY_VCD = HERE.parent / "captures/golden/g202-p16-dirhold2-worst.vcd"
#: the goals of issue 38
STEPGEN_LONG_GOAL = 100.0
PLOT_GOAL = 1.5
FST_GOAL = 1.0
#: the options that go with the 120 s sine (as bench/stepgen_cli.py's, without latency)
LONG_OPTIONS = ["--position-scale", "1000", "--maxvel", "15", "--maxaccel", "100"]


def _interleaved(cmds: dict[str, list[str]], runs: int) -> tuple[dict[str, list[float]], float]:
    """CPU seconds of each command's runs, interleaved; the highest load seen."""
    cpu: dict[str, list[float]] = {k: [] for k in cmds}
    loads = []
    for _ in range(runs):
        loads.append(load1())
        for k, c in cmds.items():
            t = timed(c)
            if t["rc"] not in (0, 1):
                raise SystemExit(f"{sh(c)}: exit {t['rc']}: {t['stderr'][-300:]}")
            cpu[k].append(_cpu(t))
    return cpu, max(loads)


def bench_stepgen_long(quick: bool, runs: int) -> dict[str, Any]:
    """``stepgen simulate`` of a 120 s sine with a VCD out, as a process, against real time."""
    key, seconds = ("cmd20s", 20) if quick else ("cmd120s", 120)
    csv = ensure(key)
    with tempfile.TemporaryDirectory() as tmp:
        cmd = [STEPGEN, "simulate", "--command", str(csv), *LONG_OPTIONS,
               "--duration", f"{seconds}s", "-o", f"{tmp}/out.vcd", "-q"]  # fmt: skip
        numpy = [PY, "-c", "import numpy"]
        print(f"  $ {sh(cmd)}\n  $ {sh(numpy)}")
        cpu, load = _interleaved({"stepgen": cmd, "numpy": numpy}, max(3, runs))
        rss = timed(cmd)["max_rss_mb"]
        size = Path(f"{tmp}/out.vcd").stat().st_size
    best = min(cpu["stepgen"])
    x = seconds / best
    print(f"  {seconds} s simulated, VCD {size / 1e6:.1f} MB: {best:.2f} s CPU (runs "
          f"{min(cpu['stepgen']):.2f}–{max(cpu['stepgen']):.2f}), peak RSS {rss:.0f} MB; import "
          f"numpy {min(cpu['numpy']):.2f} s")  # fmt: skip
    ok = x >= STEPGEN_LONG_GOAL
    figure(f"`stepgen simulate` {seconds} s + VCD, whole process", f"{x:.0f}× real time "
           f"({best:.2f} s cpu, {rss:.0f} MB)", f"≥ {STEPGEN_LONG_GOAL:g}×", ok,
           f"real time {seconds} s; import numpy {min(cpu['numpy']):.2f} s", load)  # fmt: skip
    return {"command": sh(cmd), "cpu_s": cpu, "realtime": x, "rss_mb": rss, "load": load,
            "target": ok}  # fmt: skip


def bench_plot(runs: int) -> dict[str, Any]:
    """CPU ``--plot`` adds to a check of a tiny capture, against importing matplotlib.pyplot."""
    with tempfile.TemporaryDirectory() as tmp:
        base = [WAVECHECK, "check", str(TINY_VCD), "--drive", "gecko-g202"]
        cmds = {
            "plot": [*base, "--plot", f"{tmp}/out.png"],
            "check": base,
            "pyplot": [PY, "-c", "import matplotlib.pyplot"],
        }
        for c in cmds.values():
            print(f"  $ {sh(c)}")
        cpu, load = _interleaved(cmds, max(5, runs))
        size = Path(f"{tmp}/out.png").stat().st_size
    best = {k: min(v) for k, v in cpu.items()}
    added = best["plot"] - best["check"]
    ratio = added / best["pyplot"]
    print(f"  check --plot {best['plot']:.2f} s, check {best['check']:.2f} s, import "
          f"matplotlib.pyplot {best['pyplot']:.2f} s CPU (best of {max(5, runs)}); PNG {size} bytes")  # fmt: skip
    ok = ratio <= PLOT_GOAL
    figure("`check --plot` tiny capture, CPU added vs `import matplotlib.pyplot`",
           f"{ratio:.2f}× ({added:.2f} s added)", f"≤ {PLOT_GOAL:g}×", ok,
           f"import matplotlib.pyplot {best['pyplot']:.2f} s", load)  # fmt: skip
    return {"cpu_s": cpu, "ratio": ratio, "load": load, "target": ok}


def _fst_pair(tmp: Path, steps: int) -> tuple[Path, Path]:
    """The VCD and FST of one Icarus Verilog run of ``bench/fst_read.py``'s test bench."""
    from bench.fst_read import TB

    (tmp / "tb.v").write_text(TB.replace("STEPS", str(steps)))
    for ext, flag in (("vcd", []), ("fst", ["-fst"])):
        subprocess.run(["iverilog", f'-DDUMP="{ext}.{ext}"', "-o", f"{ext}.vvp", "tb.v"],
                       cwd=tmp, check=True)  # fmt: skip
        subprocess.run(["vvp", "-n", f"{ext}.vvp", *flag], cwd=tmp, check=True,
                       capture_output=True)  # fmt: skip
    return tmp / "vcd.vcd", tmp / "fst.fst"


#: ``wavecheck check`` with the native FST reader switched off: the fst2vcd route (or, without
#: fst2vcd on PATH, pywellen's), as before round 6 (bench/README.md)
OLD_FST_ROUTE = (
    "import sys, wavecheck.capture.fst as f\n"
    "def off(*a, **k): raise f.FstUnsupported('bench: the old route')\n"
    "f.FstFile.__init__ = off\n"
    "from wavecheck.cli import main\n"
    "sys.argv[0] = 'wavecheck'\n"
    "sys.exit(main())"
)


def bench_fst(quick: bool, runs: int) -> dict[str, Any]:
    """``check`` of an FST against ``check`` of the VCD of the same simulation (CPU): the native
    reader (the default), and the routes before it (fst2vcd's included, pywellen's)."""
    if not shutil.which("iverilog"):
        print("  !! iverilog missing: section skipped")
        return {"target": False, "error": "iverilog missing"}
    steps = 50_000 if quick else 500_000
    with tempfile.TemporaryDirectory() as d:
        tmp = Path(d)
        vcd, fst = _fst_pair(tmp, steps)
        opts = ["--drive", "gecko-g202", "--map", "step=step,dir=dir", "-q"]
        old = [PY, "-c", OLD_FST_ROUTE, "check", str(fst), *opts]
        no_fst2vcd = ["env", f"PATH={Path(PY).parent}"]  # then the old route is pywellen's
        cmds = {"fst": [WAVECHECK, "check", str(fst), *opts],
                "vcd": [WAVECHECK, "check", str(vcd), *opts],
                "fst_fst2vcd": old, "fst_pywellen": [*no_fst2vcd, *old]}  # fmt: skip
        for c in cmds.values():
            print(f"  $ {sh(c)}")
        outs = {}
        for k, c in cmds.items():
            outs[k] = subprocess.run(
                [*c[:-1], "--format", "json"], capture_output=True, text=True
            ).stdout
        cpu, load = _interleaved(cmds, max(3, runs))
        sizes = (vcd.stat().st_size, fst.stat().st_size)

    def report(k: str) -> str:  # what the check found: all of the JSON report but the capture
        doc = json.loads(outs[k])
        return json.dumps({key: v for key, v in doc.items() if key != "capture"}, sort_keys=True)

    same = len({report(k) for k in cmds}) == 1
    best = {k: min(v) for k, v in cpu.items()}
    ratio = best["fst"] / best["vcd"]
    print(f"  {steps} steps; VCD {sizes[0] / 1e6:.1f} MB, FST {sizes[1] / 1e6:.2f} MB: check FST "
          f"{best['fst']:.2f} s (fst2vcd {best['fst_fst2vcd']:.2f} s, pywellen "
          f"{best['fst_pywellen']:.2f} s), VCD {best['vcd']:.2f} s CPU (best of {max(3, runs)}); "
          f"same report but path and format: {same}")  # fmt: skip
    ok = ratio <= FST_GOAL and same
    figure("`check` FST vs the same run's VCD (CPU)", f"{ratio:.2f}× ({best['fst']:.2f} s; "
           f"{'same report' if same else 'REPORTS DIFFER'})", f"≤ {FST_GOAL:g}×", ok,
           f"VCD {best['vcd']:.2f} s", load)  # fmt: skip
    for k, name in (("fst_fst2vcd", "fst2vcd"), ("fst_pywellen", "pywellen")):
        print(f"  (the route before round 6, through {name}: {best[k] / best['vcd']:.2f}× the VCD)")
    return {"cpu_s": cpu, "ratio": ratio, "same": same, "load": load, "target": ok}
