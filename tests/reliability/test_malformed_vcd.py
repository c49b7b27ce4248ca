"""Malformed VCDs: a fixed corpus, truncation at every offset, mutations, tiny read chunks."""

from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tests.reliability.corpus import Case, truncation_offsets, vcd_cases, vcd_text
from tests.reliability.helpers import (
    info_then_check,
)
from wavecheck.capture.vcd import read_vcd, read_vcd_reference
from wavecheck.errors import CaptureError

CASES = list(vcd_cases())
GOOD = vcd_text().encode()
FUZZ = settings(
    max_examples=150,
    deadline=None,
    derandomize=True,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)


def _info_and_check(folder: Path, case: Case) -> None:
    info_then_check(folder, case)


@pytest.mark.parametrize("case", CASES, ids=[c.name for c in CASES])
def test_corpus(tmp_path: Path, case: Case) -> None:
    _info_and_check(tmp_path, case)


@pytest.mark.parametrize("offset", truncation_offsets(len(GOOD), 120))
def test_truncated(tmp_path: Path, offset: int) -> None:
    _info_and_check(tmp_path, Case(f"cut-{offset}", GOOD[:offset], ".vcd", "either"))


def test_truncated_every_offset_in_process(tmp_path: Path) -> None:
    """Every cut of the small VCD: a CaptureError naming the file, or a capture that agrees with
    the simple pyvcd-based reader."""
    path = tmp_path / "cut.vcd"
    for offset in range(len(GOOD) + 1):
        path.write_bytes(GOOD[:offset])
        try:
            fast = read_vcd(path, chunk_bytes=16)
        except CaptureError as err:
            assert str(path) in str(err)
            continue
        ref = read_vcd_reference(path)
        assert [c.edges.tolist() for c in fast.channels] == [c.edges.tolist() for c in ref.channels]
        assert (fast.start, fast.end) == (ref.start, ref.end)


_TOKENS = st.sampled_from(
    ["#", "#0", "#5", "#1200", "#-3", "#99999999999999999999", "0!", "1!", 'x"', 'z"', "1?",
     "b1 !", "b101 \"", "r1.5 !", "$dumpvars", "$end", "$comment", "$bogus", "\x00", "\n", " ",
     "1", "!", "hello", "\r\n", "b", "$dumpoff", "U!", "-\""]
)  # fmt: skip


@FUZZ
@given(tokens=st.lists(_TOKENS, max_size=30), at=st.integers(0, 100))
def test_fuzz_body_tokens(tmp_path: Path, tokens: list[str], at: int) -> None:
    """Random tokens spliced into the value changes."""
    body_start = GOOD.index(b"#0")
    pos = body_start + (at * (len(GOOD) - body_start)) // 100
    data = GOOD[:pos] + b" " + " ".join(tokens).encode("latin-1") + b"\n" + GOOD[pos:]
    _info_and_check(tmp_path, Case("tokens", data, ".vcd", "either"))


@FUZZ
@given(
    flips=st.lists(
        st.tuples(st.integers(0, len(GOOD) - 1), st.integers(1, 255)), min_size=1, max_size=4
    )
)
def test_fuzz_byte_flips(tmp_path: Path, flips: list[tuple[int, int]]) -> None:
    data = bytearray(GOOD)
    for pos, x in flips:
        data[pos] ^= x
    _info_and_check(tmp_path, Case("flipped", bytes(data), ".vcd", "either"))


@FUZZ
@given(timescale=st.text(alphabet=st.sampled_from("0123456789 .-+eEnupfmsakMGx\t"), max_size=10))
def test_fuzz_timescale(tmp_path: Path, timescale: str) -> None:
    data = GOOD.replace(b"$timescale 1 ns $end", f"$timescale {timescale} $end".encode())
    _info_and_check(tmp_path, Case("timescale", data, ".vcd", "either"))
