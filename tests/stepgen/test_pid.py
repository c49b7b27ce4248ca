"""LinuxCNC's pid against every test vector of shared/reference/pid-linuxcnc.md §5, exactly.

Each row is one ``do-pid-calcs`` call at N = 1 000 000 ns on a fresh instance; the expected
numbers are the reference's Python reprs of the compiled pid.c's doubles, compared with ``==``.
"""

from __future__ import annotations

import math

import pytest

from stepgen.pid import SATURATED_COUNT_MAX, Pid, PidGains

N = 1_000_000

# (k, en, command, feedback, error, errorI, errorD, commandD, output)
VECTOR_A = [
    (0, 0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0),
    (1, 1, 0.002, 0.0, 0.0, 0.0, 2.0, 2.0, 0.0),
    (
        2,
        1,
        0.006,
        0.0003,
        0.0017000000000000001,
        1.2000000000000002e-06,
        3.7,
        4.0,
        1.2000000000000002,
    ),
    (
        3,
        1,
        0.012,
        0.0041,
        0.0018999999999999998,
        2.5999999999999997e-06,
        2.1999999999999997,
        6.0,
        1.3999999999999997,
    ),
    (4, 1, 0.02, 0.0052, 0.0068000000000000005, 7.100000000000001e-06, 6.9, 8.0, 4.500000000000001),
    (
        5,
        1,
        0.02,
        0.0185,
        0.0015000000000000013,
        8.100000000000002e-06,
        -13.299999999999999,
        0.0,
        1.0000000000000013,
    ),
    (
        6,
        1,
        0.02,
        0.0212,
        -0.0011999999999999997,
        7.400000000000002e-06,
        -2.700000000000001,
        0.0,
        -0.6999999999999996,
    ),
    (
        7,
        1,
        0.02,
        0.0203,
        -0.0002999999999999982,
        7.400000000000002e-06,
        0.9000000000000015,
        0.0,
        0.0,
    ),
]
# (k, en, command, feedback, error, errorI, errorD, commandD, output, saturated, count)
VECTOR_B = [
    (0, 0, 0.01, 0.0, 0.01, 0.0, 10.0, 10.0, 0.0, 0, 0),
    (1, 1, 0.01, 0.0, 0.01, 1e-05, 0.0, 0.0, 0.52, 0, 0),
    (2, 1, 0.01, 0.0, 0.01, 2e-05, 0.0, 0.0, 0.535, 1, 1),
    (3, 1, 0.01, 0.0, 0.01, 2e-05, 0.0, 0.0, 0.535, 1, 2),
    (4, 1, 0.01, 0.002, 0.008, 2e-05, -2.0, 0.0, 0.44, 0, 0),
    (5, 1, 0.01, 0.006, 0.004, 2.2e-05, -4.0, 0.0, 0.244, 0, 0),
    (
        6,
        1,
        0.01,
        0.0098,
        0.00020000000000000052,
        2.2e-05,
        -3.7999999999999994,
        0.0,
        0.05400000000000002,
        0,
        0,
    ),
    (
        7,
        1,
        0.01,
        0.0103,
        -0.0002999999999999999,
        2.17e-05,
        -0.5000000000000004,
        0.0,
        0.028400000000000005,
        0,
        0,
    ),
    (
        8,
        1,
        0.01,
        0.0101,
        -9.99999999999994e-05,
        2.16e-05,
        0.2000000000000005,
        0.0,
        0.03820000000000003,
        0,
        0,
    ),
]
VECTOR_C = [
    (0, 0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0),
    (1, 1, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0),
    (2, 1, 0.005, 0.0, 0.0, 0.0, 5.0, 5.0, 6.0),
    (3, 1, 0.015, 0.004, 0.001, 1e-06, 5.999999999999998, 9.999999999999998, 12.199999999999998),
    (
        4,
        1,
        0.025,
        0.0142,
        0.0007999999999999986,
        1.7999999999999986e-06,
        -0.1999999999999993,
        10.000000000000002,
        10.76,
    ),
    (
        5,
        1,
        0.035,
        0.0251,
        -9.99999999999994e-05,
        1.6999999999999992e-06,
        -0.8999999999999986,
        10.000000000000002,
        9.720000000000002,
    ),
    (
        6,
        1,
        0.045,
        0.0349,
        0.00010000000000000286,
        1.800000000000002e-06,
        0.19999999999999574,
        9.999999999999995,
        10.139999999999997,
    ),
    (
        7,
        1,
        0.05,
        0.0452,
        -0.0001999999999999988,
        1.6000000000000033e-06,
        -5.299999999999993,
        5.000000000000004,
        3.7400000000000073,
    ),
    (
        8,
        1,
        0.05,
        0.0501,
        -9.999999999999593e-05,
        1.5000000000000074e-06,
        -4.900000000000001,
        0.0,
        -1.0799999999999963,
    ),
]
# (k, en, ie, command, feedback, error, errorI, errorD, commandD, output)
VECTOR_D = [
    (0, 0, 1, 1.0, 1.0, -1.0, 0.0, 0.0, 1000.0, 0.0),
    (
        1,
        1,
        1,
        1.002,
        1.0015,
        -0.0015000000000000568,
        -1.5000000000000568e-06,
        0.49999999999994493,
        2.0000000000000018,
        0.49999999999994493,
    ),
    (
        2,
        1,
        1,
        1.004,
        1.0035,
        -0.0015000000000000568,
        -3.0000000000001136e-06,
        0.0,
        2.0000000000000018,
        0.49999999999994493,
    ),
    (
        3,
        1,
        1,
        1.006,
        1.0052,
        -0.0012000000000000899,
        -4.200000000000204e-06,
        0.29999999999996696,
        2.0000000000000018,
        0.7999999999999119,
    ),
    (
        4,
        1,
        0,
        0.008,
        0.0074,
        0.0005999999999999998,
        -3.600000000000204e-06,
        0.29999999999996696,
        2.0000000000000018,
        2.6000000000000014,
    ),
    (
        5,
        1,
        0,
        0.01,
        0.0095,
        -0.0014999999999999996,
        -5.100000000000204e-06,
        -0.09999999999999964,
        2.0,
        0.5000000000000004,
    ),
]

GAINS = {
    "A": PidGains(Pgain=1000.0, deadband=0.0005, maxerror=0.005),
    "B": PidGains(
        Pgain=50.0, Igain=2000.0, maxerrorI=2.2e-5, maxoutput=0.535, error_previous_target=False
    ),
    "C": PidGains(Pgain=1000.0, Dgain=0.2, FF1=1.0),
    "D": PidGains(Pgain=1000.0, FF1=1.0),
}


def _rows() -> list[tuple[str, int, dict[str, float], dict[str, float]]]:
    """(vector, k, inputs, expected pins) for every row of every vector."""
    out = []
    for name, table in (("A", VECTOR_A), ("B", VECTOR_B), ("C", VECTOR_C)):
        for row in table:
            k, en, c, f, err, ei, ed, cd, u = row[:9]
            expect = {"error": err, "errorI": ei, "errorD": ed, "commandD": cd, "output": u}
            if name == "B":
                expect["saturated"] = row[9]
                expect["saturated_count"] = row[10]
            out.append((name, k, {"enable": en, "ie": 0, "command": c, "feedback": f}, expect))
    for k, en, ie, c, f, err, ei, ed, cd, u in VECTOR_D:
        expect = {"error": err, "errorI": ei, "errorD": ed, "commandD": cd, "output": u}
        out.append(("D", k, {"enable": en, "ie": ie, "command": c, "feedback": f}, expect))
    return out


ROWS = _rows()


def _run(name: str, upto: int) -> Pid:
    pid = Pid(GAINS[name])
    for vec, k, inp, _ in ROWS:
        if vec == name and k <= upto:
            pid.calc(
                N,
                inp["command"],
                inp["feedback"],
                bool(inp["enable"]),
                index_enable=bool(inp["ie"]),
            )
    return pid


@pytest.mark.parametrize(
    ("vector", "k", "inputs", "expect"), ROWS, ids=[f"{r[0]}-k{r[1]}" for r in ROWS]
)
def test_reference_vector_row(vector: str, k: int, inputs: dict, expect: dict) -> None:
    """pid-linuxcnc.md §5: each pin after call k equals the compiled pid.c's double exactly."""
    pid = _run(vector, k)
    got = {name: getattr(pid, name) for name in expect}
    got = {n: (int(v) if n.startswith("saturated") else v) for n, v in got.items()}
    assert got == expect
    for name, value in got.items():  # == on floats, and the same repr (no -0.0 vs 0.0 slips)
        if isinstance(value, float):
            assert repr(value) == repr(expect[name]) or value == expect[name] == 0.0


def test_vector_c_commanddd_rounding_residue() -> None:
    """§5 C, k4: commandDD is the rounding residue 3.552713678800501e-12 (the bit-exact path)."""
    assert _run("C", 4).commandDD == 3.552713678800501e-12


def test_defaults_are_linuxcnc_s() -> None:
    """§1/§6.2: Pgain defaults to 1.0, error-previous-target to TRUE, everything else 0."""
    g = PidGains()
    assert (g.Pgain, g.error_previous_target, g.Igain, g.maxoutput) == (1.0, True, 0.0, 0.0)
    assert "error-previous-target" in PidGains.pin_names()


def test_stale_limit_state_when_maxoutput_is_cleared() -> None:
    """§6.3: maxoutput set to 0 while saturated leaves limit_state, so saturated keeps counting
    and integration stays blocked in that direction until the loop is disabled."""
    from dataclasses import replace

    pid = Pid(PidGains(Pgain=100.0, maxoutput=0.1, error_previous_target=False))
    pid.calc(N, 1.0, 0.0)
    assert pid.saturated and pid.limit_state == 1
    pid.gains = replace(pid.gains, maxoutput=0.0)
    before = pid.errorI
    pid.calc(N, 1.0, 0.0)
    assert pid.saturated and pid.saturated_count == 2 and pid.errorI == before
    pid.calc(N, 1.0, 0.0, enable=False)
    assert not pid.saturated and pid.saturated_count == 0 and pid.errorI == 0.0


def test_disabled_drops_bias_and_nan_error_is_deadbanded() -> None:
    """§2 consequences: disabled → output 0 (no bias); a NaN error becomes 0 in the deadband
    but a NaN feedback still reaches the output through errorD."""
    pid = Pid(PidGains(bias=0.5))
    assert pid.calc(N, 0.0, 0.0, enable=False) == 0.0
    assert pid.calc(N, 0.0, 0.0) == 0.5
    pid = Pid(PidGains(Pgain=0.0))
    out = pid.calc(N, 0.0, math.nan)
    assert math.isnan(out) and pid.errorI == 0.0


def test_saturated_count_stops_at_s32_max() -> None:
    """§2 step 17: saturated-count stops at 2^31 − 1."""
    pid = Pid(PidGains(Pgain=100.0, maxoutput=0.1, error_previous_target=False))
    pid.saturated_count = SATURATED_COUNT_MAX - 1
    pid.limit_state = 1
    pid.calc(N, 1.0, 0.0)
    pid.calc(N, 1.0, 0.0)
    assert pid.saturated_count == SATURATED_COUNT_MAX


def test_ideal_plant_sanity_sequences() -> None:
    """§5 closing check: with f ← f + T·output and a 0.01 step, P = 1/T is deadbeat, P = 2/T
    oscillates with constant amplitude, P = 1.5/T halves the error each period."""
    for p, expect in ((1000.0, [0, 0.01, 0, 0, 0]), (2000.0, [0, 0.01, -0.01, 0.01, -0.01])):
        pid, f, errs = Pid(PidGains(Pgain=p)), 0.0, []
        for _ in range(5):
            u = pid.calc(N, 0.01, f)
            errs.append(pid.error)
            f += 1e-3 * u
        assert errs == pytest.approx(expect, abs=1e-15)
    pid, f, errs = Pid(PidGains(Pgain=1500.0)), 0.0, []
    for _ in range(6):
        u = pid.calc(N, 0.01, f)
        errs.append(pid.error)
        f += 1e-3 * u
    assert [e / errs[1] for e in errs[1:]] == pytest.approx([1, -0.5, 0.25, -0.125, 0.0625])
