"""Speed work changes no result: stdout, stderr and exit code of ``wavecheck`` commands run by an
older tree (``git archive COMMIT``, as ``before_after.py`` unpacks it) and by this one, compared
byte for byte (each tree's own path written as ``TREE``; with ``-j`` the error lines on stderr,
which print as the captures finish, are compared sorted).

    .venv/bin/python bench/same_output.py c5483b7            # the set below
    .venv/bin/python bench/same_output.py c5483b7 --every 3  # + every 3rd real capture ≤ 3 MB

The set: every golden VCD (its drive from its .toml, else gecko-g202) as text and JSON; the grbl
capture mapped, as text, JSON and JUnit, with ``--firmware`` and ``--base-period``, and unmapped;
a bad drive; the golden VCDs in one run with ``-j 2`` (text, JSON); ``drives`` with and without an id, as text and JSON; ``info`` and ``measure``;
``--help`` (alone, before and after a command), ``--version``, usage errors, an unknown command; and ``check FILE --drive gecko-g202`` on real captures.
"""

from __future__ import annotations

import argparse
import difflib
import subprocess
import sys
import tomllib
from pathlib import Path

from before_after import ROOT, tree

SHARED = ROOT.parent / "shared" / "captures"
GRBL = str(ROOT / "captures/real/grbl_cnc_1.sr")
TINY = str(ROOT / "captures/golden/g202-p16-dirhold2-worst.vcd")
MAP = ["--drive", "leadshine-dm542", "--map", "step=STEP (Y axis),dir=EN"]


def commands(every: int) -> list[list[str]]:
    """The argument lists compared."""
    out: list[list[str]] = []
    for vcd in sorted((ROOT / "captures/golden").glob("*.vcd")):
        meta = tomllib.loads(vcd.with_suffix(".toml").read_text())
        drive = meta.get("wavecheck", {}).get("drive", "gecko-g202")
        for fmt in ("text", "json"):
            out.append(["check", str(vcd), "--drive", drive, "--format", fmt])
    out += [["check", GRBL, *MAP, "--format", f] for f in ("text", "json", "junit")]
    out += [
        ["check", GRBL, *MAP, "--firmware", str(ROOT / "captures/firmware/grbl/settings.md")],
        ["check", GRBL, *MAP, "--base-period", "25us"],
        ["check", GRBL, "--drive", "leadshine-dm542"],
        ["check", TINY, "--drive", "no-such-drive"],
        ["check", str(ROOT / "captures/golden/*.vcd"), "--drive", "gecko-g202", "-j", "2"],
        [
            "check",
            str(ROOT / "captures/golden/*.vcd"),
            "--drive",
            "gecko-g202",
            "-j",
            "2",
            "--format",
            "json",
        ],
        ["drives"],
        ["drives", "--format", "json"],
        ["drives", "gecko-g202"],
        ["drives", "gecko-g202", "--format", "json"],
        ["info", TINY],
        ["measure", TINY],
        ["--help"],
        ["--help", "check"],
        ["--version"],
        ["check", "--help"],
        ["check"],
        ["check", TINY, "--drive", "gecko-g202", "--format", "nope"],
        ["drives", "--bogus"],
        ["no-such-command"],
    ]
    if every:
        real = sorted(
            p
            for p in SHARED.rglob("*")
            if p.suffix in (".sr", ".vcd") and p.stat().st_size <= 3 * 2**20
        )
        out += [["check", str(p), "--drive", "gecko-g202"] for p in real[::every]]
    return out


def run(root: Path, argv: list[str]) -> tuple[int, str, str]:
    # main() with no argv, as the console script calls it (the collector tuned: as_program)
    code = "import sys; sys.path.insert(0, sys.argv[1]); from wavecheck.cli import main; " \
           "sys.argv = ['wavecheck', *sys.argv[2:]]; sys.exit(main())"  # fmt: skip
    p = subprocess.run([sys.executable, "-c", code, str(root), *argv], capture_output=True,
                       text=True, cwd=ROOT)  # fmt: skip
    out = [p.stdout, p.stderr]
    for path in (str(root), str(ROOT)):  # the tree run, and the files named from this checkout
        out = [t.replace(path, "TREE") for t in out]
    return p.returncode, out[0], out[1]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("commit")
    ap.add_argument("--every", type=int, default=0, help="also every Nth real capture ≤ 3 MB")
    ap.add_argument("-v", "--verbose", action="store_true")
    args = ap.parse_args()
    old = tree(args.commit)
    cmds = commands(args.every)
    differ = []
    codes: dict[int, int] = {}
    for argv in cmds:
        before, after = run(old, argv), run(ROOT, argv)
        if "-j" in argv:  # error lines print as captures finish, in any order: compare them sorted
            before, after = (
                (code, out, "".join(sorted(err.splitlines(keepends=True))))
                for code, out, err in (before, after)
            )
        codes[after[0]] = codes.get(after[0], 0) + 1
        if before != after:
            differ.append(argv)
            print("DIFFERS:", " ".join(argv), f"(exit {before[0]} -> {after[0]})")
            for name, b, a in (("stdout", before[1], after[1]), ("stderr", before[2], after[2])):
                lines = difflib.unified_diff(b.splitlines(), a.splitlines(), name, name, n=1)
                print("\n".join(list(lines)[:20]))
        elif args.verbose:
            print(f"same (exit {after[0]}):", " ".join(argv), after[2].strip()[:100])
    shown = ", ".join(f"exit {c}: {n}" for c, n in sorted(codes.items()))
    print(f"{len(cmds) - len(differ)} of {len(cmds)} commands identical to {args.commit} ({shown})")
    sys.exit(1 if differ else 0)


if __name__ == "__main__":
    main()
