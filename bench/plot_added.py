"""Issue 38's ``plot`` row as a before/after pair: the CPU ``check --plot`` adds to the same
``check`` on the tiny capture, by an older tree and by this one, against ``python -c "import
matplotlib.pyplot"``, all five commands interleaved in one loop (CPU from ``wait4``; best and
median; the load at the start and the end).

    .venv/bin/python bench/plot_added.py c5483b7 --runs 9
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile

from before_after import ROOT, interleaved, tree, tree_command

TINY = str(ROOT / "captures/golden/g202-p16-dirhold2-worst.vcd")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("commit")
    ap.add_argument("--runs", type=int, default=9)
    args = ap.parse_args()
    trees = {"before": tree(args.commit), "after": ROOT}
    with tempfile.TemporaryDirectory() as tmp:
        check = ["check", TINY, "--drive", "gecko-g202"]
        cmds = {"pyplot": [sys.executable, "-c", "import matplotlib.pyplot"]}
        for name, path in trees.items():
            cmds[f"{name} check"] = tree_command("wavecheck", path, check)
            cmds[f"{name} plot"] = tree_command("wavecheck", path,
                                                [*check, "--plot", f"{tmp}/{name}.png"])  # fmt: skip
        cpu, load0 = interleaved(cmds, args.runs)
    print(f"check --plot, CPU added (best of {args.runs}, interleaved; load {load0:.1f} -> "
          f"{os.getloadavg()[0]:.1f})")  # fmt: skip
    peer = min(cpu["pyplot"])
    print(f"  import matplotlib.pyplot {peer * 1e3:7.1f} ms best, "
          f"{statistics.median(cpu['pyplot']) * 1e3:7.1f} ms median")  # fmt: skip
    for name in trees:
        plot, base = cpu[f"{name} plot"], cpu[f"{name} check"]
        added = min(plot) - min(base)
        print(f"  {name:6s} check {min(base) * 1e3:7.1f} ms, with --plot {min(plot) * 1e3:7.1f} "
              f"ms: added {added * 1e3:6.1f} ms = {added / peer:.2f}x the peer "
              f"(medians: {(statistics.median(plot) - statistics.median(base)) * 1e3:.1f} ms)")  # fmt: skip


if __name__ == "__main__":
    main()
