"""stepgen options out of range: exit 2, one line, nothing written (issue 8)."""

from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from stepgen.reference import StepgenConfig
from tests.reliability.helpers import assert_no_output, cli
from wavecheck.errors import ConfigError

BASE = [
    "--base-period",
    "25us",
    "--servo-period",
    "1ms",
    "--mode",
    "velocity",
    "--velocity",
    "100",
    "--duration",
    "20ms",
]

BAD_SIMULATE = {
    "period-0": ["--base-period", "0"],
    "period-negative": ["--base-period", "-25us"],
    "period-junk": ["--base-period", "fast"],
    "servo-0": ["--servo-period", "0"],
    "servo-below-base": ["--servo-period", "10us"],
    "steplen-past-u32": ["--steplen", "5s"],
    "scale-0": ["--position-scale", "0"],
    "scale-nan": ["--position-scale", "nan"],
    "scale-inf": ["--position-scale", "inf"],
    "maxvel-negative": ["--maxvel", "-1"],
    "maxaccel-nan": ["--maxaccel", "nan"],
    "type-16": ["--type", "16"],
    "type-negative": ["--type", "-1"],
    "type-15-no-table": ["--type", "15"],
    "user-table-junk": ["--type", "15", "--user-step-type", "1,x"],
    "steplen-u32-overflow": ["--steplen", "99999999999"],
    "dirhold-negative": ["--dirhold", "-1"],
    "duration-0": ["--duration", "0"],
    "duration-negative": ["--duration", "-1s"],
    "periods-0": ["--periods", "0"],
    "latency-junk": ["--latency", "sometimes"],
    "latency-worst-bad-rule": ["--latency", "worst:11us:wobble"],
    "latency-negative": ["--latency", "uniform:-5us"],
    "seed-junk": ["--seed", "abc"],
    "command-missing-file": ["--command", "/nonexistent/cmd.csv"],
    "move-junk": ["--move", "??"],
}


@pytest.mark.parametrize("name", sorted(BAD_SIMULATE))
def test_simulate_refuses(tmp_path: Path, name: str) -> None:
    out = tmp_path / "out"
    out.mkdir()
    argv = ["simulate", *BASE, *BAD_SIMULATE[name], "-o", str(out / "trace.vcd")]
    rc, _, err = cli("stepgen", argv)
    assert rc == 2, f"exit {rc}: {err}"
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1 and "Traceback" not in err, err
    assert_no_output(out)


def test_steplen_past_the_servo_period_is_simulated_as_linuxcnc_does(tmp_path: Path) -> None:
    """LinuxCNC puts no limit on steplen against the servo period (stepgen reference §3/§4: only
    max_freq = 1e9/(steplen + stepspace) follows from it), so a faithful model simulates it."""
    rc, out, err = cli(
        "stepgen", ["simulate", *BASE, "--steplen", "2ms", "-o", str(tmp_path / "t.vcd")]
    )
    assert rc == 0, err
    assert (tmp_path / "t.vcd").exists()


def test_simulate_valid_baseline(tmp_path: Path) -> None:
    rc, _, err = cli("stepgen", ["simulate", *BASE, "-o", str(tmp_path / "t.vcd"), "-q"])
    assert rc == 0, err
    assert (tmp_path / "t.vcd").exists()


BAD_PLAN = {
    "base-period-0": ["--base-period", "0"],
    "base-period-negative": ["--base-period", "-16us"],
    "latency-negative": ["--latency", "-11us"],
    "latency-junk": ["--latency", "lots"],
    "latency-missing-file": ["--latency", "/nonexistent/latency.txt"],
    "drive-unknown": ["--drive", "no-such-drive"],
    "base-period-too-short": ["--base-period", "1ns"],
}


@pytest.mark.parametrize("name", sorted(BAD_PLAN))
def test_plan_refuses(tmp_path: Path, name: str) -> None:
    args = {"--drive": "gecko-g202", "--latency": "11us"}
    extra = BAD_PLAN[name]
    for key, value in zip(extra[::2], extra[1::2], strict=True):
        args[key] = value
    argv = ["plan"] + [x for kv in args.items() for x in kv] + ["-o", str(tmp_path / "p.txt")]
    rc, _, err = cli("stepgen", argv)
    assert rc == 2, f"exit {rc}: {err}"
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err
    assert not (tmp_path / "p.txt").exists()


_NS = st.integers(-(2**40), 2**40)


@settings(max_examples=300, deadline=None, derandomize=True)
@given(
    base=_NS,
    servo=_NS,
    steplen=_NS,
    stepspace=_NS,
    dirsetup=_NS,
    dirhold=_NS,
    scale=st.floats(allow_nan=True, allow_infinity=True),
    step_type=st.integers(-3, 20),
)
def test_config_validate_total(
    base: int, servo: int, steplen: int, stepspace: int, dirsetup: int, dirhold: int,
    scale: float, step_type: int,
) -> None:  # fmt: skip
    """Any setting: validate() passes or raises a one-line ConfigError, never anything else."""
    cfg = StepgenConfig(
        step_type=step_type,
        base_period_ns=base,
        servo_period_ns=servo,
        steplen=steplen,
        stepspace=stepspace,
        dirsetup=dirsetup,
        dirhold=dirhold,
        position_scale=scale,
    )
    try:
        cfg.validate()
    except ConfigError as err:
        assert "\n" not in str(err) and str(err)
        return
    assert base > 0 and servo >= base and scale == scale and abs(scale) not in (0.0, float("inf"))


@settings(
    max_examples=40,
    deadline=None,
    derandomize=True,
    suppress_health_check=[HealthCheck.function_scoped_fixture],
)
@given(
    option=st.sampled_from(
        ["--base-period", "--servo-period", "--steplen", "--stepspace", "--dirsetup",
         "--dirhold", "--position-scale", "--maxvel", "--maxaccel", "--duration"]
    ),
    value=st.one_of(
        st.sampled_from(["0", "-1", "1e400", "nan", "inf", "-0", "1ns", "", "1 furlong"]),
        st.integers(-(10**9), 10**9).map(str),  # bare ns: up to 1 s
    ),
)  # fmt: skip
def test_fuzz_simulate_option(tmp_path: Path, option: str, value: str) -> None:
    """Any value of one option: a trace (exit 0) or exit 2 with one line and no file."""
    # a 1..999 ns base period is valid but makes 20k..20M periods: slow, not wrong
    assume(
        not (
            option == "--base-period"
            and (value == "1ns" or value.isdigit() and 0 < int(value) < 1000)
        )
    )
    out = tmp_path / "fz"
    out.mkdir(exist_ok=True)
    for p in out.iterdir():
        p.unlink()
    argv = ["simulate", *BASE, f"{option}={value}", "--max-samples", "200000", "-q",
            "-o", str(out / "t.vcd")]  # fmt: skip
    rc, _, err = cli("stepgen", argv)
    assert rc in (0, 2), err
    assert "Traceback" not in err
    if rc == 2:
        assert len(err.strip().splitlines()) == 1, err
        assert_no_output(out)


def _limited_memory() -> None:
    import resource

    resource.setrlimit(resource.RLIMIT_AS, (3 << 30, 3 << 30))


@pytest.mark.parametrize(
    "option,value,what",
    [("--duration", "1e400", "OverflowError in update_schedule (range of 1e400 periods)"),
     ("--servo-period", "1e400", "OverflowError in motion.commands (int too large for float)")],
)  # fmt: skip
def test_simulate_huge_value_refused(tmp_path: Path, option: str, value: str, what: str) -> None:
    argv = ["simulate", *BASE, f"{option}={value}", "-q", "-o", str(tmp_path / "t.vcd")]
    try:
        rc, _, err = cli("stepgen", argv)
    except OverflowError as exc:
        raise AssertionError(f"traceback: {what}") from exc
    assert rc == 2 and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "t.vcd").exists()


def test_simulate_absurd_duration_refused(tmp_path: Path) -> None:
    """4e10 base periods are refused up front (exit 2, one line), not run into MemoryError."""
    import subprocess
    import sys

    argv = [sys.executable, "-m", "stepgen", "simulate", *BASE[:-2], "--duration", "999999s",
            "-q", "-o", str(tmp_path / "t.vcd")]  # fmt: skip
    proc = subprocess.run(
        argv, capture_output=True, text=True, timeout=120, preexec_fn=_limited_memory, check=False
    )
    assert proc.returncode == 2, proc.stderr[-500:]
    assert len(proc.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "t.vcd").exists()
