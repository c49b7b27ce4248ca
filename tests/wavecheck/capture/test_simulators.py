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
from wavecheck.errors import UsageError
from wavecheck.report import Report
from wavecheck.steps.interface import find_channel

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


# Issue 26: a bit of a vector is the bit at that index of its *declared* range. Each vector is
# declared the "wrong" way round for a [width-1:0] guess: rev [0:3] / (0 to 3) and off [5:2] /
# (5 downto 2); the leftmost bit (rev[0], off[5]) toggles 8 times, the rightmost (rev[3],
# off[2]) 4 times and the two middle bits never, so any other reading of the range picks a bit
# with another edge count.
BUS_V = """`timescale 1ns/1ps
module tb;
  reg [0:3] rev = 4'b0000;
  reg [5:2] off = 4'b0000;
  integer k;
  initial begin
    $dumpfile(`DUMPFILE);
    $dumpvars(0, tb);
    for (k = 0; k < 8; k = k + 1) begin
      #10 rev[0] = ~rev[0]; off[5] = ~off[5];
      if (k < 4) begin rev[3] = ~rev[3]; off[2] = ~off[2]; end
    end
    #10 $finish;
  end
endmodule
"""
BUS_VHD = """library ieee; use ieee.std_logic_1164.all;
entity tb is end;
architecture sim of tb is
  signal rev : std_logic_vector(0 to 3) := "0000";
  signal off : std_logic_vector(5 downto 2) := "0000";
begin
  process begin
    for k in 0 to 7 loop
      wait for 10 ns;
      rev(0) <= not rev(0); off(5) <= not off(5);
      if k < 4 then rev(3) <= not rev(3); off(2) <= not off(2); end if;
    end loop;
    wait;
  end process;
end;
"""
BUS_EDGES = {"rev[0]": 8, "rev[1]": 0, "rev[3]": 4, "off[5]": 8, "off[4]": 0, "off[2]": 4}


@pytest.fixture(scope="module")
def bus_dumps(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """The same two vectors dumped by Icarus (VCD, FST) and GHDL (VCD, FST, GHW)."""
    tmp = tmp_path_factory.mktemp("bus")
    dumps: dict[str, Path] = {}
    if shutil.which("iverilog") and shutil.which("vvp"):
        (tmp / "bus.v").write_text(BUS_V)
        for ext in ("vcd", "fst"):
            exe = tmp / f"bus-{ext}.vvp"
            dump = tmp / f"icarus.{ext}"
            subprocess.run(
                ["iverilog", f'-DDUMPFILE="{dump}"', "-o", str(exe), "bus.v"], check=True, cwd=tmp
            )
            flags = ["-fst"] if ext == "fst" else []
            subprocess.run(
                ["vvp", "-n", str(exe), *flags], check=True, cwd=tmp, capture_output=True
            )
            dumps[f"icarus-{ext}"] = dump
    if shutil.which("ghdl"):
        (tmp / "bus.vhd").write_text(BUS_VHD)
        subprocess.run(["ghdl", "-a", "bus.vhd"], check=True, cwd=tmp)
        subprocess.run(["ghdl", "-e", "tb"], check=True, cwd=tmp)
        subprocess.run(
            ["ghdl", "-r", "tb", "--vcd=ghdl.vcd", "--fst=ghdl.fst", "--wave=ghdl.ghw"],
            check=True, cwd=tmp, capture_output=True,
        )  # fmt: skip
        dumps.update({f"ghdl-{e}": tmp / f"ghdl.{e}" for e in ("vcd", "fst", "ghw")})
    return dumps


@pytest.mark.parametrize("dump", ["icarus-vcd", "icarus-fst", "ghdl-vcd", "ghdl-fst", "ghdl-ghw"])
def test_bits_of_buses_follow_the_declared_range(bus_dumps: dict[str, Path], dump: str) -> None:
    if dump not in bus_dumps:
        pytest.skip("needs iverilog and ghdl (make system-deps)")
    cap = open_capture(bus_dumps[dump])
    got = {name: len(find_channel(cap, name).edges) for name in BUS_EDGES}
    assert got == BUS_EDGES
    ranges = {key.rsplit(".", 1)[-1]: v.range_text for key, v in cap.vectors.items()}
    assert ranges == {"rev": "[0:3]", "off": "[5:2]"}
    with pytest.raises(UsageError, match="has no bit 1 .bits 2 to 5"):
        find_channel(cap, "off[1]")


def test_fst_through_pywellen_offers_no_bits_it_cannot_place(bus_dumps: dict[str, Path]) -> None:
    """pywellen does not give an FST vector's range: without fst2vcd no bit is guessed."""
    if "icarus-fst" not in bus_dumps:
        pytest.skip("needs iverilog (make system-deps)")
    cap = read_wellen(bus_dumps["icarus-fst"], kind="fst")
    assert cap.vectors == {}
    assert any("fst2vcd" in n for n in cap.notes)
    with pytest.raises(UsageError, match="no channel 'rev.0.'"):
        find_channel(cap, "rev[0]")


@pytest.mark.parametrize("dump", ["ghdl-vcd", "ghdl-fst", "ghdl-ghw", "icarus-vcd"])
def test_a_bit_in_vhdl_spelling_maps(bus_dumps: dict[str, Path], dump: str) -> None:
    """Issue 34: ``--map step=pins(2)``, VHDL's index spelling, names the bit ``pins[2]`` does."""
    if dump not in bus_dumps:
        pytest.skip("needs iverilog and ghdl (make system-deps)")
    cap = open_capture(bus_dumps[dump])
    for name, edges in BUS_EDGES.items():
        vhdl = name.replace("[", "(").replace("]", ")")
        assert len(find_channel(cap, vhdl).edges) == edges, vhdl
        assert find_channel(cap, vhdl.replace("(", " ( ")) is find_channel(cap, name)
    with pytest.raises(UsageError, match="has no bit 1 .bits 2 to 5"):
        find_channel(cap, "off(1)")


def test_the_cli_maps_a_bit_in_vhdl_spelling(bus_dumps: dict[str, Path]) -> None:
    if "ghdl-vcd" not in bus_dumps:
        pytest.skip("needs ghdl (make system-deps)")
    from wavecheck.cli import main

    args = ["info", str(bus_dumps["ghdl-vcd"])]
    assert main(args) == 0
    common = ["check", str(bus_dumps["ghdl-vcd"]), "--drive", "gecko-g202", "--format", "json"]
    assert main([*common, "--map", "step=off(5),dir=off(2)"]) in (0, 1)
    assert main([*common, "--map", "step=off(9),dir=off(2)"]) == 2
