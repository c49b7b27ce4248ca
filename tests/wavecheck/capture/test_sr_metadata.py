"""A .sr's metadata read as libsigrok reads it (GLib's GKeyFile: capture/keyfile.py), not as
configparser did: each case read by wavecheck and, where installed, by the real sigrok-cli
(``--show``), which must agree (the channel names, or both refuse the file)."""

from __future__ import annotations

import subprocess
import zipfile
from pathlib import Path

import pytest

from wavecheck.capture.sigrokcli import find_sigrok_cli
from wavecheck.capture.sr import read_sr
from wavecheck.errors import CaptureError

HEAD = ("[global]\nsigrok version=0.5.2\n\n[device 1]\ncapturefile=logic-1\ntotal probes=2\n"
        "samplerate=1 MHz\ntotal analog=0\n")  # fmt: skip
END = "unitsize=1\n"  # last: libsigrok reports an earlier key's bad escape only when it reads one

CASES = [
    # g_key_file_parse_key_value_pair keeps a value's trailing whitespace; configparser stripped it
    ("trailing space", "probe1=STEP  \nprobe2=DIR\n", ["STEP  ", "DIR"]),
    # g_key_file_get_string unescapes \s \t (_parse_value_as_string); configparser kept them
    ("escapes", "probe1=\\sSTEP\nprobe2=D\\tIR\n", [" STEP", "D\tIR"]),
    # leading whitespace before a key or a group is skipped (g_key_file_parse_line)
    ("indented key", "  probe1=A\nprobe2=B\n", ["A", "B"]),
    # ';' starts no comment in a key file (_line_is_comment: '#' only); configparser skipped it
    ("semicolon", "; note\nprobe1=A\nprobe2=B\n", "line 9: Key file contains line “; note”"),
    # no continuation lines (each line parsed alone); configparser joined it to probe1's value
    ("continuation", "probe1=A\n  more\nprobe2=B\n", "line 10: Key file contains line “ +more”"),
    # an escape GLib does not know: g_key_file_get_string fails for that key
    (
        "bad escape",
        "probe1=A\\q\nprobe2=B\n",
        "probe1='A\\\\\\\\q' cannot be read: .*invalid escape",
    ),
]


def _write(path: Path, tail: str) -> Path:
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as z:
        z.writestr("version", "2")
        z.writestr("metadata", HEAD + tail + END)
        z.writestr("logic-1-1", bytes([0, 1, 0, 1, 3, 0] * 10))
    return path


def _sigrok_names(path: Path) -> list[str] | None:
    """The channel names sigrok-cli shows, None when it cannot load the file."""
    tool = find_sigrok_cli()
    if tool is None:
        pytest.skip("sigrok-cli not installed")
    run = subprocess.run([tool, "-i", str(path), "--show"], capture_output=True, text=True,
                         timeout=60)  # fmt: skip
    if "Failed to load" in run.stderr or run.returncode:
        return None
    return [line[2:].rpartition(": logic")[0] for line in run.stdout.splitlines()
            if line.startswith("- ") and line.endswith(": logic")]  # fmt: skip


@pytest.mark.parametrize(("what", "tail", "expect"), CASES, ids=[c[0] for c in CASES])
def test_metadata_reads_as_glib_reads_it(
    what: str, tail: str, expect: object, tmp_path: Path
) -> None:
    path = _write(tmp_path / "a.sr", tail)
    if isinstance(expect, list):
        assert [c.name for c in read_sr(path).channels] == expect
    else:
        with pytest.raises(CaptureError, match=f"metadata: (cannot be parsed: )?{expect}"):
            read_sr(path)


@pytest.mark.sigrok
@pytest.mark.parametrize(("what", "tail", "expect"), CASES, ids=[c[0] for c in CASES])
def test_sigrok_cli_agrees(what: str, tail: str, expect: object, tmp_path: Path) -> None:
    path = _write(tmp_path / "a.sr", tail)
    assert _sigrok_names(path) == (expect if isinstance(expect, list) else None)
