"""What ``--plot`` writes and draws (issue 26).

- A figure is written in the format its file name says (``out.jpg`` was PNG bytes): PNG, JPEG,
  SVG or PDF, whichever command draws it; any other extension is refused before any work, in
  one line, and nothing is written.
- A step/dir axis without DIR has no position: the motion panel says "no DIR: position unknown"
  instead of a flat line at 0 (``check --plot`` and ``measure --plot``); the figure's title
  names the rules that were not checked, as the verdict line does.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest

from stepgen.cli import main as stepgen_main
from wavecheck.cli import main as wavecheck_main
from wavecheck.report.claims import verdict_line


def _exit(main: Callable[[list[str]], int], argv: list[str]) -> int:
    """The exit code of a command (argparse's usage errors exit through SystemExit)."""
    try:
        return main(argv)
    except SystemExit as done:
        return int(done.code or 0)


def wavecheck(argv: list[str]) -> int:
    return _exit(wavecheck_main, argv)


def stepgen(argv: list[str]) -> int:
    return _exit(stepgen_main, argv)


REPO = Path(__file__).resolve().parents[3]
GOLDEN = REPO / "captures" / "golden" / "g202-p20-worst-dirhold.vcd"
TWO_AXES = REPO / "captures" / "examples" / "two-axis.vcd"
#: The first bytes of each format (PNG signature, JPEG SOI marker, PDF header, SVG's XML).
MAGIC = {".png": b"\x89PNG\r\n", ".jpg": b"\xff\xd8\xff", ".jpeg": b"\xff\xd8\xff",
         ".pdf": b"%PDF-", ".svg": b"<?xml"}  # fmt: skip

COMMANDS = {
    "check": lambda out: wavecheck(["check", str(GOLDEN), "--drive", "gecko-g202", "--plot", out]),
    "measure": lambda out: wavecheck(["measure", str(GOLDEN), "--plot", out]),
    "latency": lambda out: wavecheck(["latency", str(GOLDEN), "--plot", out]),
    "simulate --pid": lambda out: stepgen(
        [
            "simulate",
            "--pid",
            "--move",
            "1",
            "--move-vel",
            "20",
            "--move-accel",
            "200",
            "--duration",
            "50ms",
            "-o",
            str(Path(out).with_suffix(".vcd")),
            "--plot",
            out,
        ]
    ),  # fmt: skip
}


@pytest.mark.parametrize(
    ("command", "suffix"),
    [("check", s) for s in sorted(MAGIC)]  # every format once; then one per other command
    + [
        (c, s)
        for c, s in zip(sorted(set(COMMANDS) - {"check"}), [".jpg", ".pdf", ".svg"], strict=True)
    ],
)
def test_the_file_name_says_the_format(
    command: str, suffix: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / f"fig{suffix}"
    assert COMMANDS[command](str(out)) in (0, 1, 3)
    assert out.read_bytes().startswith(MAGIC[suffix])
    if suffix == ".svg":
        assert b"<svg" in out.read_bytes()[:2000]


@pytest.mark.parametrize("command", sorted(COMMANDS))
def test_an_unknown_extension_is_refused_before_any_work(
    command: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    capsys.readouterr()
    out = tmp_path / "fig.gif"
    assert COMMANDS[command](str(out)) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert "a figure is written as PNG, JPEG, SVG or PDF, not GIF" in err
    assert list(tmp_path.iterdir()) == []  # nothing written, not even the VCD


def test_tune_and_follow_take_the_same_figure_names(tmp_path: Path, capsys) -> None:
    assert stepgen(["tune", "--plot", str(tmp_path / "t.bmp")]) == 2
    assert "not BMP" in capsys.readouterr().err
    assert wavecheck(["follow", str(GOLDEN), "--command", str(GOLDEN), "--plot",
                      str(tmp_path / "f.tiff")]) == 2  # fmt: skip
    assert "not TIFF" in capsys.readouterr().err


def _texts(fig: object) -> list[str]:
    return [t.get_text() for ax in fig.axes for t in ax.texts]  # type: ignore[attr-defined]


def test_without_dir_the_position_is_unknown_not_a_flat_line() -> None:
    import wavecheck as wc
    from wavecheck.report.plot import figure

    report = wc.check(TWO_AXES, "gecko-g202", map={"step": "x_step"}, pictures=True)
    fig = figure(report)
    pos = next(ax for ax in fig.axes if ax.get_title(loc="left").startswith("steps: position"))
    assert pos.get_title(loc="left") == "steps: position unknown (no DIR)"
    assert [t.get_text() for t in pos.texts] == ["no DIR: position unknown"]
    assert pos.get_lines() == []  # no position drawn at all
    assert pos.get_xlabel() == "time (s); 4 steps, none of known direction"
    title = fig._suptitle.get_text()  # noqa: SLF001 - the figure's title
    assert title.splitlines()[1] == verdict_line(report)[len("PASS ") :]
    assert "dir_setup, dir_hold not checked: no DIR channel" in title
    # with DIR, the same axis's position is drawn: 4 steps to +2, one reversal
    with_dir = figure(wc.check(TWO_AXES, "gecko-g202", map={"step": "x_step", "dir": "x_dir"},
                               pictures=True))  # fmt: skip
    pos = next(a for a in with_dir.axes if a.get_title(loc="left").startswith("steps: position"))
    assert pos.get_title(loc="left") == "steps: position, 1 reversal(s)"
    assert "no DIR: position unknown" not in _texts(with_dir)
    assert max(pos.get_lines()[0].get_ydata()) == 2


def test_measure_says_it_too(grbl_sr: Path) -> None:
    """The grbl capture of sigrok-dumps: 10,508 steps, no DIR channel."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    from matplotlib.figure import Figure

    from wavecheck.capture.open import open_source
    from wavecheck.engine import CheckOptions
    from wavecheck.measurement import measure
    from wavecheck.report.measured_plot import draw_motion, position_unknown
    from wavecheck.steps.mapping import AxisMap

    m = measure(open_source(grbl_sr), CheckOptions(axes=(AxisMap(None, {"step": "1"}),)))
    (a,) = m.axes
    assert (
        a.steps.count == 10_508 and position_unknown(a.step_type, a.interface, a.steps) == "no DIR"
    )
    fig = Figure()
    pos, rate = fig.subplots(1, 2)
    draw_motion(pos, rate, a.trace, m.capture.timebase, "axis", "no DIR")
    assert [t.get_text() for t in pos.texts] == ["no DIR: position unknown"] and not pos.get_lines()
    assert pos.get_xlabel() == "time (s); 10,508 steps, none of known direction"
