"""`wavecheck drives`: list, show, JSON, exit codes."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from wavecheck.cli import main
from wavecheck.drives.library import rules_dir


def test_list_text(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["drives"]) == 0
    out = capsys.readouterr().out
    line = next(ln for ln in out.splitlines() if ln.startswith("gecko-g202 "))
    assert line.split()[-6:] == ["4.5", "0.5", "1", "20", "200", "kHz"]
    assert "falling" in line
    n = len(list(rules_dir().glob("*.toml")))
    assert f"{n} drives" in out


def test_list_json(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["drives", "--format", "json"]) == 0
    data = json.loads(capsys.readouterr().out)
    by_id = {d["id"]: d for d in data["drives"]}
    g = by_id["gecko-g202"]
    assert g["limits"]["dir_hold"]["value_ns"] == 20000
    assert g["max_rate"]["value_hz"] == 200000
    assert g["drive_rate_hz"] == 200000  # min(200 kHz, 1 / (4.5 + 0.5 us))
    assert by_id["xylotex"]["drive_rate_hz"] == pytest.approx(1e9 / 3000)


def test_show_text_has_every_figure_and_source(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["drives", "teknic-clearpath"]) == 0
    out = capsys.readouterr().out
    for rule in ("step_high", "step_low", "dir_setup", "dir_hold", "max_rate"):
        assert rule in out
    assert "uncertain" in out
    assert "[C1] Teknic ClearPath MC/SD User Manual Rev 3.09" in out


def test_show_json(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["drives", "tmc5160", "--format", "json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["limits"]["step_high"]["status"] == "uncertain"
    assert d["limits"]["dir_setup"]["value_ns"] == 20
    assert d["limits"]["dir_setup"]["source_text"].startswith("Trinamic TMC5160")


def test_show_by_path(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    own = tmp_path / "xylotex.toml"
    own.write_text((rules_dir() / "xylotex.toml").read_text())
    assert main(["drives", str(own)]) == 0
    assert str(own) in capsys.readouterr().out


def test_unknown_id_exits_2_with_one_line(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["drives", "gecko-g20"]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err
    assert "gecko-g202" in err and "wavecheck drives" in err


def test_malformed_file_exits_2(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    bad = tmp_path / "xylotex.toml"
    bad.write_text((rules_dir() / "xylotex.toml").read_text().replace('"2.0us"', '"2.0 parsecs"'))
    assert main(["drives", str(bad)]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "limits.step_high.value" in err and str(bad) in err


def test_bad_format_is_usage_error(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exc:
        main(["drives", "--format", "xml"])
    assert exc.value.code == 2
