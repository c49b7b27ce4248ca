"""What a check is asked to do: one frozen options object, built by every entry point.

The CLI (``check``, ``watch``, ``measure``), :func:`wavecheck.check` / :func:`wavecheck.check_axes`,
the pytest plugin, the cocotb monitor and the sigrok decoder each turn their own spelling of the
options into one :class:`CheckOptions`; the engine (:func:`wavecheck.engine.run.check_source`)
takes nothing else. What cannot apply is refused here, the same way for every entry point.

Per-axis values (:data:`PerAxis`) map an axis name to its value; the key ``None`` gives the value
of every axis not named (``--drive gecko-g202 --drive y=leadshine-dm542`` is
``{None: g202, "y": dm542}``).
"""

from __future__ import annotations

from collections.abc import Mapping
from fractions import Fraction
from typing import TYPE_CHECKING, TypeVar

from wavecheck.drives.datasheet import ActiveEdge, Drive
from wavecheck.errors import UsageError
from wavecheck.record import field, record
from wavecheck.rules import RULE_IDS
from wavecheck.steps.mapping import AxisMap
from wavecheck.verdict import check_require

if TYPE_CHECKING:  # the LinuxCNC config is read only when given
    from wavecheck.linuxcnc.stepgen_config import LinuxCNCConfig

__all__ = [
    "DEFAULT_BLOCK_EDGES",
    "DEFAULT_KEEP",
    "INFER_EDGES",
    "CheckOptions",
    "PerAxis",
    "for_axis",
]

T = TypeVar("T")
PerAxis = Mapping[str | None, T]
"""Axis name → value; ``None``: every axis not named."""

#: Edges gathered before a window is checked: ~40 MB of working arrays at the peak.
DEFAULT_BLOCK_EDGES = 1 << 18
#: Violations kept per rule (the worst ones; the counts are exact).
DEFAULT_KEEP = 1000
#: Edges read (over every channel) to tell the roles from the waveforms when none is mapped.
INFER_EDGES = 1 << 22


def for_axis(values: PerAxis[T], axis: str | None) -> T | None:
    """The value of ``axis`` (its own, else the one for every axis), None when neither is given."""
    if axis in values:
        return values[axis]
    return values.get(None)


@record(frozen=True)
class CheckOptions:
    """Everything a check is asked (times exact; drives loaded).

    Attributes:
        drive: the drive of each axis (``{None: drive}`` for one drive); empty: no limit
            (``wavecheck measure``: every interval measured, nothing judged).
        axes: the mapping, one :class:`~wavecheck.steps.mapping.AxisMap` per axis (``--map``); empty:
            channels named after their roles, else the roles told from the waveforms.
        invert: roles to invert, ``AXIS.ROLE`` or a bare role for every axis.
        step_type: LinuxCNC step type 0–15 per axis (default: found with the roles, else the
            drive's, else 0 step/dir or 1 up/down).
        forward_level: the DIR level meaning forward per axis (default 0: DIR high = reverse).
        user_table: the state table of step type 15.
        pulse_level: the level of the generator's pulses at its output (1 high, 0 low); None:
            as the waveform shows it at the drive's input, else high at the output.
        active_edge: override every drive's active edge.
        resolution: T in exact seconds (None: the capture's own).
        limits: ``RULE=T`` figures replacing the drives' (``--limit``).
        margin: ``Nx`` or ``+T`` tightening every figure (``--margin``).
        stepgen: a LinuxCNC stepgen configuration for the ``config``/``latency_safe`` rates.
        latency_ns: the worst base-thread latency J for ``latency_safe`` (exact ns).
        keep_violations: violations kept per rule (the worst; counts are exact).
        block_edges: edges gathered before a window is checked (memory follows it).
        pictures: keep what ``--plot``/``--html``/``--gtkw`` draw (signal windows around the
            worst places, a thinned step trace); off, nothing is kept that no output needs.
        infer_edges: edges read to tell roles from the waveforms when none is mapped.
        require: rule ids (or ``all``: every rule the drive gives a figure for) that must be
            decided: one unchecked or indeterminate makes the run exit 4 (``--require``;
            :mod:`wavecheck.verdict`, judged on the report by :mod:`wavecheck.report.claims`).
    """

    drive: PerAxis[Drive] = field(default_factory=dict)
    axes: tuple[AxisMap, ...] = ()
    invert: tuple[str, ...] = ()
    step_type: PerAxis[int] = field(default_factory=dict)
    forward_level: PerAxis[int] = field(default_factory=dict)
    user_table: tuple[int, ...] | None = None
    pulse_level: int | None = None
    active_edge: ActiveEdge | None = None
    resolution: Fraction | None = None
    limits: tuple[str, ...] = ()
    margin: str | None = None
    stepgen: LinuxCNCConfig | None = None
    latency_ns: Fraction | None = None
    keep_violations: int = DEFAULT_KEEP
    block_edges: int = DEFAULT_BLOCK_EDGES
    pictures: bool = False
    infer_edges: int = INFER_EDGES
    require: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        check_require(self.require, RULE_IDS)
        if self.pulse_level not in (None, 0, 1):
            raise UsageError(f"pulse level must be 0 (low) or 1 (high), got {self.pulse_level!r}")
        for axis, level in self.forward_level.items():
            if level not in (0, 1):
                where = "" if axis is None else f" of axis {axis}"
                raise UsageError(f"DIR forward level{where} must be 0 or 1, got {level!r}")
        if self.active_edge not in (None, "rising", "falling", "both"):
            raise UsageError(f"active edge must be rising, falling or both: {self.active_edge!r}")
        if self.resolution is not None and self.resolution < 0:
            raise UsageError(f"--resolution must not be negative, got {self.resolution} s")
        if self.latency_ns is not None:
            if self.stepgen is None:
                raise UsageError(
                    "--latency needs the stepgen configuration: give --ini/--hal or --base-period"
                )
            if self.latency_ns < 0:
                raise UsageError(f"--latency must not be negative, got {self.latency_ns} ns")
        if self.block_edges < 1:
            raise UsageError(f"--block-edges must be 1 or more, got {self.block_edges}")
        if self.keep_violations < 0:
            raise UsageError(f"violations kept must be 0 or more, got {self.keep_violations}")
        if self.infer_edges < 1:
            raise UsageError(f"edges read for the roles must be 1 or more: {self.infer_edges}")

    @property
    def measure_only(self) -> bool:
        """No drive: every interval measured, nothing judged (``wavecheck measure``)."""
        return not self.drive
