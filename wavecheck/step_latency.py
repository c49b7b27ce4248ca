"""The base-thread latency of a capture's step channels, for a library caller (``stepgen plan
--latency-from CAPTURE``): the channels mapped as ``check`` maps them (the engine's planning),
their edges read as the invocation lattice of one periodic thread (:mod:`wavecheck.lattice`).
``wavecheck latency`` is the same with its options.
"""

from __future__ import annotations

import os
from typing import TYPE_CHECKING

from wavecheck.capture.edges import Capture
from wavecheck.engine import CheckOptions
from wavecheck.errors import UsageError

if TYPE_CHECKING:
    from wavecheck.lattice import LatencyReport

__all__ = ["latency_of", "step_channels"]


def step_channels(capture: Capture, options: CheckOptions) -> tuple[list[str], dict[str, str]]:
    """Every channel the axes of ``options`` map in ``capture`` (as ``check`` maps them; ENABLE
    left out), and role → channel of the first axis (the roles the worst-case patterns are
    told by).

    Raises:
        UsageError: the axis options do not fit the capture.
    """
    from wavecheck.engine import axes_for
    from wavecheck.engine.planning import plan_axes

    axes, _ = axes_for(options, capture)
    names: list[str] = []
    first: dict[str, str] = {}
    for plan in plan_axes(capture, axes, options, capture):
        roles = {r: s.channel for r, s in plan.interface.signals.items() if r != "enable"}
        names += list(roles.values())
        first = first or roles
    return list(dict.fromkeys(names)), first


def latency_of(path: str | os.PathLike[str]) -> LatencyReport:
    """What ``wavecheck latency PATH`` finds with no options: the channels mapped as ``check``
    maps them, the base period inferred from the edges.

    Raises:
        CaptureError: the file cannot be read.
        UsageError: no step channel found.
    """
    from wavecheck.capture.open import open_capture
    from wavecheck.lattice import analyse

    capture = open_capture(path)
    names, roles = step_channels(capture, CheckOptions(active_edge="rising"))
    if not names:
        raise UsageError(
            f"{capture.path}: no step channel found (channels: "
            f"{', '.join(repr(c.name) for c in capture.channels)})"
        )
    return analyse(capture, names, None, roles)
