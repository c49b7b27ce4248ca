"""The options that change a drive's figures and what must be decided, shared by ``check``,
``watch``, ``config`` and ``stepgen plan``: ``--limit RULE=VALUE``, ``--margin``, ``--require``."""

from __future__ import annotations

import argparse

__all__ = ["add_limit_arguments", "add_tuning_arguments", "required"]


def add_limit_arguments(p: argparse.ArgumentParser) -> None:
    """``--limit RULE=VALUE`` (repeatable) and ``--margin 2x|+500ns``: the drive's figures as
    the user changes them (:func:`wavecheck.drives.overrides.tune_drive`; ``stepgen plan`` too)."""
    p.add_argument(
        "--limit",
        action="append",
        default=[],
        metavar="RULE=VALUE",
        help="override one drive figure (step_high=5us, max_rate=100kHz; repeatable); the "
        "report shows the datasheet figure beside it",
    )
    p.add_argument(
        "--margin",
        metavar="2x|+500ns",
        help="tighten every datasheet figure: a factor (2x, as StepConf advises for 3.3 V "
        "parallel ports) or an added time (+500ns); --limit figures are taken as given",
    )


def add_tuning_arguments(p: argparse.ArgumentParser) -> None:
    """:func:`add_limit_arguments` and ``--require RULES|all`` (which rules must be decided)."""
    add_limit_arguments(p)
    p.add_argument(
        "--require",
        action="append",
        default=[],
        metavar="RULES|all",
        help="rules that must be decided (comma-separated; all: every rule the drive gives a "
        "figure for): one not checked or indeterminate makes the run exit 4, with a line "
        "saying why (repeatable)",
    )


def required(args: argparse.Namespace) -> tuple[str, ...]:
    """``--require`` as rule ids (and ``all``), each once (checked by the options object)."""
    from wavecheck.verdict import require_list

    return require_list(getattr(args, "require", None))
