"""The drive rule library: ``rules/*.toml`` (and users' own files) read into :class:`Drive`.

A rule file names one drive, its interface and active edge, and its limits; every figure carries
a citation key and a status. ``rules/README.md`` documents the format. Values go through
:mod:`wavecheck.units` (``"4.5us"``, ``"200 kHz"``); time limits become exact ns, the maximum
rate exact Hz. Every malformed file raises :class:`~wavecheck.errors.RuleError` naming the file
and the key.

Search path for ids: the directories in ``$WAVECHECK_RULES`` (``os.pathsep``-separated, first
wins), then the built-in library (:func:`rules_dir`).
"""

from __future__ import annotations

import os
import re
from fractions import Fraction
from pathlib import Path
from typing import Any, get_args

import rtoml

from wavecheck.drives.datasheet import TIME_RULES, ActiveEdge, Drive, Figure, Interface, Status
from wavecheck.errors import RuleError, UnitError
from wavecheck.units import parse_quantity

__all__ = [
    "ENV_VAR",
    "KINDS",
    "LIMIT_KEYS",
    "list_drives",
    "load_drive",
    "rules_dir",
    "search_path",
]

#: Environment variable with extra rule directories (searched before the built-in library).
ENV_VAR = "WAVECHECK_RULES"
#: Keys allowed under ``[limits]``: the time rules (ns) and ``max_rate`` (Hz).
LIMIT_KEYS: tuple[str, ...] = (*TIME_RULES, "max_rate")
KINDS: tuple[str, ...] = ("drive", "ic", "preset", "user")
STATUSES: tuple[str, ...] = get_args(Status)
INTERFACES: tuple[str, ...] = get_args(Interface)
EDGES: tuple[str, ...] = get_args(ActiveEdge)

_ID = re.compile(r"^[a-z0-9]+(?:-[a-z0-9]+)*$")
_TOP_REQUIRED = ("id", "name", "kind", "interface", "active_edge", "limits", "sources")
_TOP_OPTIONAL = ("notes", "step_type", "opto")
_FIGURE_REQUIRED = ("value", "source", "status")
_FIGURE_OPTIONAL = ("note",)
_EDGE_REQUIRED = ("value", "source", "status")
#: The citation key of a user file's plain string limits (``step_high = "2.5us"``).
_USER_SOURCE = "user"
# Sanity bounds: beyond them a figure is a typo (and would overflow float formatting).
_MAX_LIMIT_S = 1000
_MAX_RATE_HZ = 10**12


def rules_dir() -> Path:
    """The built-in rule library: ``wavecheck/_rules``, which in the repository is a symlink to
    ``rules/`` (so this returns the repo's ``rules/``) and in a wheel holds the shipped copy."""
    package = Path(__file__).resolve().parent.parent
    shipped = package / "_rules"
    if shipped.is_dir():
        return shipped.resolve()
    return package.parent / "rules"  # a checkout without symlinks


def search_path() -> list[Path]:
    """Directories searched for ids: ``$WAVECHECK_RULES`` entries, then :func:`rules_dir`."""
    extra = [Path(p) for p in os.environ.get(ENV_VAR, "").split(os.pathsep) if p]
    return [*extra, rules_dir()]


#: Per process: each drive file parsed once while its bytes are unchanged (``check`` of many
#: captures loads the same drive for every one; a file's mtime can stay the same across a quick
#: rewrite, so the bytes are compared), and each search path listed once while no folder of it
#: changes (mtime). A :class:`Drive` is immutable. A user file with ``extends`` is not cached
#: (its base may change apart from it).
_DRIVES: dict[tuple[str, bool], tuple[bytes, Drive]] = {}
_LISTINGS: dict[tuple[tuple[str, int], ...], dict[str, Path]] = {}


def _mtime(path: Path) -> int:
    """``path``'s modification time in ns (-1 when it cannot be stat'ed)."""
    try:
        return path.stat().st_mtime_ns
    except OSError:
        return -1


def _rule_files() -> dict[str, Path]:
    """id → file over the search path (first directory wins); listed again only when a folder
    of the search path changes (a file added, removed or renamed changes its mtime)."""
    folders = search_path()
    key = tuple((str(f), _mtime(f)) for f in folders)
    cached = _LISTINGS.get(key)
    if cached is not None:
        return dict(cached)
    found: dict[str, Path] = {}
    for folder in folders:
        if folder.is_dir():
            for path in sorted(folder.glob("*.toml")):
                found.setdefault(path.stem, path)
    _LISTINGS.clear()
    _LISTINGS[key] = found
    return dict(found)


def list_drives() -> list[Drive]:
    """Every drive on the search path, sorted by id. A malformed file raises RuleError."""
    return [_load_file(path) for _, path in sorted(_rule_files().items())]


def _file_of(files: dict[str, Path], drive_id: str) -> Path | None:
    """The rule file of ``drive_id``: ids are case-insensitive (``DRV8825`` is ``drv8825``), an
    exact match first."""
    if drive_id in files:
        return files[drive_id]
    folded = [path for name, path in files.items() if name.casefold() == drive_id.casefold()]
    return folded[0] if folded else None


def load_drive(id_or_path: str | os.PathLike[str]) -> Drive:
    """Load a drive by id (``"gecko-g202"``) or from a TOML file path of the same form.

    Raises:
        RuleError: the file is malformed (names file and key), or the id is unknown (lists close
            matches).
    """
    text = os.fspath(id_or_path)
    looks_like_path = text.endswith(".toml") or os.sep in text or "/" in text
    if looks_like_path or (not _ID.match(text.lower()) and Path(text).is_file()):
        path = Path(text)
        if not path.is_file():
            raise RuleError(
                path, None, "no such rule file (give a drive id or a path to a .toml file)"
            )
        return _load_file(path, user=not _in_library(path))
    files = _rule_files()
    found = _file_of(files, text)
    if found is not None:
        return _load_file(found)
    close = _close_matches(text.lower(), list(files), n=4, cutoff=0.5)
    hint = f"did you mean {', '.join(close)}? " if close else ""
    raise RuleError(text, None, f"unknown drive id ({hint}`wavecheck drives` lists them)")


# ---------------------------------------------------------------------------------------------
# parsing and validation


def _close_matches(word: str, possibilities: Any, n: int = 3, cutoff: float = 0.6) -> list[str]:
    """difflib's close matches, imported only for an error's hint."""
    import difflib

    return difflib.get_close_matches(word, possibilities, n=n, cutoff=cutoff)


def _in_library(path: Path) -> bool:
    try:
        path.resolve().relative_to(rules_dir())
    except ValueError:
        return False
    return True


#: How deep ``extends`` may chain (a cycle is an error long before this).
_MAX_EXTENDS = 8


def _read_toml(path: Path, raw: bytes | None = None) -> dict[str, Any]:
    """The file's TOML data (``raw``: its bytes, when already read). rtoml (compiled) parses
    it, the library's 46 files in ~1 ms against tomllib's ~8 ms, to the same data (tested); a
    file rtoml refuses is parsed again by tomllib, whose message (or data, should it accept)
    counts."""
    try:
        text = (path.read_bytes() if raw is None else raw).decode("utf-8")
    except UnicodeDecodeError as err:
        raise RuleError(
            path, None, f"not UTF-8 text (byte {err.start}): a rule file must be UTF-8 TOML"
        ) from None
    except OSError as err:
        raise RuleError(path, None, f"cannot read: {err.strerror}") from None
    try:
        data: dict[str, Any] = rtoml.loads(text)
    except rtoml.TomlParsingError:
        import tomllib  # its messages are the ones users see

        try:
            data = tomllib.loads(text)
        except tomllib.TOMLDecodeError as err:
            raise RuleError(path, None, f"not valid TOML: {err}") from None
    return data


def _load_file(path: Path, user: bool = False) -> Drive:
    """The drive of ``path``, parsed once per process while the file's bytes are unchanged."""
    try:
        raw = path.read_bytes()
    except OSError:
        return _parse_file(path, user)  # its error, as without the cache
    key = (os.path.abspath(path), user)
    hit = _DRIVES.get(key)
    if hit is not None and hit[0] == raw:
        return hit[1]
    drive = _parse_file(path, user, raw)
    if not (user and b"extends" in raw):
        _DRIVES[key] = (raw, drive)
    return drive


def _parse_file(path: Path, user: bool, raw: bytes | None = None) -> Drive:
    data = _read_toml(path, raw)
    if user:
        data = _resolve_extends(path, data, ())
    return _parse(path, data, user=user)


def _resolve_extends(path: Path, data: dict[str, Any], seen: tuple[Path, ...]) -> dict[str, Any]:
    """A user file's ``extends = "ID|PATH"``: the base file's keys, the user's on top (``limits``
    and ``sources`` merged per key); ``id`` defaults to the file name."""
    data = dict(data)
    base_ref = data.pop("extends", None)
    if base_ref is None:
        return data
    data.setdefault("id", path.stem)
    if not isinstance(base_ref, str) or not base_ref.strip():
        raise RuleError(path, "extends", f"expected a drive id or a path, got {base_ref!r}")
    if len(seen) >= _MAX_EXTENDS or path.resolve() in seen:
        raise RuleError(path, "extends", f"{base_ref!r}: extends chain loops or is too long")
    looks_like_path = base_ref.endswith(".toml") or "/" in base_ref or os.sep in base_ref
    files = _rule_files()
    if looks_like_path:
        base_path = (path.parent / base_ref) if not Path(base_ref).is_absolute() else Path(base_ref)
    elif (found := _file_of(files, base_ref)) is not None:
        base_path = found
    else:
        close = _close_matches(base_ref, list(files), n=3, cutoff=0.5)
        hint = f" (did you mean {', '.join(close)}?)" if close else ""
        raise RuleError(path, "extends", f"unknown drive {base_ref!r}{hint}")
    if not base_path.is_file():
        raise RuleError(path, "extends", f"no such rule file {str(base_path)!r}")
    base = _read_toml(base_path)
    base = _resolve_extends(base_path, base, (*seen, path.resolve()))
    merged = {**base, **data}
    for key in ("limits", "sources"):
        if isinstance(base.get(key), dict) and isinstance(data.get(key), dict):
            merged[key] = {**base[key], **data[key]}
    merged["notes"] = [
        *(base.get("notes", []) if isinstance(base.get("notes", []), list) else []),
        f"extends {base['id'] if 'id' in base else base_ref} ({base_path})",
        *(data.get("notes", []) if isinstance(data.get("notes", []), list) else []),
    ]
    if "kind" not in data:
        merged["kind"] = "user"
    return merged


def _check_keys(
    path: Path,
    where: str,
    table: dict[str, Any],
    required: tuple[str, ...],
    optional: tuple[str, ...],
) -> None:
    allowed = (*required, *optional)
    for key in table:
        if key not in allowed:
            close = _close_matches(key, allowed, n=1)
            hint = f"did you mean {close[0]!r}?" if close else f"allowed: {', '.join(allowed)}"
            if not where and key in LIMIT_KEYS:  # a figure written at the top of the file
                value = table[key]
                shown = f'"{value}"' if isinstance(value, str) else repr(value)
                hint = f"a figure goes under [limits]: [limits] {key} = {shown}"
            raise RuleError(path, f"{where}{key}", f"unknown key ({hint})")
    for key in required:
        if key not in table:
            raise RuleError(path, f"{where}{key}", "missing (required)")


def _string(path: Path, key: str, value: Any) -> str:
    if not isinstance(value, str) or not value.strip():
        raise RuleError(path, key, f"expected a non-empty string, got {value!r}")
    return value


def _choice(path: Path, key: str, value: Any, choices: tuple[str, ...]) -> str:
    if value not in choices:
        raise RuleError(path, key, f"{value!r} is not one of {', '.join(choices)}")
    return str(value)


def _source(path: Path, key: str, value: Any, sources: dict[str, str]) -> str:
    cite = _string(path, key, value)
    if cite not in sources:
        raise RuleError(path, key, f"source {cite!r} is not in the [sources] table")
    return cite


def _figure(
    path: Path, rule: str, table: Any, sources: dict[str, str], user: bool = False
) -> Figure:
    where = f"limits.{rule}"
    if user and isinstance(table, str):
        table = {"value": table, "source": _USER_SOURCE, "status": "user"}
    if not isinstance(table, dict):
        raise RuleError(path, where, "expected a table with value, source, status")
    _check_keys(path, where + ".", table, _FIGURE_REQUIRED, _FIGURE_OPTIONAL)
    raw = table["value"]
    if not isinstance(raw, str):
        raise RuleError(
            path,
            f"{where}.value",
            f"expected a quantity string with a unit such as '4.5us', got {raw!r}",
        )
    try:
        value, dim = parse_quantity(raw)
    except UnitError as err:
        raise RuleError(path, f"{where}.value", str(err)) from None
    if rule == "max_rate":
        if dim != "frequency":
            raise RuleError(
                path,
                f"{where}.value",
                f"{raw!r} is a time; max_rate is a frequency such as '200 kHz'",
            )
        if value <= 0:
            raise RuleError(path, f"{where}.value", f"{raw!r} must be positive")
        if value > _MAX_RATE_HZ:
            raise RuleError(path, f"{where}.value", f"{raw!r} is implausibly high (at most 1 THz)")
    else:
        if dim != "time":
            raise RuleError(
                path, f"{where}.value", f"{raw!r} is a frequency; {rule} is a time such as '4.5us'"
            )
        if value < 0:
            raise RuleError(
                path, f"{where}.value", f"{raw!r} is negative (limits are minimum times >= 0)"
            )
        if value > _MAX_LIMIT_S:
            raise RuleError(path, f"{where}.value", f"{raw!r} is implausibly long (at most 1000 s)")
        value = value * 10**9
    status = _choice(path, f"{where}.status", table["status"], STATUSES)
    note = table.get("note", "")
    if not isinstance(note, str):
        raise RuleError(path, f"{where}.note", f"expected a string, got {note!r}")
    return Figure(
        value=Fraction(value),
        source=_source(path, f"{where}.source", table["source"], sources),
        status=status,  # type: ignore[arg-type]
        note=note,
    )


class _Errors:
    """Collects a rule file's errors so that a user file's are reported all at once."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.found: list[RuleError] = []

    def run(self, fn: Any, *args: Any, default: Any = None) -> Any:
        try:
            return fn(*args)
        except RuleError as err:
            self.found.append(err)
            return default

    def raise_any(self) -> None:
        if len(self.found) == 1:
            raise self.found[0]
        if self.found:
            prefix = f"{self.path}: "
            parts = "; ".join(str(e).removeprefix(prefix) for e in self.found)
            raise RuleError(self.path, None, f"{len(self.found)} errors: {parts}")


def _parse(path: Path, data: dict[str, Any], user: bool = False) -> Drive:
    errors = _Errors(path)
    if user:
        data = dict(data)
        if isinstance(data.get("sources"), dict) and _USER_SOURCE not in data["sources"]:
            data["sources"] = {**data["sources"], _USER_SOURCE: f"user rule file {path}"}
    _check_keys(path, "", data, _TOP_REQUIRED, _TOP_OPTIONAL)
    drive_id = _string(path, "id", data["id"])
    if drive_id != path.stem and not user:
        raise RuleError(
            path, "id", f"{drive_id!r} does not match the file name {path.stem!r} (rename one)"
        )
    if not _ID.match(drive_id):
        errors.found.append(
            RuleError(path, "id", f"{drive_id!r} must be lower case letters, digits and hyphens")
        )

    sources = data["sources"]
    if not isinstance(sources, dict) or not sources:
        raise RuleError(path, "sources", "expected a table of citation key = full reference")
    for key, text in sources.items():
        errors.run(_string, path, f"sources.{key}", text)

    kind = errors.run(_choice, path, "kind", data["kind"], KINDS, default="user")
    interface = errors.run(
        _choice, path, "interface", data["interface"], INTERFACES, default="step-dir"
    )

    edge_raw = data["active_edge"]
    edge_source, edge_status, edge_note = "", None, ""
    edge: Any = "rising"
    if isinstance(edge_raw, dict):
        errors.run(_check_keys, path, "active_edge.", edge_raw, _EDGE_REQUIRED, _FIGURE_OPTIONAL)
        if all(k in edge_raw for k in _EDGE_REQUIRED):
            edge = errors.run(
                _choice, path, "active_edge.value", edge_raw["value"], EDGES, default="rising"
            )
            edge_source = errors.run(
                _source, path, "active_edge.source", edge_raw["source"], sources, default=""
            )
            edge_status = errors.run(
                _choice, path, "active_edge.status", edge_raw["status"], STATUSES
            )
        edge_note = edge_raw.get("note", "")
        if not isinstance(edge_note, str):
            errors.found.append(
                RuleError(path, "active_edge.note", f"expected a string, got {edge_note!r}")
            )
            edge_note = ""
    else:
        edge = errors.run(_choice, path, "active_edge", edge_raw, EDGES, default="rising")

    limits_raw = data["limits"]
    if not isinstance(limits_raw, dict):
        raise RuleError(path, "limits", "expected a table of [limits.RULE] tables")
    limits: dict[str, Figure] = {}
    max_rate: Figure | None = None
    for rule, table in limits_raw.items():
        if rule not in LIMIT_KEYS:
            close = _close_matches(rule, LIMIT_KEYS, n=1)
            hint = f"did you mean {close[0]!r}?" if close else f"allowed: {', '.join(LIMIT_KEYS)}"
            errors.found.append(RuleError(path, f"limits.{rule}", f"unknown rule ({hint})"))
            continue
        fig = errors.run(_figure, path, rule, table, sources, user)
        if fig is None:
            continue
        if rule == "max_rate":
            max_rate = fig
        else:
            limits[rule] = fig

    notes = data.get("notes", [])
    if not isinstance(notes, list) or not all(isinstance(n, str) for n in notes):
        errors.found.append(RuleError(path, "notes", "expected a list of strings"))
        notes = []
    step_type = data.get("step_type")
    if step_type is not None and (
        not isinstance(step_type, int) or isinstance(step_type, bool) or not 0 <= step_type <= 15
    ):
        errors.found.append(
            RuleError(path, "step_type", f"expected a LinuxCNC step type 0..15, got {step_type!r}")
        )
    opto = data.get("opto")
    if opto is not None and not isinstance(opto, bool):
        errors.found.append(RuleError(path, "opto", f"expected true or false, got {opto!r}"))
    errors.raise_any()

    return Drive(
        id=drive_id,
        name=_string(path, "name", data["name"]),
        path=path,
        kind=kind,
        interface=interface,
        active_edge=edge,
        limits=limits,
        max_rate=max_rate,
        sources=dict(sources),
        notes=tuple(notes),
        edge_source=edge_source,
        edge_status=edge_status,
        edge_note=edge_note,
        step_type=step_type,
        opto=opto,
    )
