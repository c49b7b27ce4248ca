"""Channel mapping never silently changes what is checked (issue 12).

A repeated role and one channel in two roles are usage errors (until several axes get a
meaning); a name two channels share is ambiguous (map by index); a partial hierarchical name
resolves when it is unique and says "ambiguous: candidates …" when not, never "no channel".
"""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.engine_probe import run_check
from tests.reliability.helpers import cli
from tests.wavecheck.waves import capture, drive, pulses
from wavecheck.errors import UsageError
from wavecheck.steps.interface import build_interface, parse_map

US = 1000

#: --map values → the words the error must contain
BAD_MAPS: list[tuple[list[str], list[str]]] = [
    (["step=3,dir=4", "step=5,dir=6"], ["role step is mapped twice", "step=3", "step=5"]),
    (["step=3,dir=4,step=5"], ["role step is mapped twice", "step=3", "step=5"]),
    (["dir=1", "step=0,dir=1"], ["role dir is mapped twice"]),
    (["step=3,dir=3"], ["channel '3' is mapped as both step and dir"]),
    (["step=STEP", "enable=STEP"], ["channel 'STEP' is mapped as both step and enable"]),
]


@pytest.mark.parametrize(("items", "words"), BAD_MAPS, ids=[" ".join(i) for i, _ in BAD_MAPS])
def test_parse_map_refuses_repeats(items: list[str], words: list[str]) -> None:
    with pytest.raises(UsageError) as info:
        parse_map(items)
    for word in words:
        assert word in str(info.value)
    assert "several axes are named" in str(info.value) or "one channel can have one role" in str(
        info.value
    )


def test_parse_map_keeps_commas_in_names() -> None:
    assert parse_map(["step=STEP (Y, left),dir=3"]) == {"step": "STEP (Y, left)", "dir": "3"}


def _vcd(tmp_path: Path, names: list[str]) -> Path:
    """A VCD of channels ``names`` (dotted names become scopes); each ``*.step`` has one 2 us
    pulse, the others stay low."""
    lines = ["$timescale 1 ns $end"]
    for i, name in enumerate(names):
        *scopes, leaf = name.split(".")
        lines += [f"$scope module {s} $end" for s in scopes]
        lines.append(f"$var wire 1 {chr(33 + i)} {leaf} $end")
        lines += ["$upscope $end"] * len(scopes)
    lines += ["$enddefinitions $end", "#0", "$dumpvars"]
    lines += [f"0{chr(33 + i)}" for i in range(len(names))]
    steps = [chr(33 + i) for i, n in enumerate(names) if n.endswith(".step")]
    lines += ["$end", "#10000"] + [f"1{c}" for c in steps]
    lines += ["#12000"] + [f"0{c}" for c in steps] + ["#20000"]
    path = tmp_path / "m.vcd"
    path.write_text("\n".join(lines) + "\n")
    return path


CLI_MAPS: list[tuple[list[str], str]] = [
    (["--map", "step=0,dir=1", "--map", "step=2,dir=3"], "role step is mapped twice"),
    (["--map", "step=0,dir=1,step=2"], "role step is mapped twice"),
    (["--map", "step=0,dir=0"], "mapped as both step and dir"),
    (["--map", "step=0,dir=tb.s1.step"], "channel 0 'tb.s1.step' is mapped as both step and dir"),
    (["--map", "step=step"], "ambiguous: candidates 0='tb.s1.step', 2='tb.s2.step'"),
    (["--map", "step=S1.STEP,dir=dir"], "ambiguous: candidates 1='tb.s1.dir', 3='tb.s2.dir'"),
]


@pytest.mark.parametrize(("argv", "says"), CLI_MAPS, ids=[" ".join(a[1:]) for a, _ in CLI_MAPS])
def test_check_refuses_a_mapping_that_would_change_what_is_checked(
    tmp_path: Path, argv: list[str], says: str
) -> None:
    vcd = _vcd(tmp_path, ["tb.s1.step", "tb.s1.dir", "tb.s2.step", "tb.s2.dir"])
    rc, _, err = cli("wavecheck", ["check", str(vcd), "--drive", "a4988", *argv])
    assert rc == 2 and len(err.strip().splitlines()) == 1, err
    assert says in err and "no channel" not in err, err


@pytest.mark.parametrize(
    ("ref", "name"),
    [("s2.step", "tb.s2.step"), ("tb.s2.step", "tb.s2.step"), ("S2.STEP", "tb.s2.step"),
     ("s1.dir", "tb.s1.dir"), ("2", "tb.s2.step")],
)  # fmt: skip
def test_a_unique_partial_hierarchical_name_resolves(tmp_path: Path, ref: str, name: str) -> None:
    from wavecheck.capture.vcd import read_vcd
    from wavecheck.steps.interface import find_channel

    cap = read_vcd(_vcd(tmp_path, ["tb.s1.step", "tb.s1.dir", "tb.s2.step", "tb.s2.dir"]))
    assert find_channel(cap, ref).name == name


def test_partial_names_check_the_axis_named(tmp_path: Path) -> None:
    vcd = _vcd(tmp_path, ["tb.s1.step", "tb.s1.dir", "tb.s2.step", "tb.s2.dir"])
    rc, out, err = cli(
        "wavecheck", ["check", str(vcd), "--drive", "a4988", "--map", "step=s2.step,dir=s2.dir"]
    )
    assert rc == 0, err
    assert "step='tb.s2.step', dir='tb.s2.dir'" in out


def test_a_name_two_channels_share_is_ambiguous() -> None:
    cap = capture({"x": (0, []), "y": (0, [])})
    dup = capture({"a": (0, [10, 20]), "b": (0, []), "c": (0, [5, 50])})
    dup.channels[0].name = dup.channels[2].name = "STEP"
    dup.channels[1].name = "DIR"
    with pytest.raises(
        UsageError, match=r"ambiguous: indices 0 and 2 are both 'STEP'; map by index"
    ):
        build_interface(dup, {"step": "STEP"})
    with pytest.raises(UsageError, match=r"ambiguous: indices 0, 2 share the name"):
        dup.channel("STEP")  # the capture's own lookup never takes the first either
    assert build_interface(dup, {"step": "2"}).require("step").edges.tolist() == [5, 50]
    assert build_interface(cap, {"step": "y"}).require("step").channel == "y"


def test_auto_map_does_not_give_a_mapped_channel_a_second_role() -> None:
    """--map step=DIR on a capture with channels STEP and DIR: DIR is the step line, and is not
    also taken as the DIR role by its name (that would check a line against itself)."""
    cap = capture({"STEP": (0, []), "DIR": (0, pulses([10 * US, 20 * US], 2 * US))})
    report = run_check(cap, drive(step_high=1 * US), {"step": "DIR"})
    assert report.interface.require("step").channel == "DIR"
    assert report.interface.get("dir") is None
    assert report.steps.count == 2
