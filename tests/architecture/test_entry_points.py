"""Every entry point accepts the same options (issue 23), as the one table of their spellings
says (:data:`wavecheck.options.OPTIONS`, issue 37): each field of the one options object,
:class:`wavecheck.engine.CheckOptions`, is set by an option of the table, and the command line
(``check``, ``watch``), :func:`wavecheck.check` / :func:`wavecheck.check_axes`, the cocotb
``StepMonitor``, the pytest plugin's ``wavecheck.toml`` and the PulseView decoder take each
option in the spelling the table gives it. An entry point that cannot take one says why here."""

from __future__ import annotations

import argparse
import importlib
import inspect
from dataclasses import fields
from pathlib import Path

import pytest

from wavecheck.engine import CheckOptions
from wavecheck.options import OPTIONS, CheckKeywords

#: option → why ``wavecheck watch`` has no spelling of it.
NOT_WATCH = {
    "block_edges": "a live watch checks what arrived every few tenths of a second",
    "pictures": "a live watch keeps --snippets of the violations instead",
    "samplerate": "the device's --samplerate is the acquisition's (another option)",
    "input_format": "a live device is read by sigrok-cli",
}
#: option → why the cocotb ``StepMonitor`` has no keyword of it.
NOT_COCOTB = {
    "map": "the roles are the DUT's handles: step=, dir=, axes=",
    "samplerate": "the simulator's time precision is the time base",
    "input_format": "no file is read",
}
#: CheckOptions fields no user option sets.
ENGINE_ONLY = {"infer_edges": "the engine's own bound on what it reads to tell roles"}


def _cli_options(command: str) -> set[str]:
    """The options of ``wavecheck COMMAND`` (its module's own ``register``)."""
    sub = argparse.ArgumentParser().add_subparsers()
    importlib.import_module(f"wavecheck.cli.{command}").register(sub)
    return {o for a in sub.choices[command]._actions for o in a.option_strings}


def _keywords(function: object) -> set[str]:
    """The keywords ``function`` takes: its parameters and its ``**keywords``' TypedDict."""
    parameters = inspect.signature(function).parameters  # type: ignore[arg-type]
    named = {n for n, p in parameters.items() if p.kind is not p.VAR_KEYWORD}
    if any(p.kind is p.VAR_KEYWORD for p in parameters.values()):
        named |= set(CheckKeywords.__annotations__)
    return named


def test_every_field_is_set_by_an_option() -> None:
    names = {f.name for f in fields(CheckOptions)}
    set_by_options = {o.field for o in OPTIONS if o.field}
    assert set_by_options | set(ENGINE_ONLY) == names
    assert len({o.name for o in OPTIONS}) == len(OPTIONS)


def test_the_keywords_typed_are_the_table_s() -> None:
    own_parameters = {"drive", "map", "samplerate", "input_format"}
    assert set(CheckKeywords.__annotations__) == {o.keyword for o in OPTIONS if o.keyword} - (
        own_parameters
    )


@pytest.mark.parametrize("command", ["check", "watch"])
def test_the_command_line_takes_every_option(command: str) -> None:
    accepted = _cli_options(command)
    skip = NOT_WATCH if command == "watch" else {}
    missing = [f for o in OPTIONS if o.name not in skip for f in o.cli if f not in accepted]
    assert not missing, f"wavecheck {command} does not take {missing}"
    assert all(o.cli for o in OPTIONS), "every option has a command-line spelling"


def test_the_python_entry_points_take_every_keyword() -> None:
    from wavecheck.api import check, check_axes
    from wavecheck.cocotb import StepMonitor

    for entry, skip in ((check, {}), (check_axes, {}), (StepMonitor, NOT_COCOTB)):
        accepted = _keywords(entry)
        missing = [o.keyword for o in OPTIONS if o.keyword and o.name not in skip]
        assert not [k for k in missing if k not in accepted], entry


def test_the_plugin_and_the_decoder_take_their_spellings() -> None:
    from wavecheck.pytest_plugin import _KEYS
    from wavecheck.sigrok.decoder.pd import OPTIONS as DECODER

    assert {o.toml for o in OPTIONS if o.toml} <= _KEYS
    ids = {d["id"] for d in DECODER}
    assert {o.decoder for o in OPTIONS if o.decoder} <= ids
    # the decoder's other options are its own (how it shows what it finds)
    assert ids - {o.decoder for o in OPTIONS} == {"unit", "pause"}


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
