"""The format registry (capture/formats.py): each record tells its own files, and the formats
recognised only to be refused (LXT2 and LXT in a ``.vcd``, a Saleae ``.sal`` session) are
refused by name, from a file and from standard input alike."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

from wavecheck.capture.formats import FORMATS, by_content, by_name
from wavecheck.capture.open import detect_format, open_capture, open_source
from wavecheck.cli import main
from wavecheck.errors import CaptureError, UsageError

VERILOG = """module t; reg s = 0;
initial begin $dumpfile("dump.vcd"); $dumpvars(0, t); #10 s = 1; #10 s = 0; #5 $finish; end
endmodule
"""


def test_names_are_unique() -> None:
    names = [n for f in FORMATS for n in (f.name, *f.aliases)]
    assert len(names) == len(set(names))


@pytest.mark.parametrize("fmt", [f for f in FORMATS if f.magic], ids=lambda f: f.name)
def test_each_magic_tells_its_own_format_first(fmt: object) -> None:
    """A record's magic, followed by what its files hold, is told as that record (the zip of a
    Saleae session is not taken for a .sr, nor the reverse)."""
    from wavecheck.capture.formats import Format

    assert isinstance(fmt, Format)
    tail = b"meta.json" if fmt.name == "saleae-session" else b"metadata"
    told = by_content(fmt.magic[0] + b"\0" * 30 + tail)
    assert told is fmt


def test_options_refused_where_a_format_takes_none() -> None:
    with pytest.raises(UsageError, match="sr takes no options"):
        by_name("sr:foo=1")
    assert by_name("vcd:downsample=10").name == "sigrok-cli"
    assert by_name("chronovu-la8").name == "chronovu-la8"
    assert by_name("SRZIP").name == "sr"


@pytest.fixture(scope="module")
def lxt_dumps(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """What Icarus writes with vvp -lxt2 and -lxt: the $dumpfile's name, dump.vcd, for both."""
    if not (shutil.which("iverilog") and shutil.which("vvp")):
        pytest.skip("needs iverilog (make system-deps)")
    tmp = tmp_path_factory.mktemp("lxt")
    (tmp / "t.v").write_text(VERILOG)
    subprocess.run(["iverilog", "-o", "t.vvp", "t.v"], check=True, cwd=tmp)
    out = {}
    for flag in ("lxt2", "lxt"):
        run = tmp / flag
        run.mkdir()
        subprocess.run(["vvp", "-n", str(tmp / "t.vvp"), f"-{flag}"], check=True, cwd=run,
                       capture_output=True)  # fmt: skip
        out[flag] = run / "dump.vcd"
    return out


@pytest.mark.parametrize("flag,name", [("lxt2", "an LXT2 file"), ("lxt", "an LXT file")])
def test_an_lxt_file_named_vcd_is_refused_by_name(
    lxt_dumps: dict[str, Path], flag: str, name: str
) -> None:
    path = lxt_dumps[flag]
    assert detect_format(path) == flag
    with pytest.raises(CaptureError, match=f"{name} .GTKWave's .*not a VCD"):
        open_capture(path)
    with pytest.raises(CaptureError, match=f"{name} "):
        open_source(path)
    with pytest.raises(CaptureError, match=f"{name} "):
        open_capture(path, input_format=flag)


def test_lxt2_converted_by_gtkwave_is_read(lxt_dumps: dict[str, Path], tmp_path: Path) -> None:
    """The route the message names works: lxt2vcd's VCD is read (s rises at 10, falls at 20)."""
    if shutil.which("lxt2vcd") is None:
        pytest.skip("needs gtkwave's lxt2vcd")
    vcd = tmp_path / "dump.vcd"
    with open(vcd, "wb") as out:
        subprocess.run(["lxt2vcd", str(lxt_dumps["lxt2"])], check=True, stdout=out,
                       stderr=subprocess.DEVNULL)  # fmt: skip
    cap = open_capture(vcd)
    assert cap.channel("s[0]").edges.tolist() == [10, 20]  # lxt2vcd names the reg s[0]


def test_lxt2_on_standard_input_is_refused_by_name(lxt_dumps: dict[str, Path]) -> None:
    run = subprocess.run(
        [sys.executable, "-m", "wavecheck", "info", "-"],
        input=lxt_dumps["lxt2"].read_bytes(),
        capture_output=True,
    )
    assert run.returncode == 2
    err = run.stderr.decode()
    assert err.count("\n") == 1 and "<stdin>" in err and "an LXT2 file" in err


def _session(path: Path, *, meta_first: bool = True) -> Path:
    """A Logic 2 session's layout: a zip of meta.json and digital-N.bin (their content is
    Saleae's own, undocumented; the member names are what tell it)."""
    meta = json.dumps({"version": 16, "data": {"captureSettings": {"digitalSampleRate": 500000}}})
    members = [("meta.json", meta.encode())] + [
        (f"digital-{i}.bin", bytes(range(64)) * 64) for i in range(3)
    ]
    if not meta_first:
        members.reverse()
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as zf:
        for name, data in members:
            zf.writestr(name, data)
    return path


@pytest.mark.parametrize("meta_first", [True, False])
@pytest.mark.parametrize("name", ["capture.sal", "capture.sr", "capture"])
def test_a_saleae_session_is_told_by_content(tmp_path: Path, name: str, meta_first: bool) -> None:
    path = _session(tmp_path / name, meta_first=meta_first)
    assert detect_format(path) == "saleae-session"
    with pytest.raises(CaptureError) as err:
        open_capture(path)
    msg = str(err.value)
    assert "Saleae Logic 2 session" in msg and "File > Export Raw Data" in msg
    assert "\n" not in msg and "not a sigrok .sr" not in msg


def test_a_saleae_session_through_the_cli(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = _session(tmp_path / "run.sal")
    assert main(["check", str(path), "--drive", "gecko-g202"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "run.sal" in err and "Export Raw Data" in err


def test_a_saleae_session_on_standard_input(tmp_path: Path) -> None:
    data = _session(tmp_path / "s.sal").read_bytes()
    run = subprocess.run(
        [sys.executable, "-m", "wavecheck", "info", "-"], input=data, capture_output=True
    )
    assert run.returncode == 2 and b"Saleae Logic 2 session" in run.stderr


def test_a_real_sr_is_still_a_sr(grbl_sr: Path) -> None:
    assert detect_format(grbl_sr) == "sr"


def test_a_zip_that_is_neither_names_the_sr_reader(tmp_path: Path) -> None:
    path = tmp_path / "other.zip"
    with zipfile.ZipFile(path, "w") as zf:
        zf.writestr("readme.txt", "hello")
    assert detect_format(path) == "sr"
    with pytest.raises(CaptureError, match="not a sigrok .sr file"):
        open_capture(path)


def test_the_hint_lists_the_formats(tmp_path: Path) -> None:
    path = tmp_path / "mystery.bin"
    path.write_bytes(b"\x7fELF" + bytes(100))
    with pytest.raises(CaptureError) as err:
        open_capture(path)
    msg = str(err.value)
    assert "saleae1-csv" in msg and "binary:numchannels=N" in msg and "lxt2" not in msg
    assert "sigrok-cli format such as csv, chronovu-la8, logicport" in msg
