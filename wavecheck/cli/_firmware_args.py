"""A capture against the firmware configuration that made it: the options ``check``, ``measure``
and ``config`` share (``--firmware``, ``--axis``, ``--firmware-axis``, ``--firmware-format``,
``--hm2-clock``) and :func:`check_firmware`, which ``check --firmware`` runs on each report and
``measure --firmware`` on each axis (pairing: :mod:`wavecheck.firmware.pairing`)."""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING, Any

from wavecheck.firmware import FIRMWARES, read_firmware
from wavecheck.units import parse_frequency, time_ns

if TYPE_CHECKING:  # imported where used: only with a firmware configuration
    from wavecheck.firmware.capture import FirmwareCheck
    from wavecheck.firmware.guarantee import FirmwareConfig

__all__ = ["add_firmware_arguments", "check_firmware", "firmware_config", "read_firmware_args"]


def add_firmware_arguments(p: argparse.ArgumentParser, *, positional: bool = False) -> None:
    """``--firmware FILE`` (unless ``positional``), ``--firmware-format``, ``--axis``,
    ``--hm2-clock``; LinuxCNC's ``--latency`` comes from the stepgen options where present."""
    if not positional:
        p.add_argument(
            "--firmware",
            metavar="FILE",
            help="the firmware configuration that made the capture: a capture violating its "
            "own configuration is reported apart from the drive rules",
        )
        p.add_argument(
            "--axis",
            metavar="NAME",
            help="the axis of --firmware FILE a single unnamed capture axis is (default: the "
            "only or the first; the report says which)",
        )
        p.add_argument(
            "--firmware-axis",
            action="append",
            default=[],
            metavar="CAPTURE=FIRMWARE",
            help="pair a capture axis with a firmware axis of another name (y=beta, "
            "x=stepper_x; repeatable); otherwise axes pair by name",
        )
    p.add_argument(
        "--firmware-format",
        choices=FIRMWARES,
        help="the firmware (default: detected from the content)",
    )
    p.add_argument(
        "--hm2-clock", metavar="F", help="Mesa stepgen clock (e.g. 33MHz) for exact rounding"
    )


def read_firmware_args(
    args: argparse.Namespace, path: str, ini: str | None = None
) -> FirmwareConfig:
    j = getattr(args, "latency", None)
    clock = getattr(args, "hm2_clock", None)
    return read_firmware(
        path,
        args.firmware_format,
        latency_ns=time_ns(j) if j else None,
        clock_hz=parse_frequency(clock) if clock else None,
        ini=ini,
    )


def firmware_config(args: argparse.Namespace) -> FirmwareConfig | None:
    """The configuration ``--firmware FILE`` names, read (None without ``--firmware``)."""
    path = getattr(args, "firmware", None)
    return read_firmware_args(args, path) if path else None


def check_firmware(args: argparse.Namespace, cfg: FirmwareConfig, subject: Any) -> FirmwareCheck:
    """``check --firmware`` / ``measure --firmware``: one capture axis (a Report or an
    :class:`~wavecheck.firmware.capture.Observed`) against its axis of ``cfg`` (paired by
    ``--axis``/``--firmware-axis``)."""
    from wavecheck.firmware.capture import Observed, firmware_check
    from wavecheck.firmware.pairing import pair_axis, parse_pairs

    name = subject.axis_name if isinstance(subject, Observed) else subject.axis
    pairing = pair_axis(cfg, name, parse_pairs(getattr(args, "firmware_axis", []) or []),
                        getattr(args, "axis", None))  # fmt: skip
    return firmware_check(subject, cfg, pairing.axis, str(pairing))
