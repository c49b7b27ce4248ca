"""The typed Python API: ``wavecheck.check(capture, drive, ...) -> Report``.

>>> report = wavecheck.check("run.sr", "gecko-g202", map={"step": "5", "dir": "6"})  # doctest: +SKIP
>>> report.verdict, report.rule("dir_hold").min_margin_ns                              # doctest: +SKIP
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Mapping, Sequence
from fractions import Fraction

from wavecheck.capture.model import Capture
from wavecheck.drives.model import ActiveEdge, Drive
from wavecheck.engine import run_check
from wavecheck.report.model import Report
from wavecheck.units import SAMPLE_RATE, parse_frequency, parse_option

__all__ = ["check"]


def check(
    capture: str | os.PathLike[str] | Capture,
    drive: str | os.PathLike[str] | Drive,
    *,
    map: Mapping[str, str] | None = None,  # noqa: A002 - mirrors the CLI's --map
    invert: Iterable[str] = (),
    step_type: int | None = None,
    resolution: str | Fraction | None = None,
    samplerate: str | Fraction | None = None,
    input_format: str | None = None,
    forward_level: int = 0,
    pulse_level: int = 1,
    active_edge: ActiveEdge | None = None,
    user_table: tuple[int, ...] | None = None,
    ini: str | os.PathLike[str] | None = None,
    hal: str | os.PathLike[str] | Sequence[str | os.PathLike[str]] | None = None,
    channel: int = 0,
    latency: str | Fraction | None = None,
) -> Report:
    """Check a capture against a drive and return the :class:`~wavecheck.report.Report`.

    Args:
        capture: a file path (read with :func:`wavecheck.capture.open.open_capture`) or a
            :class:`~wavecheck.capture.model.Capture`.
        drive: a drive id from ``rules/``, a rule file path, or a :class:`Drive`.
        map: role → channel name or index (``{"step": "STEP (Y axis)"}``).
        invert: roles to invert.
        step_type: LinuxCNC step type 0–15 (default: the drive's, else 0).
        resolution: T, a time (``"500ns"``) or exact seconds; default the capture's.
        samplerate: sample rate for a file without one (``"12MHz"`` or exact Hz).
        input_format: force a reader (``"sr"``, ``"vcd"``, a sigrok-cli format).
        forward_level: DIR level that means forward (0 or 1).
        pulse_level: level of the generator's step pulses at its output (1 high, 0 low).
        active_edge: override the drive's active edge.
        user_table: the state table of step type 15.
        ini: a LinuxCNC INI file (BASE_PERIOD) for the ``config`` and ``latency_safe`` rates.
        hal: LinuxCNC HAL file(s) with the stepgen settings.
        channel: the stepgen channel of the HAL files.
        latency: the worst base-thread latency ``J`` (``"11us"`` or exact seconds) for
            ``latency_safe``.

    Raises:
        WavecheckError: unreadable capture or rule file, unknown channel, bad option.
    """
    if not isinstance(capture, Capture):
        from wavecheck.capture.open import open_capture

        rate = None
        if isinstance(samplerate, str):  # text needs its unit (README "Numbers and units")
            rate = parse_option(samplerate, "samplerate", "frequency", SAMPLE_RATE)
        elif samplerate is not None:
            rate = parse_frequency(samplerate, default_unit="Hz")
        capture = open_capture(capture, samplerate=rate, input_format=input_format)
    if not isinstance(drive, Drive):
        from wavecheck.drives.library import load_drive

        drive = load_drive(drive)
    stepgen = None
    if ini is not None or hal is not None:
        from wavecheck.linuxcnc.config import read_config

        hals = [hal] if isinstance(hal, (str, os.PathLike)) else list(hal or [])
        stepgen = read_config(ini, hals, channel)
    j = None
    if latency is not None:
        j = (
            parse_option(latency, "latency", "time") if isinstance(latency, str) else Fraction(latency)
        ) * 10**9
    res: str | Fraction | None = resolution
    if isinstance(resolution, str):
        res = parse_option(resolution, "resolution", "time")
    return run_check(
        capture,
        drive,
        map,
        invert,
        step_type,
        res,
        forward_level=forward_level,
        pulse_level=pulse_level,
        active_edge=active_edge,
        user_table=user_table,
        stepgen=stepgen,
        latency_ns=j,
    )
