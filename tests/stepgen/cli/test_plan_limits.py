"""``stepgen plan --limit RULE=T --margin 2x|+T`` (issue 26): the drives that give no DIR hold
figure (Leadshine DM542, StepperOnline DM542T; the TB6600 gives no DIR figure at all) were
refused with no way to plan them; the refusal now says how to give the figure, and
``--limit``/``--margin`` change the figures as for ``wavecheck check`` and ``config``
(:mod:`wavecheck.drives.overrides`)."""

from __future__ import annotations

import json

import pytest

from stepgen.cli import main

#: The figures each drive's rule file lacks for a plan (rules/*.toml).
MISSING = {
    "leadshine-dm542": ["dir_hold"],
    "stepperonline-dm542t": ["dir_hold"],
    "tb6600": ["dir_setup", "dir_hold"],
}


def run(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    code = main(["plan", *argv])
    out, err = capsys.readouterr()
    return code, out, err


@pytest.mark.parametrize("drive", sorted(MISSING))
def test_the_refusal_says_how_to_give_the_figure(drive: str, capsys) -> None:
    code, out, err = run(capsys, "--drive", drive, "--latency", "11us")
    assert code == 2 and out == ""
    assert err.count("\n") == 1
    missing = MISSING[drive]
    assert f"gives no {', '.join(missing)} figure" in err
    assert " ".join(f"--limit {r}=T" for r in missing) in err
    assert f'extends = "{drive}"' in err


@pytest.mark.parametrize("drive", sorted(MISSING))
def test_limit_gives_the_missing_figure(drive: str, capsys) -> None:
    limits = [a for r in MISSING[drive] for a in ("--limit", f"{r}=5us")]
    code, out, _ = run(capsys, "--drive", drive, "--latency", "11us", *limits, "--format", "json")
    assert code == 0
    margins = json.loads(out)["margins_ns"]
    assert set(MISSING[drive]) <= set(margins)


def test_margin_tightens_every_figure_and_the_report_says_so(capsys) -> None:
    base = ["--drive", "leadshine-dm542", "--latency", "11us", "--limit", "dir_hold=5us"]
    code, plain, _ = run(capsys, *base, "--format", "json")
    code2, doubled, _ = run(capsys, *base, "--margin", "2x", "--format", "json")
    assert code == code2 == 0
    # J + the longer of step high/low: 11 + 2.5 us, and 11 + 2 × 2.5 us with the margin
    assert json.loads(plain)["min_base_period_ns"] == 13_500
    assert json.loads(doubled)["min_base_period_ns"] == 16_000
    code, text, _ = run(capsys, *base, "--margin", "2x")
    assert "figures changed on the command line (the table uses them):" in text
    assert "  step_high: 5000 ns applied (--margin 2x); datasheet 2500 ns" in text
    assert "  dir_hold: 5000 ns applied (--limit dir_hold=5us); datasheet none" in text
    code, hal, _ = run(capsys, *base, "--format", "hal")
    assert "# dir_hold: 5000 ns applied (--limit dir_hold=5us); datasheet none" in hal


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--limit", "dir_hld=5us"], "--limit 'dir_hld=5us': write RULE=VALUE"),
        (["--limit", "dir_hold=5"], "dir_hold=5"),
        (["--margin", "0.5x"], "a factor below 1 would loosen the limits"),
    ],
)
def test_bad_limit_or_margin_is_one_line(argv: list[str], message: str, capsys) -> None:
    code, out, err = run(capsys, "--drive", "gecko-g202", "--latency", "11us", *argv)
    assert code == 2 and out == "" and message in err and err.count("\n") == 1
