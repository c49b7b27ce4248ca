"""``wavecheck sigrok install [--dir DIR]``: the violations in PulseView and sigrok-cli.

Installs the ``wavecheck`` protocol decoder (:mod:`wavecheck.sigrok`) where libsigrokdecode
looks (default: the user decoder directory, which PulseView and sigrok-cli search), then runs
sigrok-cli with it on a small capture to show that libsigrokdecode's Python can import wavecheck.
Exit 0 when the decoder ran (or sigrok-cli is absent and ``--no-probe`` was not needed), 2 when
it is installed but cannot run, with the reason.
"""

from __future__ import annotations

import argparse
from typing import Any

from wavecheck.verdict import EXIT_PASS, EXIT_USAGE

__all__ = ["register", "run"]


def register(sub: Any) -> None:
    """Add the ``sigrok`` subcommand."""
    p = sub.add_parser(
        "sigrok",
        description="Install the wavecheck decoder for libsigrokdecode (PulseView, sigrok-cli): "
        "violations as annotations on the waveform.",
    )
    actions = p.add_subparsers(dest="sigrok_action", metavar="ACTION")
    actions.required = True
    inst = actions.add_parser(
        "install",
        help="put the decoder where libsigrokdecode looks and try it with sigrok-cli",
        description="Copy the decoder into DIR/wavecheck (default: the user decoder directory, "
        "$XDG_DATA_HOME/libsigrokdecode/decoders) with the paths libsigrokdecode's Python needs "
        "to import wavecheck, then run it with sigrok-cli on a small capture.",
    )
    inst.add_argument(
        "--dir", metavar="DIR", help="decoder directory (a SIGROKDECODE_DIR line is printed "
        "when libsigrokdecode does not search it)"
    )  # fmt: skip
    inst.add_argument(
        "--no-probe", action="store_true", help="do not run sigrok-cli with the installed decoder"
    )
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Install the decoder; returns 0, or 2 when sigrok-cli cannot run it."""
    from wavecheck.sigrok.install import install, probe

    installed = install(args.dir)
    print(f"installed the wavecheck decoder in {installed.folder}")
    if not installed.searched:
        print(
            f"libsigrokdecode does not search {installed.folder.parent} by default; "
            f"start sigrok-cli and PulseView after:\n  {installed.env_line}"
        )
    if args.no_probe:
        return EXIT_PASS
    result = probe(installed)
    print(("ok: " if result.ok else "not working: ") + result.text)
    if result.ok or "not installed" in result.text:
        return EXIT_PASS
    return EXIT_USAGE
