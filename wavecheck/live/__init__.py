"""Live checks: a logic analyzer streamed through sigrok-cli into the engine.

:mod:`.sigrok` starts and stops sigrok-cli and reads its raw samples; :mod:`.snippets` keeps the
recent samples and writes a short ``.sr`` around each violation; :mod:`.watch` runs the loop
(samples → :class:`~wavecheck.capture.binary.SampleBlocks` →
:class:`~wavecheck.engine.axis.MachineCheck`) with a status line and the stop conditions.
"""

#: Seconds beyond ``--time`` a watch may take in all (the analyzer's start, the pipe's delay)
#: before it ends short of the samples asked (:mod:`wavecheck.live.watch`).
START_GRACE = 10.0
