"""Shared command-line plumbing: subcommand dispatch, ``--version``, the output checks and the
one-line error contract.

Exit codes: 0 pass, 1 a rule failed, 3 only indeterminate results, 4 a rule ``--require`` asks
for was not decided, 2 unusable input or usage (:mod:`wavecheck.verdict`).

Every output option is declared with ``type=``:func:`wavecheck.output.output_file`; before a
command runs, each one is checked (:func:`wavecheck.output.check_outputs`) against the command's
inputs (every file named by another option), and those inputs stay protected while it runs.
"""

from __future__ import annotations

import argparse
import atexit
import gc
import importlib
import os
import sys
from collections.abc import Callable, Mapping, Sequence
from typing import Any, NamedTuple

from wavecheck import __version__
from wavecheck.errors import UsageError, WavecheckError
from wavecheck.output import OUTPUT_TYPES, check_outputs, protect_inputs

__all__ = ["GC_YOUNG_THRESHOLD", "Command", "as_program", "keep_freed_memory", "run_cli"]


class Command(NamedTuple):
    """A subcommand: the module whose ``register(subparsers)`` builds its parser, and the one
    line the tool's ``--help`` lists for it (the module is imported only when it runs)."""

    module: str
    help: str


class _Parser(argparse.ArgumentParser):
    """argparse with the project's one-line usage errors (exit code 2)."""

    intermixed = False
    """Positionals may follow options (``config HAL --drive X INI``): argparse's plain parse
    takes an optional positional as absent at the first option and then refuses it."""
    _mixing = False

    def error(self, message: str) -> None:  # type: ignore[override]
        self.exit(UsageError.exit_code, f"{self.prog}: error: {message} (see {self.prog} --help)\n")

    _checking = False

    def add_argument(self, *args: Any, **kwargs: Any) -> argparse.Action:
        self._checking = True
        try:
            return super().add_argument(*args, **kwargs)
        finally:
            self._checking = False

    def _get_formatter(self) -> argparse.HelpFormatter:
        # add_argument asks for a formatter only to check the metavar against nargs; the
        # formatter asks for the terminal's width (shutil, ~2 ms of start-up), wanted only
        # when help or an error is written
        if self._checking:
            return self.formatter_class(prog=self.prog, width=80)  # type: ignore[call-arg]
        return super()._get_formatter()

    def parse_known_args(  # type: ignore[override]
        self, args: Sequence[str] | None = None, namespace: argparse.Namespace | None = None
    ) -> tuple[argparse.Namespace, list[str]]:
        if not self.intermixed or self._mixing:
            return super().parse_known_args(args, namespace)
        self._mixing = True  # parse_known_intermixed_args calls parse_known_args itself
        try:
            return self.parse_known_intermixed_args(args, namespace)
        finally:
            self._mixing = False


def run_cli(
    prog: str, description: str, commands: Mapping[str, Command], argv: Sequence[str] | None
) -> int:
    """Build the parser of the subcommand asked for and run it.

    Only that subcommand's module is imported: its ``register(subparsers)`` adds its parser and
    sets ``func`` to a ``run(args) -> int``. When the command is not the first word (``--help``,
    ``--version``, a usage error), every other subcommand is listed from ``commands`` with an
    empty parser that never parses.
    """
    # numpy's OpenBLAS starts a thread per core when numpy is imported: about 0.1 s of CPU at
    # every start, for linear algebra no command does (an environment variable says otherwise)
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    words = sys.argv[1:] if argv is None else list(argv)
    chosen = _command_word(words)
    parser = _Parser(prog=prog, description=description)
    parser.add_argument("--version", action="version", version=f"{prog} {__version__}")
    # dest: not "command", which stepgen simulate's --command option also sets
    # prog given: argparse would format the tool's usage (a formatter, the terminal's width) for it
    sub = parser.add_subparsers(
        dest="_subcommand", metavar="COMMAND", parser_class=_Parser, prog=prog
    )
    sub.required = True
    # the others only where argparse may show them: help or an error before the command word
    alone = bool(words) and words[0] == chosen and chosen in commands
    for name, command in commands.items():
        if name == chosen:
            importlib.import_module(command.module).register(sub)
        elif not alone:
            sub.add_parser(name, help=command.help)
    if argv is None and "numpy" in sys.modules:
        # the program's run (as_program) of a command that works on arrays (numpy has loaded
        # ctypes already): ~5 ms less on grbl_cnc_1.sr's check, 23 % on a 10 M-edge VCD's
        keep_freed_memory()
    args = parser.parse_args(words)
    try:
        outputs, inputs = _files(sub.choices[args._subcommand], args)
        check_outputs(outputs, inputs)  # before any work
        with protect_inputs(inputs):
            return int(args.func(args))
    except WavecheckError as err:
        print(f"{prog}: error: {err}", file=sys.stderr)
        for line in err.details:
            print(f"  {line}", file=sys.stderr)
        return err.exit_code
    except KeyboardInterrupt:
        print(f"{prog}: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        return 0


#: Allocations between two young-generation collections while a command runs as the program
#: (Python's default is 700): importing numpy and a command's modules made dozens of
#: collections. The cyclic garbage a collection would free waits for at most this many.
GC_YOUNG_THRESHOLD = 50_000


def as_program(run: Callable[[], int]) -> int:
    """``run()`` as the whole program (the console script, ``python -m``): the cyclic garbage
    collector runs less often, and when the command leaves no file open, the objects left at
    the end are frozen, so the collection at interpreter exit does not walk them again
    (``wavecheck check`` on grbl_cnc_1.sr: ~25 ms of ~165 ms CPU; bench/README.md, Round 6,
    start-up), and when nothing else is left for the interpreter's teardown to do but free
    memory, the process ends there (:func:`_leave_now`). A file left open is not frozen: the
    teardown frees it, which writes what it still buffers."""
    gc.set_threshold(GC_YOUNG_THRESHOLD, *gc.get_threshold()[1:])
    fds = _open_fds()
    nothing_open = False
    try:
        code = run()
    finally:
        nothing_open = fds is not None and _open_fds() == fds
        if nothing_open:
            gc.freeze()
    if nothing_open:
        _leave_now(code)
    return code


#: Where the process's open file descriptors are listed (Linux; /dev/fd elsewhere).
_FD_DIRS = ("/proc/self/fd", "/dev/fd")


def _open_fds() -> frozenset[str] | None:
    """The process's open file descriptors (with the listing's own), or None if unknown."""
    for folder in _FD_DIRS:
        try:
            return frozenset(os.listdir(folder))
        except OSError:
            continue
    return None


def _leave_now(code: int) -> None:
    """End the process with ``code`` now, without the interpreter's teardown (freeing every
    module and object: ~4 ms after a ``check``; bench/README.md, Round 7), when, beyond what
    :func:`as_program` checked (no file opened since the start), that teardown has nothing
    else to do: no ``atexit`` callback (multiprocessing, coverage, a temporary folder's
    finalizer register one), no other thread, and both standard streams flushed. Otherwise it
    returns and the interpreter exits as usual."""
    if getattr(atexit, "_ncallbacks", lambda: 1)():
        return
    threading = sys.modules.get("threading")
    if threading is not None and threading.active_count() > 1:
        return
    try:
        sys.stdout.flush()
        sys.stderr.flush()
    except (OSError, ValueError):  # a closed pipe: the usual exit reports it as it always did
        return
    os._exit(code)


def glob_matches(text: str) -> list[str] | None:
    """The paths the glob pattern ``text`` matches (``**`` recursive), or None when it has no
    wildcard (``glob.has_magic``; glob itself is imported only for a pattern)."""
    if not any(c in text for c in "*?["):
        return None
    import glob

    return glob.glob(text, recursive=True)


#: glibc ``mallopt`` parameters (malloc.h).
_M_TRIM_THRESHOLD, _M_TOP_PAD, _M_MMAP_THRESHOLD = -1, -2, -3


def keep_freed_memory(top_pad: int = 0) -> None:
    """Ask glibc's malloc to keep freed memory for the next allocations instead of returning it
    to the kernel: trim threshold 1 GiB, and blocks up to 32 MiB from the heap (setting the trim
    threshold alone freezes the mmap threshold at 128 KiB, so every array of 128 KiB or more
    would be mapped, unmapped and faulted in again); ``top_pad``: grow the heap that much at a
    time. A minor page fault costs ~3.5 µs of system time on the bench machine; peak memory is
    the same (bench/README.md, Round 7). Nothing happens off glibc."""
    import ctypes

    try:
        mallopt = ctypes.CDLL(None).mallopt
    except (AttributeError, OSError, TypeError):  # no mallopt (not glibc), no C library
        return
    mallopt(_M_TRIM_THRESHOLD, 1 << 30)
    mallopt(_M_MMAP_THRESHOLD, 32 << 20)  # its largest value
    if top_pad:
        mallopt(_M_TOP_PAD, top_pad)


def _command_word(words: Sequence[str]) -> str | None:
    """The word argparse takes for the subcommand: the tool's own options (``-h``,
    ``--version``) take no value, so it is the first word that is not an option."""
    return next((word for word in words if not word.startswith("-")), None)


def _files(
    parser: argparse.ArgumentParser, args: argparse.Namespace
) -> tuple[dict[str, str | None], dict[str, list[str]]]:
    """The command's output options (option → path) and the files its other options name.

    An input is any existing file named by a free-text option or argument (``FILE``,
    ``ID|FILE``, ``kind:FILE``, a glob pattern); options with choices, numbers and flags are not.
    """
    outputs: dict[str, str | None] = {}
    inputs: dict[str, list[str]] = {}
    for action in parser._actions:  # noqa: SLF001 - argparse has no public list
        if action.nargs == 0 or action.choices is not None or action.dest == argparse.SUPPRESS:
            continue
        name = action.option_strings[0] if action.option_strings else action.dest
        value = getattr(args, action.dest, None)
        if action.type in OUTPUT_TYPES:
            outputs[name] = value
            continue
        if action.type not in (None, str):
            continue
        for text in value if isinstance(value, list) else [value]:
            if not isinstance(text, str) or not text:
                continue
            paths = [text, text.partition(":")[2]]
            paths += glob_matches(text) or []
            found = [p for p in paths if p and os.path.isfile(os.path.expanduser(p))]
            inputs.setdefault(name, []).extend(os.path.expanduser(p) for p in found)
    return outputs, inputs
