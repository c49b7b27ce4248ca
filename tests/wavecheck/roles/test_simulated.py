"""Role inference on simulated dumps and a real device driver's captures: Icarus Verilog and
GHDL (VCD and GHW) dumps of a step generator among clocks, buses, a UART, PWM and enable lines
(``sim/lines.v``, ``sim/lines.vhd``); LinuxCNC's stepgen (``stepgen simulate``) under latency,
with neutral channel names; and every pattern of sigrok-cli's ``demo`` driver, none of them a
step signal (its ``graycode`` pattern's two top bits are quadrature at one rate: a free-running
counter, not established as a motor, unlike sigrok-dumps' graycode capture, whose rate ramps). Lines never get a role their waveform contradicts."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import pytest

from stepgen.cli import main as stepgen_main
from wavecheck.capture.open import open_capture
from wavecheck.roles import Proposal, propose

from ..waves import renamed

SIM = Path(__file__).parent / "sim"


def _roles(p: Proposal) -> list[dict[str, str]]:
    return [{r.role: r.channel for r in a.roles} for a in p.axes]


def _need(*tools: str) -> None:
    for tool in tools:
        if shutil.which(tool) is None:
            pytest.skip(f"needs {tool} (make system-deps)")


@pytest.fixture(scope="module")
def icarus(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    _need("iverilog", "vvp")
    tmp = tmp_path_factory.mktemp("icarus")
    dumps = {}
    for name, defines in {"steps": [], "steps+spi": ["WITH_SPI"], "buses": ["TB_BUSES"]}.items():
        dump = tmp / f"{name}.vcd"
        exe = tmp / f"{name}.vvp"
        flags = [f"-D{d}" for d in defines]
        source = str(SIM / "lines.v")
        cmd = ["iverilog", "-g2012", *flags, f'-DDUMPFILE="{dump}"', "-o", str(exe), source]
        subprocess.run(cmd, check=True, cwd=tmp)
        subprocess.run(["vvp", "-n", str(exe)], check=True, cwd=tmp, capture_output=True)
        dumps[name] = dump
    return dumps


def test_icarus_step_generator_among_a_clock_and_an_spi_bus(icarus: dict[str, Path]) -> None:
    for name in ("steps", "steps+spi"):
        p = propose(open_capture(icarus[name]))
        assert p.unambiguous, p.text()
        assert _roles(p) == [{"step": "n1", "dir": "n0", "enable": "n2"}], name
        looks = {k.channel: k.word for k in p.looks}
        assert looks["clk"] == "clock"
    p = propose(open_capture(icarus["steps+spi"]))
    looks = {k.channel: k.word for k in p.looks}
    assert (looks["sck"], looks["mosi"]) == ("bus clock", "bus data")


def test_icarus_lines_of_other_kinds_are_no_step_signal(icarus: dict[str, Path]) -> None:
    p = propose(open_capture(icarus["buses"]))
    assert not p.axes and not p.ambiguous, p.text()
    looks = {k.channel: k.word for k in p.looks}
    assert looks["pwm"] == "PWM" and looks["pwm_fixed"] == "periodic pulses"
    assert looks["q"] == "periodic pulses"  # one rate, never a pause: a STEP only when named so
    assert looks["sda"] == "bus data" and looks["gen"] == "chip select"


@pytest.mark.parametrize("dump", ["l.vcd", "l.ghw"])
def test_ghdl_step_generator_beside_a_uart(
    tmp_path_factory: pytest.TempPathFactory, dump: str
) -> None:
    _need("ghdl")
    tmp = tmp_path_factory.mktemp("ghdl")
    shutil.copy(SIM / "lines.vhd", tmp / "lines.vhd")
    for cmd in (["-a"], ["-e"]):
        subprocess.run(["ghdl", *cmd, "--std=08", *(["lines.vhd"] if cmd == ["-a"] else ["tb"])],
                       check=True, cwd=tmp)  # fmt: skip
    subprocess.run(
        ["ghdl", "-r", "--std=08", "tb", "--vcd=l.vcd", "--wave=l.ghw"],
        check=True,
        cwd=tmp,
        capture_output=True,
    )
    p = propose(open_capture(tmp / dump))
    assert p.unambiguous, p.text()
    assert _roles(p) == [{"step": "l1", "dir": "l4", "enable": "l3"}]
    looks = {k.channel: k.word for k in p.looks}
    assert (looks["l0"], looks["l2"]) == ("serial line", "clock")


@pytest.mark.parametrize(
    ("args", "roles"),
    [
        (
            ["--maxvel", "15", "--maxaccel", "300", "--move", "2, pause 20ms, -1, 1.5@10",
             "--latency", "uniform:5us"],
            {"step": "D0", "dir": "D1"},
        ),
        # at its top rate: periods of 2 and 3 base periods in turn
        (["--maxvel", "19", "--maxaccel", "2000", "--move", "3, -3"], {"step": "D0", "dir": "D1"}),
        (
            ["--base-period", "50us", "--position-scale", "400", "--maxvel", "20", "--maxaccel",
             "100", "--move", "2, -2", "--latency", "normal:4us,20us"],
            {"step": "D0", "dir": "D1"},
        ),
        (
            ["--type", "1", "--maxvel", "10", "--maxaccel", "300", "--move", "1, pause 20ms, -1"],
            {"up": "D0", "down": "D1"},
        ),
        (
            ["--type", "2", "--maxvel", "10", "--maxaccel", "300", "--move", "1, pause 20ms, -0.5"],
            {"phase-A": "D0", "phase-B": "D1"},
        ),
    ],
)  # fmt: skip
def test_linuxcnc_stepgen_with_neutral_names(
    tmp_path: Path, args: list[str], roles: dict[str, str]
) -> None:
    base = ["--base-period", "25us", "--position-scale", "1000"]
    out = tmp_path / "run.vcd"
    assert stepgen_main(["simulate", *base, *args, "-q", "-o", str(out)]) == 0
    cap = open_capture(out)
    p = propose(renamed(cap, [f"D{c.index}" for c in cap.channels]))
    assert p.unambiguous, p.text()
    got = _roles(p)
    if "phase-A" in roles:  # which output is phase-A the waveform does not tell
        assert [set(a.values()) for a in got] == [set(roles.values())]
    else:
        assert got == [roles]


PATTERNS = ["sigrok", "random", "incremental", "walking-one", "walking-zero", "squid", "graycode"]


@pytest.mark.parametrize("pattern", PATTERNS)
def test_sigrok_demo_patterns_hold_no_step_signal(tmp_path: Path, pattern: str) -> None:
    """The ``demo`` driver runs at 200 kHz in real time: 100,000 samples take half a second."""
    _need("sigrok-cli")
    out = tmp_path / f"{pattern}.sr"
    subprocess.run(
        ["sigrok-cli", "-d", "demo:analog_channels=0", "-g", "Logic", "--config",
         f"pattern={pattern}", "--samples", "100000", "-o", str(out)],
        check=True, capture_output=True,
    )  # fmt: skip
    p = propose(open_capture(out))
    assert not p.axes, p.text()
    if pattern == "graycode":
        # a free-running Gray counter: its top two bits are quadrature at one rate, never
        # reversing or pausing, as a divider's nets are; no evidence of a motor
        why = {u.channel: u.why for u in p.unassigned}
        assert all("free-running divider" in why[c] for c in ("D6", "D7")), p.text()
