"""VCD/.sr output, the CLI contract (exit 2, nothing written) and the golden files."""

from __future__ import annotations

import filecmp
import gc
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

from stepgen.cli import main
from tools.golden import GOLDEN, SCENARIOS, generate

S0 = [
    "simulate",
    "--base-period",
    "100us",
    "--servo-period",
    "100us",
    "--position-scale",
    "32000",
    "--maxvel",
    "0.15",
    "--maxaccel",
    "2",
    "--position",
    "0.04",
    "--periods",
    "3500",
    "-q",
]


def test_vcd_has_pins_counts_and_a_final_timestamp(tmp_path: Path) -> None:
    out = tmp_path / "s0.vcd"
    assert main([*S0, "-o", str(out)]) == 0
    text = out.read_text()
    assert "$timescale 1 ns $end" in text and "$date" not in text
    for var in ("step", "dir", "counts"):
        assert f" {var} $end" in text
    lines = text.split()
    assert lines[-1] == "#350000000"  # 3500 periods of 100 µs
    assert "#3900000" in lines  # first rising edge at index 39 (§8)


def test_sr_is_srzip_with_an_exact_rate(tmp_path: Path) -> None:
    out = tmp_path / "s0.sr"
    assert main([*S0, "-o", str(out)]) == 0
    with zipfile.ZipFile(out) as z:
        assert z.read("version") == b"2"
        meta = z.read("metadata").decode()
        raw = z.read("logic-1-1")
    assert "samplerate=10 kHz" in meta and "probe1=step" in meta and "probe2=dir" in meta
    assert len(raw) == 3500
    assert raw[39] == 1 and raw[38] == 0


@pytest.mark.parametrize(
    "bad",
    [
        ["--base-period", "0"],
        ["--position-scale", "0"],
        ["--steplen", "5s"],  # more than a u32 of ns
        ["--steplen", "-5"],
        ["--latency", "sometimes"],
        ["--type", "16"],
    ],
)
def test_bad_settings_exit_2_and_write_nothing(tmp_path: Path, bad: list[str], capsys) -> None:  # type: ignore[no-untyped-def]
    out = tmp_path / "x.vcd"
    args = [
        "simulate",
        "--mode",
        "velocity",
        "--velocity",
        "1",
        "--duration",
        "10ms",
        *bad,
        "-o",
        str(out),
    ]
    assert main(args) == 2
    assert not out.exists() and not list(tmp_path.iterdir())
    err = capsys.readouterr().err.strip()
    assert err.startswith("stepgen: error:") and "\n" not in err


def test_sr_refuses_too_many_samples(tmp_path: Path) -> None:
    out = tmp_path / "x.sr"
    args = [
        "simulate",
        "--mode",
        "velocity",
        "--velocity",
        "100",
        "--duration",
        "100ms",
        "--latency",
        "uniform:3",
        "--max-samples",
        "1000",
        "-o",
        str(out),
    ]
    assert main(args) == 2
    assert not out.exists()


@pytest.mark.parametrize("sc", SCENARIOS[:3], ids=lambda s: s.name)
def test_golden_files_are_reproduced(tmp_path: Path, sc) -> None:  # type: ignore[no-untyped-def]
    generate(sc, tmp_path)
    for ext in ("vcd", "toml"):
        assert filecmp.cmp(
            GOLDEN / f"{sc.name}.{ext}", tmp_path / f"{sc.name}.{ext}", shallow=False
        )


def test_golden_set_is_small() -> None:
    assert sum(p.stat().st_size for p in GOLDEN.iterdir()) < 2_000_000


def test_simulation_and_vcd_writing_report_progress(tmp_path: Path) -> None:
    """A long run reports its progress through wavecheck.progress (the CLI draws the bar)."""
    from stepgen.motion import Motion
    from stepgen.reference import StepgenConfig
    from stepgen.simulate import simulate as run_sim
    from stepgen.vcdout import write_vcd as write
    from wavecheck.progress import _ACTIVE

    seen: list[tuple[int, int | None]] = []
    token = _ACTIVE.set(lambda done, total=None: seen.append((done, total)))
    try:
        cfg = StepgenConfig(mode="velocity", maxvel=1000.0, maxaccel=10_000.0)
        trace = run_sim(cfg, Motion("velocity", value=500.0), n_periods=400_000)
        sim_reports = len(seen)
        write(trace, tmp_path / "t.vcd")
    finally:
        _ACTIVE.reset(token)
    assert sim_reports >= 5  # 10,000 servo periods, a report every 1024
    assert all(total == 400_000 for _, total in seen[:sim_reports])
    assert seen[-1][0] == seen[-1][1]  # the writer ends at its total


def test_the_program_writes_what_main_with_argv_writes(tmp_path: Path) -> None:
    """``python -m stepgen`` (main() as the program: the collector tuned, objects frozen at the
    end) writes the same bytes as main(argv) in this process, which leaves the collector as it
    was."""
    args = ["simulate", "--move", "0.02", "--position-scale", "1000", "--maxvel", "0.5",
            "--maxaccel", "20", "--latency", "uniform:5us", "--seed", "3", "-q"]  # fmt: skip
    before = gc.get_threshold()
    assert main([*args, "-o", str(tmp_path / "a.vcd")]) == 0
    assert gc.get_threshold() == before
    run = subprocess.run(
        [sys.executable, "-m", "stepgen", *args, "-o", str(tmp_path / "b.vcd")],
        capture_output=True, text=True, check=False,
    )  # fmt: skip
    assert run.returncode == 0, run.stderr
    assert (tmp_path / "a.vcd").read_bytes() == (tmp_path / "b.vcd").read_bytes()
