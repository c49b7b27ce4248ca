"""Other formats through sigrok-cli (csv, binary, …): junk in, exit 2 with one line out."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tests.reliability.helpers import assert_contract, cli

pytestmark = pytest.mark.sigrok

CASES: list[tuple[str, bytes, str, list[str], str]] = [
    # name, content, suffix, extra args, expect
    ("csv-no-rate", b"a,b\n1,0\n0,1\n", ".csv", [], "error"),
    ("csv-ok", b"a,b\n1,0\n0,1\n1,1\n", ".csv", ["--samplerate", "1MHz"], "either"),
    ("csv-junk", b"junk", ".csv", ["--samplerate", "1MHz"], "error"),
    # sigrok-cli stops at a NUL silently (issue 12): refused, not half-checked
    ("csv-nul-byte", b"a,b\n1,0\n0,1\n\x001,1\n0,0\n", ".csv", ["--samplerate", "1MHz"], "error"),
    ("csv-first-row-is-data", b"1,0\n0,1\n1,1\n", ".csv", ["--samplerate", "1MHz"], "error"),
    ("csv-empty", b"", ".csv", ["--samplerate", "1MHz"], "error"),
    ("csv-binary", bytes(range(256)), ".csv", ["--samplerate", "1MHz"], "error"),
    ("csv-fraction-rate", b"a\n1\n0\n", ".csv", ["--samplerate", "1000.5Hz"], "error"),
    (
        "binary-ok",
        bytes([1, 2, 3, 0] * 50),
        ".bin",
        ["--input-format", "binary:numchannels=2", "--samplerate", "1MHz"],
        "ok",
    ),
    (  # read natively: info shows it untimed (counts in samples), as a .sr without a rate
        "binary-no-rate",
        bytes([1, 0] * 50),
        ".bin",
        ["--input-format", "binary:numchannels=2"],
        "ok",
    ),
    (
        "binary-odd-size",
        bytes(101),
        ".bin",
        ["--input-format", "binary:numchannels=9", "--samplerate", "1MHz"],
        "either",
    ),
    (
        "binary-0-channels",
        bytes(10),
        ".bin",
        ["--input-format", "binary:numchannels=0", "--samplerate", "1MHz"],
        "either",
    ),
    ("unknown-format", b"xyz", ".bin", ["--input-format", "nosuchformat"], "error"),
    (
        "format-bad-option",
        b"a\n1\n",
        ".csv",
        ["--input-format", "csv:bogus=1", "--samplerate", "1MHz"],
        "error",
    ),
    (
        "format-shell-chars",
        b"a\n1\n",
        ".csv",
        ["--input-format", "csv; rm -rf /", "--samplerate", "1MHz"],
        "error",
    ),
    ("unknown-extension", b"hello", ".xyz", [], "error"),
    ("rate-zero", b"a\n1\n0\n", ".csv", ["--samplerate", "0Hz"], "error"),
    ("rate-negative", b"a\n1\n0\n", ".csv", ["--samplerate", "-1MHz"], "error"),
    ("rate-junk", b"a\n1\n0\n", ".csv", ["--samplerate", "quick"], "error"),
    (
        "resolution-negative",
        b"a\n1\n0\n",
        ".csv",
        ["--samplerate", "1MHz", "--resolution", "-5ns"],
        "error",
    ),
]


@pytest.fixture(autouse=True)
def _need_sigrok() -> None:
    if shutil.which("sigrok-cli") is None:
        pytest.skip("sigrok-cli not installed (make system-deps)")


@pytest.mark.parametrize("case", CASES, ids=[c[0] for c in CASES])
def test_corpus(tmp_path: Path, case: tuple[str, bytes, str, list[str], str]) -> None:
    name, data, suffix, extra, expect = case
    path = tmp_path / f"{name}{suffix}"
    path.write_bytes(data)
    rc, _, err = cli("wavecheck", ["info", str(path), *extra])
    if rc == 2 and name.startswith(("rate-", "resolution-")) and str(path) not in err:
        # a bad option value names the option, not the file
        assert len(err.strip().splitlines()) == 1 and "Traceback" not in err, err
        return
    assert_contract(rc, err, str(path), expect)


@settings(
    max_examples=25,
    deadline=None,
    derandomize=True,
    suppress_health_check=[HealthCheck.function_scoped_fixture],
)
@given(
    data=st.binary(max_size=300),
    fmt=st.sampled_from(["csv", "binary:numchannels=3", "chronovu-la8", "logicport", "vcd"]),
)
def test_fuzz_formats(tmp_path: Path, data: bytes, fmt: str) -> None:
    path = tmp_path / "fuzz.dat"
    path.write_bytes(data)
    rc, _, err = cli(
        "wavecheck", ["info", str(path), "--input-format", fmt, "--samplerate", "1MHz"]
    )
    assert_contract(rc, err, str(path), "either")
