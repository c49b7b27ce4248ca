"""The ``--ini``/``--hal``/``--channel`` options shared by ``wavecheck check`` and ``stepgen simulate``."""

from __future__ import annotations

from typing import Any

__all__ = ["add_file_arguments"]


def add_file_arguments(group: Any) -> None:
    """Add ``--ini FILE``, ``--hal FILE`` (repeatable) and ``--channel N`` to an argparse group."""
    group.add_argument("--ini", metavar="FILE", help="INI file: [EMCMOT] BASE_PERIOD, SERVO_PERIOD")
    group.add_argument(
        "--hal",
        action="append",
        default=[],
        metavar="FILE",
        help="HAL file: loadrt stepgen step_type=/ctrl_type=, setp stepgen.N.* (repeatable)",
    )
    group.add_argument(
        "--channel", type=int, default=0, metavar="N", help="stepgen channel (default 0)"
    )
