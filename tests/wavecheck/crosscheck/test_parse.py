"""Reading sigrok-cli's annotations a block at a time with numpy gives what the line reader
gives, on any text: well-formed lines as sigrok-cli prints them, and every way to spoil one."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from wavecheck.crosscheck.sigrok import (
    _parse_plain_lines,
    parse_annotation_file,
    parse_annotations,
)
from wavecheck.errors import CaptureError

NUMBERS = st.integers(0, 10**6) | st.integers(0, 10**20)
LINES = st.one_of(
    st.builds("{}-{} stepper_motor-1: {} steps".format, NUMBERS, NUMBERS, st.integers(-(10**6), 10**6)),
    st.builds("{}-{} counter-1: {}".format, NUMBERS, NUMBERS, NUMBERS),
    st.builds("{}-{} counter-12: {}".format, NUMBERS, NUMBERS, st.integers(-5, 5)),
    st.sampled_from([
        "", " ", "1-2 stepper_motor-1: fast", "1-2 stepper_motor-1:  3 steps", "1-2 counter-1: +4", "1-2 counter-1: x",
        "1-2 counter-1: 4 ", "x1-2 counter-1: 4", "1-2 stepper_motor-1-2: 3 steps", "1-2 uart-1: 3",
        "1-2 counter-1: ٣", "1-2 counter: 3", "1-2counter-1: 3", "0-0 stepper_motor-1: -0 steps",
        "1-2 stepper_motor-1: 3 steps\r", "1-2 counter-1: 3\x0c4-5 counter-1: 6", "é", "1--2 counter-1: 3",
    ]),
)  # fmt: skip
ENDS = st.sampled_from(["\n", "\r\n", "\r"])


def _outcome(read):  # type: ignore[no-untyped-def]
    try:
        got = read()
    except CaptureError as err:
        return str(err)
    return got.counts.tolist(), got.positions.tolist()


@settings(max_examples=400, deadline=None)
@given(st.lists(st.tuples(LINES, ENDS), max_size=12), st.booleans(), st.integers(1, 64))
def test_block_reader_equals_the_line_reader(lines, last_end, block) -> None:  # type: ignore[no-untyped-def]
    text = "".join(line + end for line, end in lines)
    if not last_end:
        text = text.rstrip("\r\n")
    fd, name = tempfile.mkstemp(suffix=".txt")  # hypothesis runs a function fixture once
    try:
        os.write(fd, text.encode())
        os.close(fd)
        want = _outcome(lambda: parse_annotations(text, "x.sr"))
        assert _outcome(lambda: parse_annotation_file(Path(name), "x.sr", block)) == want
        assert _outcome(lambda: parse_annotation_file(Path(name), "x.sr")) == want
    finally:
        os.unlink(name)


@pytest.mark.parametrize(
    ("text", "fast"),
    [
        ("0-129 counter-1: 1\n129-195 stepper_motor-1: -1 steps\n", True),
        ("0-129 counter-1: 1\r\n129-195 stepper_motor-1: -1 steps\r\n", True),
        ("0-129 counter-1: 1\nsome other line\n", False),
        ("0-129 counter-1: 1", False),  # no newline: not a whole line
        ("0-1234567890123456789 counter-1: 1\n", False),  # 19 digits
    ],
)
def test_which_blocks_numpy_reads(text: str, fast: bool) -> None:
    assert (_parse_plain_lines(text.encode()) is not None) is fast
