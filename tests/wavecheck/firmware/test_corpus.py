"""Every configuration of ``../shared/firmware-corpus/`` (other people's files, unchanged) is read
or refused with one line — no traceback, no hang — and the hand-read figures of
``corpus_figures.toml`` (≥ 40 files, every family, each with the lines and the document it was
read from) are what wavecheck reads. ``python -m tools.firmware_corpus`` prints the same as a
table per family."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import pytest

from tests.wavecheck.firmware.bounded import bounded
from tools.firmware_corpus import CORPUS, FAMILIES, cases, differences, load_table
from wavecheck.errors import WavecheckError
from wavecheck.firmware import read_firmware

pytestmark = pytest.mark.skipif(not CORPUS.is_dir(), reason="shared firmware corpus not present")
ALL = list(cases(CORPUS)) if CORPUS.is_dir() else []
TABLE = load_table()


def test_the_corpus_has_every_family() -> None:
    assert {f for f, _ in ALL} == set(FAMILIES) and len(ALL) > 400


@pytest.mark.parametrize("family,path", ALL, ids=[str(p.relative_to(CORPUS)) for _, p in ALL])
def test_every_case_is_read_or_refused_in_one_line(family: str, path: Path) -> None:
    try:
        cfg = bounded(lambda: read_firmware(path))
    except WavecheckError as err:
        text = str(err)
        assert "\n" not in text and len(text) < 600, text
        m = re.match(r"(?P<file>/[^:]+?)(?::(?P<line>\d+))?: (?P<why>\S.+)$", text)
        assert m, f"the refusal does not start with a file: {text}"
        named = Path(m.group("file"))
        assert named.is_file(), f"the refusal names no file of the configuration: {text}"
        assert named == path or named.resolve().is_relative_to(CORPUS.resolve()), text
        if m.group("line") is None:  # a whole-file reason says what the file lacks
            assert re.search(r"\bno\b|\bnot\b", m.group("why")), text
        return
    assert cfg.axes and all(a.axis for a in cfg.axes)


def test_the_table_covers_every_family_and_forty_files() -> None:
    files = [c["file"] for c in TABLE]
    assert len(set(files)) >= 40
    assert {f.split("/")[0] for f in files} == set(FAMILIES)
    assert all(c.get("source") for c in TABLE), "each case says where its figures come from"


@pytest.mark.parametrize("case", TABLE, ids=[c["file"] for c in TABLE])
def test_hand_read_figures(case: dict[str, Any]) -> None:
    assert bounded(lambda: differences(case, CORPUS)) == []
