"""FST, GHW, bits of buses and mid-capture unknowns, from real simulator output.

The same step generator (``sim/gen.v``, ``sim/gen.vhd``) is simulated by Debian's Icarus Verilog
(VCD and ``vvp -fst``) at several timescales and by GHDL (``--vcd`` and ``--wave`` GHW, always
fs); every dump must give the same check against a DRV8825 (1.9 us pulses, 650 ns DIR setup and
hold), with the failures and the unknown stretch the generator was written to have.
"""

from __future__ import annotations

import shutil
import subprocess
from fractions import Fraction
from pathlib import Path

import pytest

from wavecheck.api import check
from wavecheck.capture.open import detect_format, open_capture
from wavecheck.capture.wellen import read_wellen
from wavecheck.engine.interface import find_channel
from wavecheck.errors import UsageError
from wavecheck.report import Report

SIM = Path(__file__).parent / "sim"
needs_iverilog = pytest.mark.skipif(
    shutil.which("iverilog") is None or shutil.which("vvp") is None,
    reason="needs Debian's iverilog (make system-deps)",
)
needs_ghdl = pytest.mark.skipif(
    shutil.which("ghdl") is None, reason="needs Debian's ghdl (make system-deps)"
)
SCALARS = {"step": "dut.step", "dir": "dut.dir"}
# Icarus's precision → the dump's timescale; the delays are whole ns, so exact in each
PRECISIONS = ["1fs", "1ps", "10ps", "1ns"]


def _icarus(tmp: Path, precision: str, fst: bool) -> Path:
    src = tmp / f"gen-{precision}.v"
    dump = tmp / f"gen-{precision}.{'fst' if fst else 'vcd'}"
    src.write_text((SIM / "gen.v").read_text().replace("TIMESCALE_PRECISION", precision))
    exe = tmp / f"gen-{precision}-{'fst' if fst else 'vcd'}.vvp"
    subprocess.run(
        ["iverilog", f'-DDUMPFILE="{dump}"', "-o", str(exe), str(src)], check=True, cwd=tmp
    )
    subprocess.run(
        ["vvp", "-n", str(exe), *(["-fst"] if fst else [])],
        check=True,
        cwd=tmp,
        capture_output=True,
    )
    return dump


@pytest.fixture(scope="module")
def ghdl_dumps(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    tmp = tmp_path_factory.mktemp("ghdl")
    shutil.copy(SIM / "gen.vhd", tmp / "gen.vhd")
    subprocess.run(["ghdl", "-a", "gen.vhd"], check=True, cwd=tmp)
    subprocess.run(["ghdl", "-e", "tb"], check=True, cwd=tmp)
    subprocess.run(
        ["ghdl", "-r", "tb", "--vcd=gen.vcd", "--wave=gen.ghw"],
        check=True,
        cwd=tmp,
        capture_output=True,
    )
    return tmp / "gen.vcd", tmp / "gen.ghw"


def _summary(report: Report) -> list[tuple[object, ...]]:
    """Each rule's counts, worst margin and unknown intervals, in exact seconds/ns."""
    return [
        (
            r.rule,
            r.checked,
            r.violations,
            r.indeterminate,
            r.unknown,
            r.min_margin_ns,
            r.min_margin_at_s,
            tuple(r.timebase.seconds(int(t)) for t in r.unknown_ticks),
            tuple(v.time_s for v in r.worst_violations(10)),
        )
        for r in report.rules
    ]


def _expected_facts(summary: list[tuple[object, ...]]) -> None:
    """What gen.v/gen.vhd were written to do, so equal results are also right ones."""
    by = {row[0]: row for row in summary}
    assert by["step_high"][2] == 1 and by["step_high"][5] == Fraction(-100)  # 1.8 us < 1.9 us
    assert by["dir_setup"][2] == 1 and by["dir_setup"][5] == Fraction(500 - 650)
    # DIR unknown for 1 us between pulses 14 and 15: the setup and hold around it are not judged
    assert by["dir_setup"][4] >= 1 and by["dir_hold"][4] >= 1
    assert by["step_high"][4] == 0  # STEP is known throughout


@needs_iverilog
@pytest.mark.parametrize("precision", PRECISIONS)
def test_icarus_vcd_and_fst_give_identical_checks(tmp_path: Path, precision: str) -> None:
    vcd = _icarus(tmp_path, precision, fst=False)
    fst = _icarus(tmp_path, precision, fst=True)
    assert detect_format(vcd) == "vcd" and detect_format(fst) == "fst"
    base = _summary(check(vcd, "drv8825", map=SCALARS))
    _expected_facts(base)
    assert _summary(check(fst, "drv8825", map=SCALARS)) == base
    # pywellen's FST reader (used without fst2vcd) agrees with GTKWave's
    assert _summary(check(read_wellen(fst, kind="fst"), "drv8825", map=SCALARS)) == base
    # a bit of a bus maps as a channel, in VCD and FST alike
    bits = {"step": "dut.stout[0]", "dir": "tb.dut.stout[1]"}
    assert _summary(check(vcd, "drv8825", map=bits)) == base
    assert _summary(check(fst, "drv8825", map=bits)) == base


@needs_iverilog
def test_every_timescale_gives_the_same_check(tmp_path: Path) -> None:
    results = [
        _summary(check(_icarus(tmp_path, p, fst=True), "drv8825", map=SCALARS)) for p in PRECISIONS
    ]
    assert all(r == results[0] for r in results)
    assert open_capture(_icarus(tmp_path, "1fs", fst=True)).timebase.tick_s == Fraction(1, 10**15)


@needs_ghdl
def test_ghdl_vcd_and_ghw_give_identical_checks(ghdl_dumps: tuple[Path, Path]) -> None:
    vcd, ghw = ghdl_dumps
    assert detect_format(ghw) == "ghw"
    base = _summary(check(vcd, "drv8825", map=SCALARS))
    _expected_facts(base)
    assert _summary(check(ghw, "drv8825", map=SCALARS)) == base
    bits = {"step": "dut.stout[0]", "dir": "dut.stout[1]"}
    assert _summary(check(ghw, "drv8825", map=bits)) == base
    assert _summary(check(vcd, "drv8825", map=bits)) == base


@needs_ghdl
@needs_iverilog
def test_verilog_and_vhdl_agree(tmp_path: Path, ghdl_dumps: tuple[Path, Path]) -> None:
    icarus = _summary(check(_icarus(tmp_path, "1ps", fst=True), "drv8825", map=SCALARS))
    assert _summary(check(ghdl_dumps[1], "drv8825", map=SCALARS)) == icarus


@needs_iverilog
@needs_ghdl
def test_partial_and_ambiguous_names(tmp_path: Path, ghdl_dumps: tuple[Path, Path]) -> None:
    for path in (_icarus(tmp_path, "1ps", fst=True), ghdl_dumps[1]):
        cap = open_capture(path)
        # tb.stout and tb.dut.stout both end with "stout": a partial name must not pick one
        with pytest.raises(UsageError, match="ambiguous"):
            find_channel(cap, "stout[0]", "step")
        assert find_channel(cap, "dut.stout[1]").name == "tb.dut.stout[1]"
        with pytest.raises(UsageError, match="has no bit 2"):
            find_channel(cap, "dut.stout[2]")
        with pytest.raises(UsageError, match="no vector"):
            find_channel(cap, "nothing[0]")


@needs_iverilog
@needs_ghdl
def test_a_never_known_signal_is_unknown(tmp_path: Path, ghdl_dumps: tuple[Path, Path]) -> None:
    for path in (_icarus(tmp_path, "1ps", fst=False), ghdl_dumps[1]):
        cap = open_capture(path)
        spare = [c for c in cap.channels if c.name.endswith("spare")]
        assert spare and all(c.never_known for c in spare)
        starts, ends = find_channel(cap, "dut.dir").unknown_stretches(cap.start)
        # unknown at the start (x until 1 us), then 1 us after pulse 14
        assert len(starts) == 2 and cap.timebase.seconds(int(ends[1] - starts[1])) == Fraction(
            1, 10**6
        )
