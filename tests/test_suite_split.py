"""The suite's split (issue 37): ``make test`` leaves out the tests marked slow, ``make test-all``
and .ci/run run everything, and the run's last line says what did not run and why."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from tests.conftest import SLOW

REPO = Path(__file__).resolve().parent.parent

pytest_plugins = ["pytester"]


def test_every_slow_entry_names_a_test_that_exists() -> None:
    for start, why in SLOW.items():
        path, _, name = start.partition("::")
        function = re.sub(r"\[.*", "", name)
        assert (REPO / path).is_file(), start
        assert re.search(rf"^def {function}\(", (REPO / path).read_text(), re.M), start
        assert why, start


def test_make_test_leaves_the_slow_ones_to_test_all_and_ci() -> None:
    makefile = (REPO / "Makefile").read_text(encoding="utf-8")
    fast = re.search(r"^test:.*\n((?:\t.*\n)+)", makefile, re.M)
    full = re.search(r"^test-all:.*\n((?:\t.*\n)+)", makefile, re.M)
    assert fast and full
    assert '-m "not slow"' in fast.group(1) and "-m" not in full.group(1)
    ci = (REPO / ".ci" / "run").read_text(encoding="utf-8")
    assert re.search(r"^make test-all$", ci, re.M)


@pytest.mark.parametrize("workers", [[], ["-n", "2"]], ids=["one-process", "xdist"])
def test_the_last_line_says_what_did_not_run(pytester, workers: list[str]) -> None:
    """A run with a skip and a deselected test ends with one line naming both, paths left out
    (with xdist too, whose workers deselect and tell the controller)."""
    pytester.makeconftest((REPO / "tests" / "conftest.py").read_text(encoding="utf-8"))
    pytester.makepyfile(
        test_x="""
import pytest

def test_a():
    pytest.skip("shared capture not present: /some/where/a.sr")

def test_b():
    pytest.skip("shared capture not present: /some/where/b.sr")

@pytest.mark.slow
def test_c():
    pass
"""
    )
    pytester.makeini("[pytest]\nmarkers =\n    slow: slow\n")
    result = pytester.runpytest("-m", "not slow", "-p", "no:cacheprovider", *workers)
    last = result.outlines[-1]
    assert last.startswith('not run: 1 deselected (-m "not slow"')
    assert "2 skipped: 2 shared capture not present: …" in last
