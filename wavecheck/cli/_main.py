"""Shared command-line plumbing: subcommand dispatch, ``--version`` and the one-line error
contract.

Exit codes: 0 pass, 1 a rule failed, 3 only indeterminate results, 2 unusable input or usage.
"""

from __future__ import annotations

import argparse
import importlib
import sys
from collections.abc import Sequence

from wavecheck import __version__
from wavecheck.errors import WavecheckError
from wavecheck.verdict import EXIT_FAIL, EXIT_INDETERMINATE, EXIT_PASS, EXIT_USAGE

__all__ = ["EXIT_FAIL", "EXIT_INDETERMINATE", "EXIT_PASS", "EXIT_USAGE", "run_cli"]



class _Parser(argparse.ArgumentParser):
    """argparse with the project's one-line usage errors (exit code 2)."""

    def error(self, message: str) -> None:  # type: ignore[override]
        self.exit(EXIT_USAGE, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def run_cli(prog: str, description: str, modules: Sequence[str], argv: Sequence[str] | None) -> int:
    """Build a parser from subcommand ``modules`` and run the chosen one.

    Each module defines ``register(subparsers)``, which adds its subparser and sets ``func``
    to a ``run(args) -> int``.
    """
    parser = _Parser(prog=prog, description=description)
    parser.add_argument("--version", action="version", version=f"{prog} {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    sub.required = True
    for name in modules:
        importlib.import_module(name).register(sub)
    args = parser.parse_args(argv)
    try:
        return int(args.func(args))
    except WavecheckError as err:
        print(f"{prog}: error: {err}", file=sys.stderr)
        return err.exit_code
    except KeyboardInterrupt:
        print(f"{prog}: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        return 0
