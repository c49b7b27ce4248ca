"""Role inference on HDL dumps of designs with step outputs among many other nets (issue 33): a
testbench-level dump of a parallel-port FPGA step generator with EPP handshake lines, a
gate-level netlist of a PWM controller, and a one-hot stepper sequencer with divider nets
(``tests/data/hdl``; Icarus Verilog and GHDL). Each gives exactly its step outputs, or no axis;
never a check of another line. With the names taken away, the waveforms alone must not pick a
wrong line either."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import pytest

from tests.engine_probe import options
from wavecheck.capture.edges import Capture
from wavecheck.capture.open import open_capture
from wavecheck.engine import axes_for, plan_axes
from wavecheck.errors import UsageError
from wavecheck.roles import Proposal, propose

from ..waves import renamed

HDL = Path(__file__).resolve().parents[2] / "data" / "hdl"


def _need(*tools: str) -> None:
    for tool in tools:
        if shutil.which(tool) is None:
            pytest.skip(f"needs {tool} (make system-deps)")


def _icarus(tmp: Path, source: str, *defines: str) -> Capture:
    _need("iverilog", "vvp")
    dump, exe = tmp / "dump.vcd", tmp / "sim.vvp"
    flags = [f"-D{d}" for d in defines]
    cmd = ["iverilog", "-g2012", *flags, f'-DDUMPFILE="{dump}"', "-o", str(exe), str(HDL / source)]
    subprocess.run(cmd, check=True, cwd=tmp)
    subprocess.run(["vvp", "-n", str(exe)], check=True, cwd=tmp, capture_output=True)
    return open_capture(dump)


def _lines(p: Proposal) -> set[str]:
    """Every channel some axis would check."""
    return {r.channel for a in p.axes for r in a.roles}


def _neutral(cap: Capture) -> Capture:
    return renamed(cap, [f"n{c.index}" for c in cap.channels])


def _checked(cap: Capture) -> set[int] | None:
    """The channels ``check`` (against a DRV8825, no --map) would read, or None when it
    refuses: the axes as the engine finds them (names, else waveforms), planned."""
    opts = options("drv8825")
    try:
        axes, _ = axes_for(opts, cap)
        plans = plan_axes(cap, axes, opts, cap)
    except UsageError:
        return None
    return {i for p in plans for i in p.channels}


def _named(cap: Capture, names: dict[str, str]) -> Capture:
    return renamed(cap, [names.get(c.name, c.name) for c in cap.channels])


@pytest.mark.parametrize("defines", [(), ("EPP_DATA_ONLY",)], ids=["addr+data", "data only"])
def test_parallel_port_step_generator_testbench(tmp_path: Path, defines: tuple[str, ...]) -> None:
    """Issue 33: the EPP lines were taken as a quadrature pair and failed a DRV8825, the real
    STEP outputs called "data of bus clock led". With data-only writes nDataStr and nWait walk
    quadrature in bursts at one rate: a handshake, not a motor."""
    cap = _icarus(tmp_path, "pport_stepgen.v", *defines)
    p = propose(cap)
    assert p.unambiguous, p.text()
    assert [a.mapping for a in p.axes] == [
        {"step": "step1", "dir": "dir1"},
        {"step": "step0", "dir": "dir0"},
    ]
    # without names: the step outputs or nothing, never an EPP line, the LED or the clock
    steps = {c.index for c in cap.channels if c.name in ("step0", "step1", "dir0", "dir1")}
    q = propose(_neutral(cap))
    assert {r.index for a in q.axes for r in a.roles} <= steps, q.text()
    assert not any(a.kind == "phases" for a in q.axes), q.text()
    # check reads the step outputs and nothing else, named or not; a line named after a role
    # is judged on its waveform: the bus clock called "step" is refused, not checked
    assert _checked(cap) == steps
    assert _checked(_neutral(cap)) is None  # refused: no line of it is taken for a STEP
    assert _checked(_named(cap, {"step0": "step", "dir0": "dir"})) == {
        cap.channel(n).index for n in ("step0", "dir0")
    }
    assert _checked(_named(cap, {"clk": "step"})) is None


def test_gate_level_pwm_controller_has_no_axis(tmp_path: Path) -> None:
    """Issue 33: a gate-level dump's state-machine nets and PWM output became "phase" axes. Here
    four of them walk LinuxCNC's bipolar half-step table for 47 changes with 9 reversals (a
    motor's walk goes further between reversals), and two counter nets walk quadrature at one
    rate (a divider)."""
    cap = _icarus(tmp_path, "pwm_gates.v")
    assert len(cap.channels) > 40
    for c in (cap, _neutral(cap)):
        p = propose(c)
        assert not p.axes and not p.ambiguous, p.text()
        assert _checked(c) is None
    # its PWM output or its clock called "step": refused, whatever the name says
    for line in ("pwm_out", "clk"):
        p = propose(_named(cap, {line: "step"}))
        assert not p.axes and "is named STEP, but its waveform is no STEP line" in p.text()
        assert _checked(_named(cap, {line: "step"})) is None


@pytest.mark.parametrize("dump", ["onehot.vcd", "onehot.ghw"])
def test_one_hot_stepper_sequencer(tmp_path: Path, dump: str) -> None:
    """Issue 33: two divider nets were proposed as a quadrature pair and the outputs A-D were
    missed. Here: A-D are the one axis (LinuxCNC's step type 5 table), the divider's nets walk
    quadrature at one rate (refused), the prescaler tick that drives the sequencer is its step
    request (no axis of its own), and GHDL's copies of the ports (tb.a and tb.dut.a) are one."""
    _need("ghdl")
    shutil.copy(HDL / "onehot_stepper.vhd", tmp_path)
    for cmd in (["-a", "onehot_stepper.vhd"], ["-e", "tb"]):
        subprocess.run(["ghdl", cmd[0], "--std=08", cmd[1]], check=True, cwd=tmp_path)
    subprocess.run(
        ["ghdl", "-r", "--std=08", "tb", "--vcd=onehot.vcd", "--wave=onehot.ghw"],
        check=True,
        cwd=tmp_path,
        capture_output=True,
    )
    cap = open_capture(tmp_path / dump)
    p = propose(cap)
    assert p.unambiguous, p.text()
    [axis] = p.axes
    assert (axis.kind, axis.step_type) == ("phases", 5)
    assert {r.channel for r in axis.roles if r.role.startswith("phase-")} == {
        "tb.a",
        "tb.b",
        "tb.c",
        "tb.d",
    }
    why = {u.channel: u.why for u in p.unassigned}
    assert "free-running divider" in why["div_q0"]
    assert "step request" in why["tick"]
    # without names the same axis, and no other line; the enable (3 pulses, each as long as a
    # pause) may now be asked about: a STEP of a short move, or an enable?
    q = propose(_neutral(cap))
    outputs = {c.index for c in cap.channels if c.name in ("tb.a", "tb.b", "tb.c", "tb.d")}
    [axis] = q.axes
    assert {r.index for r in axis.roles if r.role.startswith("phase-")} == outputs, q.text()
    assert {r.index for r in axis.roles} <= outputs | {cap.channel("tb.en").index}
    assert _checked(cap) == outputs | {cap.channel("tb.en").index}
    assert _checked(_neutral(cap)) is None  # the enable asked about: refused
