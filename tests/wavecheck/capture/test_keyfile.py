"""The GKeyFile reader (capture/keyfile.py): GLib's rules, each test citing the function of
``glib/gkeyfile.c`` (GLib 2.56.2) it checks, and where they differ from the configparser the
``.sr`` reader used before (``ConfigParser(interpolation=None, delimiters=("=",),
strict=False)``, ``optionxform = str``), both readings side by side."""

from __future__ import annotations

import configparser
import shutil
import subprocess
import zipfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from tests.wavecheck.capture.test_zipdir import REAL_SR
from wavecheck.capture.keyfile import KeyFileError, escape, parse_keyfile, unescape


def _configparser(text: str) -> dict[str, dict[str, str]] | str:
    cp = configparser.ConfigParser(interpolation=None, delimiters=("=",), strict=False)
    cp.optionxform = str  # type: ignore[assignment,method-assign]
    try:
        cp.read_string(text)
    except configparser.Error as err:
        return type(err).__name__
    return {name: dict(cp[name]) for name in cp.sections()}


@pytest.mark.parametrize("path", REAL_SR, ids=lambda p: p.name)
def test_every_real_metadata_reads_as_configparser_read_it(path: object) -> None:
    with zipfile.ZipFile(path) as zf:  # type: ignore[arg-type]
        text = zf.read("metadata").decode("utf-8")
    assert parse_keyfile(text) == _configparser(text)


SAME = [
    # g_key_file_parse_data: lines end at \n, a \r before it is dropped
    ("[device 1]\r\nprobe1=A\r\n", {"device 1": {"probe1": "A"}}),
    # g_key_file_parse_line: leading whitespace skipped; '#' and empty lines are comments
    ("# c\n\n  [device 1]\n\t# c\n   probe1=A\n", {"device 1": {"probe1": "A"}}),
    # g_key_file_parse_key_value_pair: whitespace around '=' dropped; the first '=' splits
    ("[d]\nkey \t=  a=b\n", {"d": {"key": "a=b"}}),
    # _add_key_value_pair: g_hash_table_replace, the last value of a key is the one read
    ("[d]\nk=1\nk=2\n", {"d": {"k": "2"}}),
    # _add_group: a group named again continues the first one
    ("[d]\na=1\n[e]\n[d]\nb=2\n", {"d": {"a": "1", "b": "2"}, "e": {}}),
    # an empty value
    ("[d]\nk=\n", {"d": {"k": ""}}),
    # keys are case-sensitive, spaces inside a key are kept
    ("[d]\nTotal Probes=1\ntotal probes=2\n", {"d": {"Total Probes": "1", "total probes": "2"}}),
]


@pytest.mark.parametrize(("text", "groups"), SAME)
def test_where_glib_and_configparser_agree(text: str, groups: dict[str, dict[str, str]]) -> None:
    assert parse_keyfile(text) == groups == _configparser(text)


DIFFERENT = [
    # _line_is_comment: only '#' starts a comment; ';' is configparser's too
    ("[d]\n; note\n", "not a key-value pair, group, or comment", {"d": {}}),
    # g_key_file_parse_line: every line stands alone (leading whitespace skipped); configparser
    # joins an indented line to the value before
    ("[d]\nprobe1=STEP\n  (Y axis)\n", "not a key-value pair", {"d": {"probe1": "STEP\n(Y axis)"}}),
    # _line_is_group: only spaces or tabs after ']'; configparser ignores the rest
    ("[d] x\nk=1\n", "not a key-value pair", {"d": {"k": "1"}}),
    # _parse_key_value_pair: a key before any group
    ("k=1\n", "does not start with a group", "MissingSectionHeaderError"),
    # _is_key_name: no '[' or ']' in a key but for a trailing [locale]
    ("[d]\na]b=1\n", "Invalid key name: a]b", {"d": {"a]b": "1"}}),
    # _is_group_name: no control characters in a group name
    ("[d\x01]\n", "Invalid group name", {"d\x01": {}}),
    # _parse_key_value_pair: Encoding in the first group must be UTF-8
    ("[d]\nEncoding=latin1\n", "unsupported encoding", {"d": {"Encoding": "latin1"}}),
]


@pytest.mark.parametrize(("text", "glib", "before"), DIFFERENT)
def test_where_glib_refuses_what_configparser_read(text: str, glib: str, before: object) -> None:
    assert _configparser(text) == before
    with pytest.raises(KeyFileError, match=glib):
        parse_keyfile(text)


@pytest.mark.parametrize(
    ("text", "glib", "before"),
    [
        # _parse_key_value_pair keeps the value's trailing whitespace (g_strndup to the end)
        ("[d]\nprobe1=STEP  \n", {"d": {"probe1": "STEP  "}}, {"d": {"probe1": "STEP"}}),
        # configparser gives [DEFAULT]'s keys to every section; GLib has no such group
        ("[DEFAULT]\nk=1\n[d]\n", {"DEFAULT": {"k": "1"}, "d": {}}, {"d": {"k": "1"}}),
        # '\v' is not g_ascii_isspace (gstrfuncs.c ascii_table_data[0x0b] = 0x004)
        ("[d]\nk=\va\n", {"d": {"k": "\va"}}, {"d": {"k": "a"}}),
        # a [locale] key is a key of its own (GLib keeps the user's locales' only)
        ("[d]\nk[de]=1\n", {"d": {"k[de]": "1"}}, {"d": {"k[de]": "1"}}),
    ],
)
def test_where_glib_reads_otherwise(text: str, glib: object, before: object) -> None:
    assert parse_keyfile(text) == glib
    assert _configparser(text) == before


@pytest.mark.parametrize(
    ("raw", "value"),
    [
        ("plain", "plain"),
        (r"\sA\tB\nC\rD\\E", " A\tB\nC\rD\\E"),  # _parse_value_as_string's five escapes
        ("no\\\\s", "no\\s"),
    ],
)
def test_values_unescape_as_g_key_file_get_string(raw: str, value: str) -> None:
    assert unescape(raw) == value


@pytest.mark.parametrize(
    ("raw", "message"),
    [("a\\x", "invalid escape sequence “\\\\x”"), ("a\\", "escape character at end of line")],
)
def test_bad_escapes_are_errors_as_in_glib(raw: str, message: str) -> None:
    with pytest.raises(KeyFileError, match=message):
        unescape(raw)


def test_errors_name_the_line() -> None:
    with pytest.raises(KeyFileError, match="^line 3: "):
        parse_keyfile("[d]\nk=1\nnonsense\n")


@settings(max_examples=300)
@given(st.text(st.characters(blacklist_categories=("Cs",), blacklist_characters="\0")))
def test_escape_reads_back_as_written(value: str) -> None:
    """``escape`` (``g_key_file_set_string``'s escaping) read back through a whole line of a
    key file gives the value: leading spaces and tabs, newlines, carriage returns and
    backslashes survive; trailing whitespace is kept by the reader. A leading form feed has no
    escape in GLib (``g_key_file_parse_string_as_value`` writes it as is) and the reader drops
    it (``g_ascii_isspace``): GLib's own limit, left out."""
    assume(not value.startswith("\f"))
    groups = parse_keyfile(f"[g]\nkey={escape(value)}\nnext=1\n")
    assert unescape(groups["g"]["key"]) == value
    assert groups["g"]["next"] == "1"


@pytest.mark.skipif(shutil.which("sigrok-cli") is None, reason="needs sigrok-cli")
def test_sigrok_cli_reads_escaped_names_as_written(tmp_path: Path) -> None:
    """What GLib itself reads (libsigrok's ``g_key_file_get_string``, through sigrok-cli
    ``--show``): names that need escaping come out as written, so do ours."""
    from wavecheck.capture.sr import read_sr
    from wavecheck.capture.srzip import write_sr_edges

    names = ["\\bus[3] ", " lead", "tab\tin", "A\\B"]
    path = tmp_path / "names.sr"
    edges = [np.array([2], dtype=np.int64)] * len(names)
    write_sr_edges(path, names, edges, [0] * len(names), 8, samplerate=1_000_000)
    assert [c.name for c in read_sr(path).channels] == names
    shown = subprocess.run(
        ["sigrok-cli", "-i", str(path), "--show"], capture_output=True, text=True, timeout=60
    )
    assert shown.returncode == 0, shown.stderr
    channels = [line[2:].removesuffix(": logic") for line in shown.stdout.split("\n")
                if line.startswith("- ") and line.endswith(": logic")]  # fmt: skip
    assert channels == names
