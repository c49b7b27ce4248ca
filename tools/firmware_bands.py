"""What the bands of uncertain figures change: ``python -m tools.firmware_bands``.

    .venv/bin/python -m tools.firmware_bands                    # ../shared/firmware-corpus
    .venv/bin/python -m tools.firmware_bands --list 20          # and 20 changed verdicts

Every case of the corpus (:func:`tools.firmware_corpus.cases`) is judged against a few common
drives (:data:`DRIVES`) twice: as read, and with every figure's band taken away
(:attr:`~wavecheck.firmware.guarantee.Guaranteed.short_by` = 0, the figure judged at face value
as before the bands). The table counts, per family, the rule verdicts each way and how many the
band turned from PASS or FAIL to indeterminate (a band can do nothing else: the value itself
still decides a FAIL). ``--list N`` prints the first N changed verdicts (case, axis, drive,
rule, the note), for a hand audit.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from collections import Counter
from fractions import Fraction
from pathlib import Path

from tools.firmware_corpus import CORPUS, cases
from wavecheck.drives.library import load_drive
from wavecheck.errors import WavecheckError
from wavecheck.firmware import read_firmware
from wavecheck.firmware.evaluate import evaluate_config
from wavecheck.firmware.guarantee import FirmwareConfig, GeneratorGuarantee, Guaranteed

#: Common drives: two Pololu carriers, a Trinamic UART driver, a Gecko and a Leadshine.
DRIVES = ("drv8825", "a4988", "tmc2209", "gecko-g202", "leadshine-dm542")


def face_value(cfg: FirmwareConfig) -> FirmwareConfig:
    """``cfg`` with every band taken away (each figure judged as exact)."""

    def exact(fig: Guaranteed) -> Guaranteed:
        return dataclasses.replace(fig, short_by=Fraction(0))

    def axis(g: GeneratorGuarantee) -> GeneratorGuarantee:
        hold_t, setup_t = g.dir_hold_trailing, g.dir_setup_trailing
        return dataclasses.replace(
            g,
            pulse=exact(g.pulse),
            idle=exact(g.idle),
            dir_setup=exact(g.dir_setup),
            dir_hold=exact(g.dir_hold),
            max_rate=exact(g.max_rate),
            dir_hold_trailing=None if hold_t is None else exact(hold_t),
            dir_setup_trailing=None if setup_t is None else exact(setup_t),
        )

    return dataclasses.replace(cfg, axes=tuple(axis(a) for a in cfg.axes))


def main(argv: list[str] | None = None) -> int:
    """Print the table (and ``--list`` changed verdicts); exit 0."""
    parser = argparse.ArgumentParser(prog="python -m tools.firmware_bands", description=__doc__)
    parser.add_argument("--corpus", type=Path, default=CORPUS, help="the corpus folder")
    parser.add_argument("--list", type=int, default=0, metavar="N", help="changed verdicts")
    args = parser.parse_args(argv)
    drives = [load_drive(d) for d in DRIVES]
    counts: dict[str, Counter[str]] = {}
    changed: list[str] = []
    for family, path in cases(args.corpus):
        tally = counts.setdefault(family, Counter())
        try:
            cfg = read_firmware(path)
        except WavecheckError:
            continue
        tally["cases"] += 1
        before = face_value(cfg)
        for drive in drives:
            now = evaluate_config(cfg, [(a, drive) for a in cfg.axes])
            was = evaluate_config(before, [(a, drive) for a in before.axes])
            for p_now, p_was in zip(now.pairs, was.pairs, strict=True):
                for r_now, r_was in zip(p_now.rows, p_was.rows, strict=True):
                    tally[f"rules {r_now.verdict}"] += 1
                    if r_now.verdict != r_was.verdict:
                        tally[f"{r_was.verdict} -> {r_now.verdict}"] += 1
                        changed.append(
                            f"{path.relative_to(args.corpus)} {p_now.axis.axis} {drive.id} "
                            f"{r_now.rule}: {r_was.verdict} -> {r_now.verdict}: {r_now.note}"
                        )
    keys = ("cases", "rules pass", "rules fail", "rules indeterminate", "pass -> indeterminate",
            "fail -> indeterminate", "pass -> fail")  # fmt: skip
    print(f"drives: {', '.join(DRIVES)}")
    print("family    " + "  ".join(f"{k:>22}" for k in keys))
    total: Counter[str] = Counter()
    for family, tally in counts.items():
        total.update(tally)
        print(f"{family:<10}" + "  ".join(f"{tally[k]:>22}" for k in keys))
    print(f"{'all':<10}" + "  ".join(f"{total[k]:>22}" for k in keys))
    for line in changed[: args.list]:
        print(line)
    return 0


if __name__ == "__main__":
    sys.exit(main())
