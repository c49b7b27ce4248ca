"""Axes from the scopes of hierarchical names (``top.axis_x.step``, ``top.axis_y.step``): one
axis per scope, named after it; anything less clear is left to the single-axis mapping or the
waveforms (issue 23: a simulator's dump of several step generators, checked without --map)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from tests.conftest import REPO, write_vcd
from wavecheck.roles.names import axes_by_scope, name_hint

CASES = [
    (
        ["top.axis_x.step", "top.axis_x.dir", "top.axis_y.step", "top.axis_y.dir", "top.clk"],
        [("x", {"step": "top.axis_x.step", "dir": "top.axis_x.dir"}),
         ("y", {"step": "top.axis_y.step", "dir": "top.axis_y.dir"})],
    ),
    (["hm2.stepgen.0.step", "hm2.stepgen.1.step"],
     [("0", {"step": "hm2.stepgen.0.step"}), ("1", {"step": "hm2.stepgen.1.step"})]),
    (["tb.s0.up", "tb.s0.down", "tb.s1.up", "tb.s1.down", "tb.s1.enable"],
     [("s0", {"up": "tb.s0.up", "down": "tb.s0.down"}),
      ("s1", {"up": "tb.s1.up", "down": "tb.s1.down", "enable": "tb.s1.enable"})]),
    (["step", "dir"], None),  # one axis: mapped by name as before
    (["a.step", "a.dir"], None),
    (["a.step", "b.step", "a.STEP"], None),  # two in one scope
    (["top.axis_x.step", "top.X_AXIS.step"], None),  # two scopes, one axis name
    (["x_step", "y_step"], None),  # no role leaf: the waveforms decide
]  # fmt: skip


@pytest.mark.parametrize(("names", "axes"), CASES)
def test_axes_by_scope(names: list[str], axes: list | None) -> None:
    assert axes_by_scope(names) == axes


def test_check_without_map_checks_each_scope(tmp_path: Path) -> None:
    steps = [t for k in range(50) for t in (10_000 + 20_000 * k, 15_000 + 20_000 * k)]
    path = write_vcd(
        tmp_path / "two.vcd",
        {
            "top.axis_x.step": (0, steps),
            "top.axis_x.dir": (0, []),
            "top.axis_y.step": (0, [t + 3_000 for t in steps[:40]]),
            "top.axis_y.dir": (0, []),
        },
    )
    run = subprocess.run(
        [sys.executable, "-m", "wavecheck", "check", str(path), "--drive", "gecko-g202",
         "--format", "json"],
        capture_output=True, text=True, cwd=REPO, timeout=120, check=False,
    )  # fmt: skip
    assert run.returncode == 0, run.stderr
    report = json.loads(run.stdout)
    got = {a["name"]: a["steps"]["count"] for a in report["axes"]}
    assert got == {"x": 50, "y": 20}


def test_names_give_roles_and_axes() -> None:
    cases = {
        "X_STEP": ({"step"}, "x"),
        "STEP (Y axis)": ({"step"}, "y"),
        "xstep": ({"step"}, "x"),
        "dirz": ({"dir"}, "z"),
        "stepgen.2.step": ({"step"}, "2"),
        "PUL+": ({"step"}, None),
        "EN": ({"enable"}, None),
        "phase-A": ({"phase-A"}, None),
        "D3": (set(), None),
        "A0": (set(), None),
        "ch3": (set(), None),
    }
    for name, (roles, axis) in cases.items():
        h = name_hint(name)
        assert (set(h.roles), h.axis) == (roles, axis), name
