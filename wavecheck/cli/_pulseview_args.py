"""``--pulseview FILE.pvs`` of ``check`` and ``simulate`` (the session is written by
:func:`wavecheck.sigrok.session.write_pulseview`, imported only when the option is given)."""

from __future__ import annotations

import argparse
from typing import Any

from wavecheck.errors import UsageError
from wavecheck.output import output_file

__all__ = ["add_pulseview_argument", "check_pulseview"]


def add_pulseview_argument(p: Any) -> None:
    """``--pulseview FILE.pvs`` (checked before any work, like every output)."""
    p.add_argument(
        "--pulseview",
        type=output_file,
        metavar="FILE.pvs",
        help="write a PulseView session with the wavecheck decoder stacked on the capture "
        "(open: pulseview -s FILE.pvs -i CAPTURE; install the decoder once with "
        "'wavecheck sigrok install')",
    )


def check_pulseview(args: argparse.Namespace, captures: int) -> None:
    """Refuse ``--pulseview`` for several captures (one session opens one capture)."""
    if captures != 1:
        raise UsageError(f"--pulseview opens one capture in PulseView; {captures} were given")
