"""Every fix ``wavecheck config`` prints works (issue 32, class 5): over the whole development
corpus, each fix printed against a demanding drive (the DM542 and the falling-edge G202 with
every timing figure raised) is applied mechanically to a copy of the file
(:mod:`.fixapply`); on the re-run, that rule of that axis no longer fails, and a fix printed
for a figure with a bounded band (:attr:`~wavecheck.firmware.guarantee.Guaranteed.short_by`)
clears it: the rule is no longer indeterminate inside the band."""

from __future__ import annotations

from collections import defaultdict
from pathlib import Path

import pytest

from tests.wavecheck.firmware.fixapply import ADVICE, NotAnEdit, apply, copy_case
from tools.firmware_corpus import CORPUS, cases
from wavecheck.drives.datasheet import Drive
from wavecheck.drives.library import load_drive
from wavecheck.drives.overrides import tune_drive
from wavecheck.errors import WavecheckError
from wavecheck.firmware import read_firmware
from wavecheck.firmware.evaluate import PairRow, evaluate_config

pytestmark = pytest.mark.skipif(not CORPUS.is_dir(), reason="shared firmware corpus not present")
_TIGHT = ["step_high=30us", "step_low=30us", "dir_setup=30us", "dir_hold=30us", "max_rate=1kHz"]


def _drives() -> list[Drive]:
    return [
        tune_drive(load_drive("leadshine-dm542"), _TIGHT, None),
        tune_drive(load_drive("gecko-g202"), _TIGHT, None),
        load_drive("leadshine-dm542"),
    ]


def _left(row: PairRow) -> str:
    """What a fix left undone: a FAIL, or a verdict still inside a bounded band."""
    bounded = row.source is not None and row.source.short_by is not None
    return "fail" if row.verdict == "fail" else ("in band" if row.in_band and bounded else "")


FAMILIES = sorted({family for family, _ in cases(CORPUS)}) if CORPUS.is_dir() else []


@pytest.mark.parametrize("family", FAMILIES)
def test_every_printed_fix_works(family: str, tmp_path: Path) -> None:
    drives = _drives()
    broken: list[str] = []
    applied = 0
    for n, (fam, path) in enumerate(cases(CORPUS)):
        if fam != family:
            continue
        try:
            cfg = read_firmware(path)
        except WavecheckError:
            continue
        # each distinct fix is applied once; the rules that printed it, per drive
        by_fix: dict[str, list[tuple[int, str, str]]] = defaultdict(list)
        for d_no, drive in enumerate(drives):
            result = evaluate_config(cfg, [(a, drive) for a in cfg.axes])
            for pair in result.pairs:
                for row in pair.rows:
                    wanted = row.verdict == "fail" or row.in_band
                    if wanted and row.fix and not ADVICE.search(row.fix):
                        by_fix[row.fix].append((d_no, pair.axis.axis, row.rule))
        for f_no, (fix, rules) in enumerate(by_fix.items()):
            copy = copy_case(cfg, CORPUS, tmp_path / f"{n}-{f_no}")
            try:
                apply(cfg.firmware, copy, fix, cfg)
                again = read_firmware(copy)
            except (NotAnEdit, WavecheckError) as err:
                broken.append(f"{path.relative_to(CORPUS)}: {fix!r}: {err}")
                continue
            applied += 1
            for d_no in sorted({d for d, _, _ in rules}):
                drive = drives[d_no]
                result2 = evaluate_config(again, [(a, drive) for a in again.axes])
                verdicts = {(p.axis.axis, r.rule): _left(r) for p in result2.pairs for r in p.rows}
                still = [f"{a}.{r}" for d, a, r in rules if d == d_no and verdicts.get((a, r))]
                if still:
                    broken.append(
                        f"{path.relative_to(CORPUS)} ({drive.id}): {fix!r} leaves {still} failing "
                        "or inside the band"
                    )
    assert broken == [], f"{len(broken)} of {applied + len(broken)} fixes:\n" + "\n".join(
        broken[:30]
    )
