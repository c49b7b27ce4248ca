"""``wavecheck crosscheck``: sigrok-cli's counter/stepper_motor against wavecheck's decode."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from tests.reliability.helpers import assert_no_output, cli

pytestmark = pytest.mark.sigrok
GOLDEN = Path(__file__).resolve().parents[2] / "captures" / "golden"


@pytest.fixture(autouse=True)
def _need_sigrok() -> None:
    if shutil.which("sigrok-cli") is None:
        pytest.skip("sigrok-cli not installed (make system-deps)")


def _json(argv: list[str]) -> tuple[int, dict]:
    rc, out, err = cli("wavecheck", ["crosscheck", *argv, "--format", "json"])
    assert rc in (0, 1), err
    return rc, json.loads(out)


@pytest.mark.parametrize("axis,step,dir_", [("X", "5", "6"), ("Y", "3", "4")])
def test_smoothieware(smoothie_sr: Path, axis: str, step: str, dir_: str) -> None:
    rc, doc = _json([str(smoothie_sr), "--map", f"step={step},dir={dir_}"])
    assert rc == 0 and doc["agree"], doc["disagreements"]
    assert doc["wavecheck_steps"] == doc["sigrok_count"] == 739
    # N steps, N-1 position lines; the last one shows the position before the last step
    assert doc["sigrok_position_lines"] == 738
    assert doc["sigrok_last_position"] == doc["expected_last_position"] == -738
    # DIR stays low: sigrok counts that as -1 per step, wavecheck (DIR low = forward) as +1
    assert doc["final_sigrok_polarity"] == -739 and doc["wavecheck_final_position"] == 739


def test_smoothieware_dir_forward_high(smoothie_sr: Path) -> None:
    rc, doc = _json([str(smoothie_sr), "--map", "step=5,dir=6", "--dir-forward", "high"])
    assert rc == 0 and doc["wavecheck_final_position"] == -739


def test_smoothieware_no_samplerate(smoothie_no_rate_sr: Path) -> None:
    rc, doc = _json([str(smoothie_no_rate_sr), "--map", "step=5,dir=6", "--samplerate", "12MHz"])
    assert rc == 0 and doc["sigrok_count"] == 739


def test_grbl_counts_only(grbl_sr: Path) -> None:
    rc, doc = _json([str(grbl_sr), "--map", "step=STEP (Y axis)"])
    assert rc == 0 and doc["agree"]
    assert doc["wavecheck_steps"] == doc["sigrok_count"] == 10508
    assert doc["dir_channel"] is None


@pytest.mark.parametrize(
    "name",
    ["stepgen0", "g202-p16-dirhold2-worst", "g202-p20-worst-dirhold", "xylotex-dirsetup-zero"],
)
def test_golden_vcds(name: str) -> None:
    path = GOLDEN / f"{name}.vcd"
    rc, doc = _json([str(path), "--map", "step=step,dir=dir"])
    assert rc == 0, doc["disagreements"]
    assert doc["downsample"] > 1
    if name == "xylotex-dirsetup-zero":  # DIR flips in the step's own sample (LinuxCNC #2332)
        assert doc["ambiguous"] == 1 and doc["wavecheck_final_position"] is None
        assert doc["final_sigrok_polarity"] == -1  # stepgen's counts end at +1, DIR high = reverse


def test_falling_edge(tmp_path: Path) -> None:
    path = GOLDEN / "g202-p16-dirhold2-worst.vcd"
    rc, doc = _json([str(path), "--map", "step=step,dir=dir", "--active-edge", "falling"])
    assert rc == 0 and doc["sigrok_count"] == 4


@pytest.mark.parametrize("timescale,factor", [("1 fs", 10**6), ("1 ps", 10**3)])
def test_fine_timescales_keep_the_downsample_in_range(
    tmp_path: Path, timescale: str, factor: int
) -> None:
    """Issue 12: a 1 fs VCD (GHDL's default) handed sigrok-cli a downsample factor above 2^31,
    which it wraps: a false DISAGREE (and above 2^31 a run that never ended)."""
    from tests.conftest import write_vcd
    from wavecheck.capture.open import open_capture

    golden = open_capture(GOLDEN / "g202-p20-worst-dirhold.vcd")  # 1 ns ticks
    signals = {
        n: (golden.channel(n).initial, [int(t) * factor for t in golden.channel(n).edges])
        for n in ("step", "dir")
    }
    path = write_vcd(tmp_path / "fine.vcd", signals, timescale=timescale, end=golden.end * factor)
    rc, doc = _json([str(path), "--map", "step=step,dir=dir"])
    assert rc == 0, doc["disagreements"]
    if factor == 10**6:  # in capture ticks above 2^31; the factor sigrok-cli got is smaller
        assert doc["downsample"] > 2**31
    assert doc["sigrok_count"] == doc["wavecheck_steps"] > 0


def test_too_coarse_downsample_disagrees() -> None:
    """Forcing a downsample that merges pulses (sigrok.md §7) must show up as a disagreement."""
    path = GOLDEN / "stepgen0.vcd"
    rc, out, err = cli(
        "wavecheck",
        ["crosscheck", str(path), "--map", "step=step,dir=dir", "--downsample", "300000"],
    )
    assert rc == 1, err
    assert "DISAGREE" in out and "step count" in out


@pytest.mark.parametrize(
    "argv",
    [
        ["{missing}", "--map", "step=5"],
        ["{smoothie}"],
        ["{smoothie}", "--map", "step=99"],
        ["{smoothie}", "--map", "step=5,up=3"],
        ["{golden}", "--map", "step=step", "--downsample", "0"],
    ],
)
def test_unusable(tmp_path: Path, smoothie_sr: Path, argv: list[str]) -> None:
    subst = {
        "{missing}": str(tmp_path / "nothere.sr"),
        "{smoothie}": str(smoothie_sr),
        "{golden}": str(GOLDEN / "stepgen0.vcd"),
    }
    out_dir = tmp_path / "out"
    out_dir.mkdir()
    args = [subst.get(a, a) for a in argv] + ["-o", str(out_dir / "x.txt")]
    rc, _, err = cli("wavecheck", ["crosscheck", *args])
    assert rc == 2 and len(err.strip().splitlines()) == 1 and "Traceback" not in err
    assert_no_output(out_dir)


def test_without_sigrok_cli(monkeypatch: pytest.MonkeyPatch, smoothie_sr: Path) -> None:
    monkeypatch.setenv("PATH", "/nonexistent")
    rc, _, err = cli("wavecheck", ["crosscheck", str(smoothie_sr), "--map", "step=5"])
    assert rc == 2 and "sigrok-cli" in err and str(smoothie_sr) in err


def test_sigrok_format_keeps_its_options(tmp_path: Path) -> None:
    """A raw binary capture (3 channels, rate given on the command line) is converted again with
    the same options: 5 rising edges on bit 0; DIR (bit 1) rises in the 4th step's own sample."""
    samples = [0, 1, 0, 1, 0, 1, 0, 3, 2, 3, 2, 2]
    path = tmp_path / "raw.bin"
    path.write_bytes(bytes(samples))
    rc, doc = _json([str(path), "--input-format", "binary:numchannels=3", "--samplerate", "1MHz",
                     "--map", "step=0,dir=1"])  # fmt: skip
    assert rc == 0, doc["disagreements"]
    assert doc["sigrok_count"] == doc["wavecheck_steps"] == 5
    assert doc["ambiguous"] == 1  # sigrok takes the new DIR level there
    assert doc["final_sigrok_polarity"] == -3 + 2
