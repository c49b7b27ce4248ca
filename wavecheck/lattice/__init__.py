"""Base-thread latency read from the wire: the invocation lattice of a periodic thread.

:mod:`.analysis` (the report and its entry points, :func:`analyse`, :func:`analyse_times`,
:func:`common_period`), :mod:`.period` (finding P) and :mod:`.reading` (where lateness 0 lies).
"""

from wavecheck.lattice.analysis import (
    ESTABLISH_EDGES,
    MAX_PERIOD_NS,
    MIN_EDGES,
    MIN_PERIOD_NS,
    WINDOW_EDGES,
    Candidate,
    CatchUp,
    EdgeKinds,
    LatencyReport,
    LatticeFit,
    Reading,
    Spike,
    analyse,
    analyse_times,
    common_period,
    simplest_between,
)

__all__ = [
    "ESTABLISH_EDGES",
    "MAX_PERIOD_NS",
    "MIN_EDGES",
    "MIN_PERIOD_NS",
    "WINDOW_EDGES",
    "Candidate",
    "CatchUp",
    "EdgeKinds",
    "LatencyReport",
    "LatticeFit",
    "Reading",
    "Spike",
    "analyse",
    "analyse_times",
    "common_period",
    "simplest_between",
]
