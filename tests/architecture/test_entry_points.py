"""Every entry point accepts the same options (issue 23): each field of the one options object,
:class:`wavecheck.engine.options.CheckOptions`, is something the command line (``check``,
``watch``), :func:`wavecheck.check` / :func:`wavecheck.check_axes`, the pytest plugin's
``wavecheck.toml`` and the cocotb ``StepMonitor`` take, each in its own spelling; a field an entry
point cannot take says why here. A field added to CheckOptions fails this test until every entry
point takes it (or says why not)."""

from __future__ import annotations

import argparse
import importlib
import inspect
from dataclasses import fields
from pathlib import Path

import pytest

from wavecheck.engine.options import CheckOptions

#: field → its spelling per entry point (a CLI option, a keyword, a TOML key); a string
#: starting with "n/a: " says why that entry point has none.
SPELLINGS: dict[str, dict[str, tuple[str, ...] | str]] = {
    "drive": {"check": ("--drive",), "watch": ("--drive",), "api": ("drive",),
              "toml": ("drive",), "cocotb": ("drive",)},
    "axes": {"check": ("--map",), "watch": ("--map",), "api": ("map",), "toml": ("map", "axes"),
             "cocotb": ("step", "dir", "axes")},
    "invert": {"check": ("--invert",), "watch": ("--invert",), "api": ("invert",),
               "toml": ("invert",), "cocotb": ("invert",)},
    "step_type": {"check": ("--type",), "watch": ("--type",), "api": ("step_type",),
                  "toml": ("type",), "cocotb": ("step_type",)},
    "forward_level": {"check": ("--dir-forward",), "watch": ("--dir-forward",),
                      "api": ("forward_level",), "toml": ("dir_forward",),
                      "cocotb": ("forward_level",)},
    "user_table": {"check": ("--user-step-type",), "watch": ("--user-step-type",),
                   "api": ("user_table",), "toml": ("user_step_type",),
                   "cocotb": ("user_table",)},
    "pulse_level": {"check": ("--pulse-level",), "watch": ("--pulse-level",),
                    "api": ("pulse_level",), "toml": ("pulse_level",), "cocotb": ("pulse_level",)},
    "active_edge": {"check": ("--active-edge",), "watch": ("--active-edge",),
                    "api": ("active_edge",), "toml": ("active_edge",), "cocotb": ("active_edge",)},
    "resolution": {"check": ("--resolution",), "watch": ("--resolution",),
                   "api": ("resolution",), "toml": ("resolution",), "cocotb": ("resolution",)},
    "limits": {"check": ("--limit",), "watch": ("--limit",), "api": ("limit",),
               "toml": ("limit",), "cocotb": ("limit",)},
    "margin": {"check": ("--margin",), "watch": ("--margin",), "api": ("margin",),
               "toml": ("margin",), "cocotb": ("margin",)},
    "stepgen": {"check": ("--ini", "--hal", "--channel", "--base-period"),
                "watch": ("--ini", "--hal", "--channel", "--base-period"),
                "api": ("ini", "hal", "channel"), "toml": ("ini", "hal", "channel"),
                "cocotb": ("ini", "hal", "channel")},
    "latency_ns": {"check": ("--latency",), "watch": ("--latency",), "api": ("latency",),
                   "toml": ("latency",), "cocotb": ("latency",)},
    "keep_violations": {"check": ("--max-violations",), "watch": ("--max-violations",),
                        "api": ("keep_violations",),
                        "toml": "n/a: a test item shows the few worst; --wavecheck-max-violations",
                        "cocotb": ("keep_violations",)},
    "block_edges": {"check": ("--block-edges",),
                    "watch": "n/a: a live watch checks what arrived every few tenths of a second",
                    "api": ("block_edges",),
                    "toml": "n/a: a test capture is checked with the engine's default blocks",
                    "cocotb": ("batch",)},
    "pictures": {"check": ("--plot", "--html", "--gtkw"),
                 "watch": "n/a: a live watch keeps --snippets of the violations instead",
                 "api": ("pictures",),
                 "toml": "n/a: the plugin draws a failing capture's page itself (--wavecheck-html)",
                 "cocotb": ("pictures",)},
    "require": {p: ("--require",) if p in ("check", "watch") else ("require",)
                for p in ("check", "watch", "api", "toml", "cocotb")},
    "infer_edges": {p: "n/a: the engine's own bound on what it reads to tell roles"
                    for p in ("check", "watch", "api", "toml", "cocotb")},
}  # fmt: skip
ENTRY_POINTS = ("check", "watch", "api", "toml", "cocotb")


def _cli_options(command: str) -> set[str]:
    """The options of ``wavecheck COMMAND`` (its module's own ``register``)."""
    sub = argparse.ArgumentParser().add_subparsers()
    importlib.import_module(f"wavecheck.cli.{command}").register(sub)
    return {o for a in sub.choices[command]._actions for o in a.option_strings}


def _accepted(entry: str) -> set[str]:
    if entry in ("check", "watch"):
        return _cli_options(entry)
    if entry == "api":
        from wavecheck.api import check, check_axes

        a, b = inspect.signature(check).parameters, inspect.signature(check_axes).parameters
        return set(a) & set(b) | {"map"}
    if entry == "toml":
        from wavecheck.pytest_plugin import _KEYS

        return set(_KEYS)
    from wavecheck.cocotb import StepMonitor

    return set(inspect.signature(StepMonitor).parameters)


def test_the_table_covers_every_field() -> None:
    names = {f.name for f in fields(CheckOptions)}
    assert set(SPELLINGS) >= names, (
        "a CheckOptions field no entry point was checked for: add it to SPELLINGS"
    )
    assert set(SPELLINGS) <= names
    for field, per in SPELLINGS.items():
        assert set(per) == set(ENTRY_POINTS), field


@pytest.mark.parametrize("entry", ENTRY_POINTS)
def test_every_entry_point_takes_every_field(entry: str) -> None:
    accepted = _accepted(entry)
    missing = []
    for field, per in SPELLINGS.items():
        spelling = per[entry]
        if isinstance(spelling, str):
            assert spelling.startswith("n/a: "), (field, entry)
            continue
        missing += [f"{field} as {s}" for s in spelling if s not in accepted]
    assert not missing, f"{entry} does not take: {', '.join(missing)}"


def test_options_that_cannot_apply_are_refused_alike() -> None:
    """--latency without a stepgen configuration: one refusal, the same words, everywhere."""
    import wavecheck
    from wavecheck.cli import main
    from wavecheck.errors import UsageError

    with pytest.raises(UsageError, match="--latency needs the stepgen configuration"):
        CheckOptions(latency_ns=1)  # type: ignore[arg-type]
    vcd = str(Path(__file__).resolve().parents[2] / "captures" / "golden" / "stepgen0.vcd")
    with pytest.raises(UsageError, match="--latency needs the stepgen configuration"):
        wavecheck.check(vcd, "gecko-g202", latency="11us")
    assert main(["check", vcd, "--drive", "gecko-g202", "--latency", "11us"]) == 2
