"""The one engine: edge blocks in, per-axis results out.

A capture (a file read block by block, a pipe, a live device, a simulation, a capture already in
memory) is a :class:`~wavecheck.capture.blocks.BlockSource`; the engine resolves each axis against
the source's skeleton (:mod:`.plan`), decodes the steps (:mod:`.decode`), measures every rule's
intervals (:mod:`.intervals`, :mod:`.primitives`), judges them (:mod:`.verdicts`) and merges them
window by window into one result per rule (:mod:`.results`), in memory that follows a window, not
the capture (:mod:`.axis`).
"""
