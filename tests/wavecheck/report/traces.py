"""A stepgen-like STEP/DIR trace built by construction (no simulator needed).

LinuxCNC stepgen, step type 0, steplen = stepspace = dirsetup = dirhold = 1 base period, STEP
pin not inverted, run under the worst case for ``dir_hold``: every invocation that makes a STEP
edge runs ``J`` late, every one that changes DIR runs on time. Against a Gecko G202 (steps on the
falling edge, i.e. the end of stepgen's pulse) every DIR hold is then ``P − J`` long: the
seed's 9 µs at P = 20 µs, J = 11 µs.
"""

from __future__ import annotations

from pathlib import Path

from tests.conftest import write_vcd


def stepgen_trace(
    moves: tuple[int, ...] = (30, -30, 30, -30),
    period_ns: int = 20_000,
    latency_ns: int = 11_000,
) -> dict[str, tuple[int, list[int]]]:
    """Edges (ns) of STEP and DIR for ``moves`` (signed step counts, one run per move)."""
    step: list[int] = []
    dirs: list[int] = []
    k = 2  # base period counter
    direction = 1
    for m in moves:
        want = 1 if m > 0 else -1
        if want != direction:
            dirs.append(k * period_ns)  # on time (dirhold = 1 after the last fall)
            k += 1  # dirsetup = 1
            direction = want
        for _ in range(abs(m)):
            step += [k * period_ns + latency_ns, (k + 1) * period_ns + latency_ns]
            k += 2  # steplen + stepspace
    return {"STEP": (0, step), "DIR": (0, dirs)}


def write_stepgen_vcd(path: Path, **kw: object) -> Path:
    """Write :func:`stepgen_trace` as a 1 ns VCD (signals ``STEP``, ``DIR``)."""
    return write_vcd(path, stepgen_trace(**kw))  # type: ignore[arg-type]
