"""``wavecheck check --pulseview``: the PulseView 0.4.2 session file (issue 28).

The format is PulseView's own (QSettings INI; ``test_pulseview.py`` opens one in real PulseView);
these tests pin what ``check`` writes into it for each axis and the escaping of names.
"""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import pytest

from wavecheck.cli import main
from wavecheck.sigrok.decoder.pd import ANNOTATION_ROWS, ANNOTATIONS, CHANNELS, OPTIONAL_CHANNELS
from wavecheck.sigrok.session import Stacked, pvs_text

ROOT = Path(__file__).resolve().parents[3]
IDS = [c["id"] for c in (*CHANNELS, *OPTIONAL_CHANNELS)]


def _groups(text: str) -> dict[str, dict[str, str]]:
    groups: dict[str, dict[str, str]] = {}
    current: dict[str, str] = {}
    for line in text.splitlines():
        if line.startswith("["):
            current = groups.setdefault(line.strip("[]"), {})
        elif "=" in line:
            key, value = line.split("=", 1)
            current[key] = value
    return groups


def _option(group: dict[str, str], name: str) -> str | None:
    """An option's value, decoded from its GVariant byte array."""
    for key, value in group.items():
        if key.endswith("\\name") and value == name:
            raw = group[key.replace("\\name", "\\value")]
            hexes = re.findall(r"\\x([0-9a-f]{2})", raw)
            data = bytes(int(h, 16) for h in hexes)
            assert data.endswith(b"\0")
            return data[:-1].decode()
    return None


@pytest.mark.parametrize(
    "name, written",
    [
        ("STEP (Y axis)", '"STEP (Y axis)"'),
        ('say "hi"\\', '"say \\"hi\\"\\\\"'),
        ("é1", '"\\xe9\\x31"'),  # a hex digit after an escape is escaped too (Qt's reader)
        ("a,b;c", '"a,b;c"'),  # quoted: not a list
        ("tab\there", '"tab\\x9here"'),
    ],
)
def test_names_are_written_as_qsettings_strings(name: str, written: str) -> None:
    text = pvs_text([Stacked("wavecheck", {"step": name}, {})], IDS)
    assert f"channel0\\assigned_signal_name={written}" in text.splitlines()


def test_options_are_gvariant_strings() -> None:
    text = pvs_text(
        [Stacked("wavecheck", {"step": "S"}, {"drive": "gecko-g202", "limit": ""})], IDS
    )
    group = _groups(text)["decode_signal0"]
    assert group["decoder0\\options"] == "1"  # an empty option keeps the decoder's default
    assert _option(group, "drive") == "gecko-g202"
    assert (
        group["decoder0\\option0\\value"]
        == "@ByteArray(" + "".join(f"\\x{b:02x}" for b in b"gecko-g202\0") + ")"
    )
    assert [group[f"channel{k}\\name"] for k in range(3)] == IDS


def test_check_writes_one_decode_signal_per_axis(tmp_path: Path) -> None:
    pvs = tmp_path / "m.pvs"
    argv = ["check", str(ROOT / "captures/examples/two-axis.vcd"), "--drive", "gecko-g202",
            "--drive", "y=leadshine-dm542", "--map", "x.step=x_step,x.dir=x_dir",
            "--map", "y.step=y_step,y.dir=y_dir", "--limit", "dir_hold=25us", "--invert", "y.dir",
            "--pulseview", str(pvs)]  # fmt: skip
    assert main(argv) == 1
    groups = _groups(pvs.read_text())
    assert groups["General"]["decode_signals"] == "2"
    x, y = groups["decode_signal0"], groups["decode_signal1"]
    assert (x["name"], y["name"]) == ('"wavecheck x"', '"wavecheck y"')
    assert (_option(x, "drive"), _option(y, "drive")) == ("gecko-g202", "leadshine-dm542")
    assert _option(x, "active_edge") == "falling" and _option(y, "active_edge") == "rising"
    assert _option(x, "limit") == _option(y, "limit") == "dir_hold=25us"
    assert _option(x, "invert") is None and _option(y, "invert") == "dir"
    assert _option(x, "resolution") == "0"  # a simulator's VCD: exact edges, as check read it
    assert (x["channel0\\assigned_signal_name"], x["channel1\\assigned_signal_name"]) == (
        '"x_step"', '"x_dir"')  # fmt: skip
    assert "channel2\\assigned_signal_name" not in x  # no ENABLE mapped


def test_a_rule_file_is_named_by_its_path(tmp_path: Path) -> None:
    rules = tmp_path / "mine.toml"
    rules.write_text((ROOT / "rules/gecko-g202.toml").read_text().replace(
        'id = "gecko-g202"', 'id = "mine"'))  # fmt: skip
    pvs = tmp_path / "m.pvs"
    argv = ["check", str(ROOT / "captures/golden/g202-p20-worst-dirhold.vcd"), "--drive",
            str(rules), "--pulseview", str(pvs)]  # fmt: skip
    assert main(argv) == 1
    assert _option(_groups(pvs.read_text())["decode_signal0"], "drive") == str(rules.resolve())


def test_several_captures_or_a_foreign_format_are_refused(tmp_path: Path, capsys) -> None:  # type: ignore[no-untyped-def]
    golden = str(ROOT / "captures/golden/g202-*.vcd")
    assert main(["check", golden, "--drive", "gecko-g202", "--pulseview", "x.pvs"]) == 2
    assert "--pulseview opens one capture in PulseView; 2 were given" in capsys.readouterr().err
    if shutil.which("sigrok-cli") is None:
        return
    csv = tmp_path / "c.csv"
    csv.write_text("step,dir\n0,0\n1,0\n0,0\n1,1\n0,1\n")
    argv = ["check", str(csv), "--drive", "gecko-g202", "--input-format", "csv:samplerate=1000000",
            "--pulseview", str(tmp_path / "c.pvs")]  # fmt: skip
    assert main(argv) == 2
    out, err = capsys.readouterr()
    assert "PulseView opens .sr and VCD files, not sigrok:csv" in err and not out  # no report
    assert not (tmp_path / "c.pvs").exists()


def test_violations_are_red_in_pulseview() -> None:
    """PulseView 0.4.2 gives an annotation the hue of the decode signal (the session's green,
    120°) + 20° per row + 55° per class (pv/views/trace/decodetrace.cpp): the classes are ordered
    so that a violation and a violation region are red, an indeterminate interval orange, and
    nothing else within 50° of red."""
    classes = [c for c, _ in ANNOTATIONS]
    row_of = {cls: r for r, (_, _, members) in enumerate(ANNOTATION_ROWS) for cls in members}

    def hue(name: str) -> int:
        k = classes.index(name)
        return (120 + 20 * row_of[k] + 55 * k) % 360

    assert min(hue("fail"), 360 - hue("fail")) <= 15
    assert min(hue("region"), 360 - hue("region")) <= 15
    assert 30 <= hue("indeterminate") <= 60
    reds = [c for c in classes if min(hue(c), 360 - hue(c)) <= 50]
    assert sorted(reds) == ["fail", "indeterminate", "region"]
