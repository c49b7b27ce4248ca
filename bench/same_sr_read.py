"""Container work changes no result: ``read_sr`` of every real ``.sr`` (``../shared/captures``
and ``captures/``) by an older tree and by this one: rate, length, resolution, notes, each
channel's name, index, initial level and edges (SHA-1), or the error, compared line by line.

    .venv/bin/python bench/same_sr_read.py 18c3145
"""

from __future__ import annotations

import argparse
import subprocess
import sys

from before_after import ROOT, tree

DUMP = """
import hashlib, json, sys
sys.path.insert(0, sys.argv[1])
from wavecheck.capture.sr import read_sr
from wavecheck.errors import CaptureError
for p in sys.argv[2:]:
    try:
        c = read_sr(p, require_rate=False)
        out = {"rate": str(c.samplerate_hz), "end": c.end, "notes": c.notes,
               "res": c.resolution_ticks, "channels": [
                   (h.name, h.index, h.initial, len(h.edges),
                    hashlib.sha1(h.edges.tobytes()).hexdigest()) for h in c.channels]}
    except CaptureError as err:
        out = {"error": str(err)}
    print(p, json.dumps(out, sort_keys=True))
"""


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("commit")
    args = ap.parse_args()
    files = sorted({*map(str, (ROOT.parent / "shared/captures").rglob("*.sr")),
                    *map(str, (ROOT / "captures").rglob("*.sr"))})  # fmt: skip
    runs = {}
    for name, where in (("before", tree(args.commit)), ("after", ROOT)):
        runs[name] = subprocess.run([sys.executable, "-c", DUMP, str(where), *files],
                                    capture_output=True, text=True, check=True).stdout.splitlines()  # fmt: skip
    same = sum(a == b for a, b in zip(runs["before"], runs["after"], strict=True))
    refused = sum('"error"' in line for line in runs["after"])
    for a, b in zip(runs["before"], runs["after"], strict=True):
        if a != b:
            print(f"DIFFERS\n  before {a[:300]}\n  after  {b[:300]}")
    print(f"{same} of {len(files)} .sr files read the same as {args.commit} "
          f"({len(files) - refused} read, {refused} refused)")  # fmt: skip
    sys.exit(0 if same == len(files) else 1)


if __name__ == "__main__":
    main()
