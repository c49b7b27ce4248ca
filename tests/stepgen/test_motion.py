"""``--command FILE.csv``: the whole-file parser gives exactly what the row-by-row reader gives."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path
from unittest import mock

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from stepgen import motion
from stepgen.motion import _parse_plain_lines, _parse_rows, parse_command_csv
from wavecheck.errors import ConfigError

#: Pieces of lines: numbers as people and programs write them, and what breaks a plain file.
FIELDS = st.one_of(
    st.floats(allow_nan=False, allow_infinity=False).map(repr),
    st.integers(-(10**20), 10**20).map(str),
    st.sampled_from(
        ["0", "-0.0", " 1.5", "2 ", "1e3", "1_000", ".5", "5.", "inf", "nan", "1e999", "x", "",
         "time_s", "value", '"1"', "#c", " ", "\u0661", "1\x00"]
    ),
)  # fmt: skip
NUMBERS = st.floats(-1e6, 1e6).map(repr)
LINES = st.one_of(
    st.tuples(NUMBERS, NUMBERS).map(",".join),
    st.tuples(NUMBERS, NUMBERS).map(",".join),
    st.tuples(FIELDS, FIELDS).map(",".join),
    st.lists(FIELDS, min_size=0, max_size=3).map(",".join),
)
ENDS = st.sampled_from(["\n", "\r\n", "\r"])


def _outcome(path: Path) -> tuple[list[float], list[float]] | str:
    try:
        t, v = _parse_rows(path)
    except ConfigError as err:
        return str(err)
    return t.tolist(), v.tolist()


#: Files a program writes: times in order, one line ending, now and then one odd line.
ORDERED = st.tuples(
    st.lists(st.tuples(st.floats(0, 1e3), NUMBERS), max_size=8),
    ENDS,
    st.none() | st.tuples(st.integers(0, 8), LINES),
).map(
    lambda a: (
        [(f"{t!r},{v}", a[1]) for t, v in sorted(a[0])]
        if a[2] is None
        else [(f"{t!r},{v}", a[1]) for t, v in sorted(a[0])][: a[2][0]] + [(a[2][1], a[1])]
    )
)


@settings(max_examples=400, deadline=None)
@given(st.lists(st.tuples(LINES, ENDS), max_size=8) | ORDERED, st.booleans(), st.booleans())
def test_whole_file_parse_equals_the_row_reader(rows, header, last_end) -> None:  # type: ignore[no-untyped-def]
    text = "".join(line + end for line, end in rows)
    if header:
        text = "time_s,value\n" + text
    if not last_end and text.endswith("\n"):
        text = text[:-1]
    data = text.encode()
    fast = _parse_plain_lines(data)
    fd, name = tempfile.mkstemp(suffix=".csv")  # hypothesis runs a function fixture once
    path = Path(name)
    try:
        os.write(fd, data)
        os.close(fd)
        plain = _outcome(path)
        if fast is not None:  # the fast path answers only what the row reader answers the same
            assert plain == (fast[0].tolist(), fast[1].tolist())
            for got, want in zip(fast, plain, strict=True):
                assert np.signbit(got).tolist() == np.signbit(want).tolist()
        try:
            t, v = parse_command_csv(path)
            assert plain == (t.tolist(), v.tolist())
        except ConfigError as err:
            assert plain == str(err)
    finally:
        path.unlink()


@pytest.mark.parametrize(
    ("text", "fast"),
    [
        ("time_s,value\n0,0\n0.001,1.5\n", True),
        ("0,0\r\n1,2\r\n", True),
        ("0,0\n\n1,2\n", False),  # a blank line
        ("# made by hand\n0,0\n", False),
        ("0,0,extra\n", False),  # three fields: the row reader takes the first two
        ('"0",1\n', False),
    ],
)
def test_which_files_take_the_whole_file_path(tmp_path: Path, text: str, fast: bool) -> None:
    assert (_parse_plain_lines(text.encode()) is not None) is fast
    path = tmp_path / "c.csv"
    path.write_text(text, newline="")
    t, v = parse_command_csv(path)
    t0, v0 = _parse_rows(path)
    np.testing.assert_array_equal(t, t0)
    np.testing.assert_array_equal(v, v0)


@settings(max_examples=200, deadline=None)
@given(st.lists(st.tuples(LINES, ENDS), max_size=8) | ORDERED, st.sampled_from([1, 5, 40]))
def test_whole_file_parse_in_pieces_is_the_same(rows, piece) -> None:  # type: ignore[no-untyped-def]
    """The whole-file path splits and converts ``_CSV_PIECE`` characters of whole lines at a
    time: pieces of one line or a few give the same answer (or the same refusal)."""
    data = "".join(line + end for line, end in rows).encode()
    whole = _parse_plain_lines(data)
    with mock.patch.object(motion, "_CSV_PIECE", piece):
        pieces = _parse_plain_lines(data)
    if whole is None:
        assert pieces is None
        return
    assert pieces is not None
    for a, b in zip(whole, pieces, strict=True):
        assert a.view(np.int64).tolist() == b.view(np.int64).tolist()
