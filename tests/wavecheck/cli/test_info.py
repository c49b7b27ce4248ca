"""`wavecheck info`: the grbl capture, the JSON contract, and one-line errors with exit code 2."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from tests.conftest import shared_capture, write_vcd
from tests.wavecheck.capture.srutil import count_edges_by_members, write_sr
from wavecheck.capture.open import open_capture
from wavecheck.cli import main
from wavecheck.errors import UsageError
from wavecheck.steps.interface import build_interface

JSON_KEYS = {"format", "samplerate_hz", "resolution_ns", "duration_s", "channels"}
CHANNEL_KEYS = {"name", "index", "initial", "edges", "rising", "falling"}


def test_grbl_text(grbl_sr: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["info", str(grbl_sr)]) == 0
    out = capsys.readouterr().out
    assert "2 MHz" in out
    _, counts, _ = count_edges_by_members(grbl_sr)
    for name, n in zip(["EN", "STEP (Y axis)", "TX", "RX"], counts, strict=False):
        line = next(ln for ln in out.splitlines() if f" {name} " in ln)
        assert line.split()[-3] == str(n)


def test_grbl_json(grbl_sr: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["info", str(grbl_sr), "--format", "json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert JSON_KEYS <= set(data)
    assert data["format"] == "sr" and data["samplerate_hz"] == 2_000_000
    assert data["resolution_ns"] == 500
    initial, counts, samples = count_edges_by_members(grbl_sr)
    assert data["duration_s"] == pytest.approx(samples / 2e6)
    assert [c["name"] for c in data["channels"]] == ["EN", "STEP (Y axis)", "TX", "RX"]
    for i, ch in enumerate(data["channels"]):
        assert set(ch) == CHANNEL_KEYS
        assert (ch["index"], ch["initial"], ch["edges"]) == (i, initial[i], counts[i])
        assert (
            ch["rising"] + ch["falling"] == ch["edges"] and abs(ch["rising"] - ch["falling"]) <= 1
        )


def test_vcd_json_has_null_samplerate(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = write_vcd(
        tmp_path / "a.vcd", {"STEP": (0, [10, 20, 30]), "DIR": (1, [])}, "10 ns", end=100
    )
    assert main(["info", str(path), "--format", "json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["samplerate_hz"] is None and data["resolution_ns"] == 0
    assert data["duration_s"] == pytest.approx(1e-6)
    assert data["channels"][0] == {
        "name": "STEP", "index": 0, "initial": 0, "edges": 3, "rising": 2, "falling": 1,
    }  # fmt: skip


def test_vcd_text_shows_timescale_and_notes(capsys: pytest.CaptureFixture[str]) -> None:
    path = shared_capture("sigrok-dumps/misc/vcd/real-analog.vcd")
    assert main(["info", str(path)]) == 0
    out = capsys.readouterr().out
    assert "1 us (timescale)" in out and "200 kHz" in out and "note: skipped 5" in out


def _bad_files(tmp_path: Path, grbl: Path) -> dict[str, Path]:
    data = grbl.read_bytes()
    files = {
        "truncated.sr": data[: len(data) // 2],
        "empty.sr": b"",
        "garbage.sr": b"\x13\x37 not a zip" * 50,
        "empty.vcd": b"",
        "garbage.vcd": b"$timescale 1 ns $end\n$enddefinitions $end\n#0 q!\n",
        "truncated.vcd": b"$timescale 1 ns $end\n$var wire 1 ! a $end\n$enddefinitions $end\n#0 0!\n#10 1",
        "nothing.vcd": b"just text\n",
    }
    out = {}
    for name, content in files.items():
        (tmp_path / name).write_bytes(content)
        out[name] = tmp_path / name
    return out


@pytest.mark.parametrize(
    "name",
    [
        "truncated.sr",
        "empty.sr",
        "garbage.sr",
        "empty.vcd",
        "garbage.vcd",
        "truncated.vcd",
        "nothing.vcd",
    ],
)
def test_bad_files_exit_2_one_line(
    tmp_path: Path, grbl_sr: Path, name: str, capsys: pytest.CaptureFixture[str]
) -> None:
    path = _bad_files(tmp_path, grbl_sr)[name]
    assert main(["info", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and str(path) in err and "Traceback" not in err


@pytest.mark.parametrize(
    ("args", "match"),
    [
        (["--samplerate", "3 parsecs"], "--samplerate 3 parsecs: unknown unit 'parsecs'"),
        (["--resolution", "5 furlongs"], "--resolution 5 furlongs: unknown unit 'furlongs'"),
    ],
)
def test_unknown_unit(
    tmp_path: Path, args: list[str], match: str, capsys: pytest.CaptureFixture[str]
) -> None:
    path = write_sr(tmp_path / "a.sr", bytes([0, 1]))
    assert main(["info", str(path), *args]) == 2
    err = capsys.readouterr().err
    assert match in err and err.count("\n") == 1


def test_file_without_samplerate_is_listed_in_samples(
    smoothie_no_rate_sr: Path, smoothie_sr: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A .sr with no sample rate: ``info`` lists the channels and edge counts in samples, says
    that times need --samplerate (it refused outright); ``check`` still refuses."""
    timed = open_capture(smoothie_sr)
    assert main(["info", str(smoothie_no_rate_sr)]) == 0
    out = capsys.readouterr().out
    assert "none stated (times need --samplerate)" in out
    assert f"duration    {timed.end} samples" in out
    for ch in timed.channels:
        assert f"{ch.index:>5}  {ch.name}  " in out and f"  {len(ch.edges):>9}  " in out
    assert main(["info", str(smoothie_no_rate_sr), "--format", "json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["time_known"] is False and data["samples"] == timed.end
    assert data["duration_s"] is None and data["tick_ns"] is None
    assert [c["edges"] for c in data["channels"]] == [len(c.edges) for c in timed.channels]
    assert any("--samplerate" in n for n in data["notes"])
    rc = main(["check", str(smoothie_no_rate_sr), "--drive", "gecko-g202", "--map", "step=3,dir=4"])
    assert rc == 2 and "--samplerate" in capsys.readouterr().err


def test_samplerate_option_rescues_file_without_one(
    smoothie_no_rate_sr: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert (
        main(["info", str(smoothie_no_rate_sr), "--samplerate", "12MHz", "--format", "json"]) == 0
    )
    data = json.loads(capsys.readouterr().out)
    assert data["samplerate_hz"] == 12_000_000 and data["time_known"] is True


def test_missing_channel_in_map(grbl_sr: Path) -> None:
    cap = open_capture(grbl_sr)
    with pytest.raises(UsageError, match=r"grbl_cnc_1.sr: no channel 'DIR' \(channels: 0='EN'"):
        build_interface(cap, {"step": "STEP (Y axis)", "dir": "DIR"})
    assert build_interface(cap, {"step": "1"}).require("step").channel == "STEP (Y axis)"


def test_info_proposes_roles_with_evidence(grbl_sr, smoothie_sr, capsys) -> None:  # type: ignore[no-untyped-def]
    """Issue 13: info proposes roles from the waveforms and says which evidence decided."""
    import json

    from wavecheck.cli import main

    assert main(["info", str(grbl_sr)]) == 0
    out = capsys.readouterr().out
    assert "proposed roles" in out and "serial line" in out
    assert "--map 'step=STEP (Y axis),enable=EN'" in out
    assert main(["info", str(smoothie_sr), "--format", "json"]) == 0
    roles = json.loads(capsys.readouterr().out)["roles"]
    assert roles["map_args"] == "--map a.step=3,a.dir=4 --map b.step=5,b.dir=6"


def test_info_shows_the_exact_resolution_check_uses(tmp_path, capsys) -> None:  # type: ignore[no-untyped-def]
    """Issue 12: --resolution 100ns on a 1 us timescale stays 100 ns (info showed it rounded up
    to one tick, 1 us, while check used 100 ns)."""
    import json

    from tests.conftest import write_vcd
    from wavecheck.cli import main

    vcd = write_vcd(tmp_path / "t.vcd", {"step": (0, [10, 12])}, timescale="1 us", end=20)
    assert main(["info", str(vcd), "--resolution", "100ns", "--format", "json"]) == 0
    assert json.loads(capsys.readouterr().out)["resolution_ns"] == 100
