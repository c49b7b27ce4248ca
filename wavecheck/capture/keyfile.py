"""GLib key files (``GKeyFile``), as libsigrok reads a ``.sr`` file's ``metadata`` with
``g_key_file_load_from_data`` and ``g_key_file_get_string``.

The rules are GLib's ``glib/gkeyfile.c`` (2.56; ``g_key_file_parse_data``, ``_parse_line``,
``_parse_group``, ``_parse_key_value_pair``, ``_is_group_name``, ``_is_key_name``,
``_add_group``, ``_add_key_value_pair``, ``_parse_value_as_string``):

- lines end at ``\\n``; one ``\\r`` before it is dropped; leading whitespace (``g_ascii_isspace``:
  space, ``\\t``, ``\\n``, ``\\f``, ``\\r``, not ``\\v``) is skipped;
- a line that is then empty or starts with ``#`` is a comment (``;`` is not a comment);
- ``[name]`` (only spaces or tabs after ``]``) starts a group; a name repeated continues that
  group; a name is not empty and holds no ``[``, ``]`` or control character;
- ``key=value`` (not starting with ``=``): the key is what comes before the first ``=`` less its
  trailing whitespace, not starting or ending with a space, without ``[``/``]`` but for a
  trailing ``[locale]``; the value is the rest less its *leading* whitespace (trailing whitespace
  stays); a key repeated in a group takes the last value; a key before any group is an error;
  ``Encoding`` in the first group must be ``UTF-8``;
- any other line is an error (no continuation lines);
- values are unescaped when read: ``\\s`` ``\\n`` ``\\t`` ``\\r`` ``\\\\``; any other escape, or a
  ``\\`` at the end, is an error; :func:`escape` writes a value so (``g_key_file_set_string``).

Translated keys (``key[de]``) are kept under their full name (GLib keeps only the user's
locales'): ``metadata`` lookups name plain keys only.
"""

from __future__ import annotations

__all__ = ["KeyFileError", "escape", "parse_keyfile", "unescape"]

_SPACE = " \t\n\f\r"  # g_ascii_isspace
_ESCAPES = {"s": " ", "n": "\n", "t": "\t", "r": "\r", "\\": "\\"}
_LOCALE_CHARS = frozenset("-_.@")


class KeyFileError(ValueError):
    """The text is not a key file GLib loads, or a value is not one it reads (GLib's wording)."""


def _is_group_name(name: str) -> bool:
    return bool(name) and not any(c in "[]" or ord(c) < 32 or ord(c) == 127 for c in name)


def _is_key_name(key: str) -> bool:
    base, bracket, rest = key.partition("[")
    if not base or "=" in base or "]" in base or base[0] == " " or base[-1] == " ":
        return False
    if not bracket:
        return True
    locale, close, after = rest.partition("]")
    return bool(close) and not after and all(c.isalnum() or c in _LOCALE_CHARS for c in locale)


def parse_keyfile(text: str) -> dict[str, dict[str, str]]:
    """The groups of key file ``text``, each a dict of key → raw value (escapes kept).

    Raises:
        KeyFileError: a line GLib refuses (the message names the line number).
    """
    groups: dict[str, dict[str, str]] = {}
    current: dict[str, str] | None = None
    first: str | None = None
    name = ""
    for number, whole in enumerate(text.split("\n"), 1):
        whole = whole.removesuffix("\r")
        line = whole.lstrip(_SPACE)
        if not line or line[0] == "#":
            continue
        if line[0] == "[" and "]" in line and not line[line.index("]") + 1 :].strip(" \t"):
            name = line[1 : line.index("]")]
            if not _is_group_name(name):
                raise KeyFileError(f"line {number}: Invalid group name: {name}")
            current = groups.setdefault(name, {})
            first = first if first is not None else name
        elif "=" in line and line[0] != "=":
            if current is None:
                raise KeyFileError(f"line {number}: Key file does not start with a group")
            key, _, value = line.partition("=")
            key = key.rstrip(_SPACE)
            if not _is_key_name(key):
                raise KeyFileError(f"line {number}: Invalid key name: {key}")
            value = value.lstrip(_SPACE)
            if name == first and key == "Encoding" and value.upper() != "UTF-8":
                raise KeyFileError(
                    f"line {number}: Key file contains unsupported encoding “{value}”"
                )
            current[key] = value
        else:
            raise KeyFileError(
                f"line {number}: Key file contains line “{whole}” which is not a key-value "
                "pair, group, or comment"
            )
    return groups


def unescape(value: str) -> str:
    """A raw value as ``g_key_file_get_string`` gives it.

    Raises:
        KeyFileError: an unknown escape or a ``\\`` at the end.
    """
    if "\\" not in value:
        return value
    out: list[str] = []
    i = 0
    while (j := value.find("\\", i)) >= 0:
        out.append(value[i:j])
        if j + 1 == len(value):
            raise KeyFileError("Key file contains escape character at end of line")
        char = _ESCAPES.get(value[j + 1])
        if char is None:
            raise KeyFileError(f"Key file contains invalid escape sequence “\\{value[j + 1]}”")
        out.append(char)
        i = j + 2
    out.append(value[i:])
    return "".join(out)


def escape(value: str) -> str:
    """``value`` as ``g_key_file_set_string`` writes it, so that :func:`unescape` (and GLib)
    read it back: ``\\``, newline and carriage return always escaped, spaces and tabs only
    while they lead (the reader drops leading whitespace and keeps trailing whitespace)."""
    out: list[str] = []
    leading = True
    for char in value:
        if leading and char in " \t":
            out.append("\\s" if char == " " else "\\t")
            continue
        leading = False
        out.append({"\\": "\\\\", "\n": "\\n", "\r": "\\r"}.get(char, char))
    return "".join(out)
