"""Malformed rule files: missing keys, negative or non-numeric limits, unknown units, junk."""

from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tests.reliability.corpus import Case, rule_cases, rule_text, vcd_text
from tests.reliability.helpers import assert_contract, assert_no_output, cli
from wavecheck.drives.library import load_drive
from wavecheck.errors import RuleError

CASES = list(rule_cases())


def _run(folder: Path, case: Case) -> None:
    path = folder / "fuzz-drive.toml"  # the file name must be the id
    path.write_bytes(case.data)
    capture = folder / "capture.vcd"
    capture.write_text(vcd_text())
    rc, _, err = cli("wavecheck", ["drives", str(path)])
    assert_contract(rc, err, str(path), case.expect)
    out_dir = folder / "out"
    out_dir.mkdir(exist_ok=True)
    for p in out_dir.iterdir():
        p.unlink()
    rc2, _, err2 = cli(
        "wavecheck",
        ["check", str(capture), "--drive", str(path), "--format", "json",
         "-o", str(out_dir / "r.json")],
    )  # fmt: skip
    assert_contract(rc2, err2, str(path), case.expect, ok_codes=(0, 1, 3))
    if rc2 == 2:
        assert_no_output(out_dir)
    if case.expect == "error":
        with pytest.raises(RuleError) as exc:
            load_drive(path)
        assert str(path) in str(exc.value)


@pytest.mark.parametrize("case", CASES, ids=[c.name for c in CASES])
def test_corpus(tmp_path: Path, case: Case) -> None:
    _run(tmp_path, case)


def test_unknown_drive_id() -> None:
    rc, _, err = cli("wavecheck", ["drives", "gecko-g2O2"])
    assert rc == 2 and len(err.strip().splitlines()) == 1 and "gecko-g2O2" in err


_VALUES = st.one_of(
    st.text(max_size=12).map(lambda s: '"' + s.replace("\\", "").replace('"', "") + '"'),
    st.integers(-(10**30), 10**30).map(str),
    st.floats(allow_nan=False, allow_infinity=False).map(repr),
    st.sampled_from(['"0"', '"0 ns"', '"1e-30 s"', '"1e30 s"', '"5us"', '" 5 us "', '"5 μs"',
                     '"5 MHz"', '"nan"', '"-0 ns"', '"1/3 us"', '"0x10 ns"']),
)  # fmt: skip


@settings(
    max_examples=150,
    deadline=None,
    derandomize=True,
    suppress_health_check=[HealthCheck.function_scoped_fixture],
)
@given(
    key=st.sampled_from(["step_high", "step_low", "dir_setup", "dir_hold", "max_rate"]),
    value=_VALUES,
)
def test_fuzz_limit_values(tmp_path: Path, key: str, value: str) -> None:
    """Any value of any limit: loads (then checks), or a one-line RuleError naming the file."""
    table = f'[limits.{key}]\nvalue = {value}\nsource = "S1"\nstatus = "datasheet"'
    _run(tmp_path, Case("fuzz", rule_text(**{key: table}).encode(), ".toml", "either"))
