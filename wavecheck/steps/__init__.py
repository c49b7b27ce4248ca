"""A capture's STEP/DIR interface, beneath the engine: which channel plays which role, and the
steps and intervals that gives.

:mod:`.mapping` reads the mapping options (``--map x.step=5``, per-axis values) into one
:class:`~wavecheck.steps.mapping.AxisMap` per axis; :mod:`.interface` binds the roles to a
capture's channels (:class:`~wavecheck.steps.interface.StepInterface`); :mod:`.decode` turns the
edges into steps (:class:`~wavecheck.steps.decode.StepEvents`) for every LinuxCNC step type;
:mod:`.primitives` measures the intervals between edges that the rules judge. The engine
(:mod:`wavecheck.engine`) runs them window by window; the commands that need steps without a
verdict (``follow``, ``crosscheck``, ``measure``, the PulseView decoder) use them directly.
"""
