"""The LinuxCNC stepgen configuration options of ``check`` and ``watch``: ``--ini``, ``--hal``,
``--channel``, ``--base-period``, ``--steplen`` …, ``--latency``, for the ``config`` and
``latency_safe`` max step rates (read into the options object: :mod:`wavecheck.cli._axis_args`)."""

from __future__ import annotations

import argparse
import sys
from fractions import Fraction
from typing import TYPE_CHECKING

from wavecheck.cli._linuxcnc_args import add_file_arguments
from wavecheck.errors import UsageError
from wavecheck.units import BASE_PERIOD, LATENCY, option_ns

if TYPE_CHECKING:  # imported where used: only with a stepgen configuration
    from wavecheck.linuxcnc.stepgen_config import LinuxCNCConfig

__all__ = ["add_stepgen_arguments", "latency_ns", "stepgen_config"]


def add_stepgen_arguments(p: argparse.ArgumentParser) -> None:
    """Add the LinuxCNC stepgen configuration options (``--ini``, ``--hal``, ``--channel``,
    ``--base-period``, ``--steplen`` …, ``--latency``) for the ``config``/``latency_safe``
    rates."""
    cfg = p.add_argument_group("stepgen configuration (config and latency_safe step rates)")
    add_file_arguments(cfg)
    for name, what in _CONFIG_OPTIONS.items():
        cfg.add_argument(
            f"--{name.replace('_', '-')}",
            metavar="T",
            help=f"{what}, with its unit (e.g. 16us; overrides --ini/--hal)"
            + ("; below 1 us is refused as a unit slip" if name == "base_period" else ""),
        )
    cfg.add_argument(
        "--latency",
        metavar="J",
        help="worst base-thread latency, with its unit (e.g. 11us), for latency_safe; "
        "below 100 ns gives a warning",
    )


#: check's stepgen-configuration options (config and latency_safe rates), LinuxCNC's names.
_CONFIG_OPTIONS = {
    "base_period": "BASE_PERIOD",
    "steplen": "stepgen steplen",
    "stepspace": "stepgen stepspace",
    "dirsetup": "stepgen dirsetup",
    "dirhold": "stepgen dirhold",
}


def stepgen_config(args: argparse.Namespace) -> LinuxCNCConfig | None:
    """The stepgen configuration of ``--ini``/``--hal``/``--base-period``/… (None: not given)."""
    cfg = None
    given = {k: getattr(args, k, None) for k in _CONFIG_OPTIONS}
    if getattr(args, "ini", None) or getattr(args, "hal", None) or any(given.values()):
        from wavecheck.linuxcnc.stepgen_config import read_config

        cfg = read_config(args.ini, list(args.hal or []), getattr(args, "channel", 0))
        for name, text in given.items():
            if text is None:
                continue
            option = f"--{name.replace('_', '-')}"
            ns = option_ns(text, option, BASE_PERIOD if name == "base_period" else None)
            if ns.denominator != 1 or ns < 0 or (name == "base_period" and ns == 0):
                raise UsageError(f"{option} {text}: must be a whole, positive number of ns")
            if name == "base_period":
                cfg.base_period_ns = int(ns)
            else:
                cfg.params[name] = int(ns)
            cfg.sources[name] = option
    elif getattr(args, "latency", None):
        raise UsageError(
            "--latency needs the stepgen configuration: give --ini/--hal or --base-period"
        )
    return cfg


def latency_ns(args: argparse.Namespace) -> Fraction | None:
    """``--latency`` in exact ns (None when not given; a warning below 100 ns)."""
    text = getattr(args, "latency", None)
    j = None
    if text is not None:
        j = option_ns(text, "--latency", LATENCY, _warn)
        if j < 0:
            raise UsageError(f"--latency {text}: must not be negative")
    return j


def _warn(message: str) -> None:
    print(f"wavecheck: warning: {message}", file=sys.stderr)
