"""The streamed engine: captures of any length checked block by block in bounded memory, with
the whole-capture path's results (:mod:`wavecheck.stream.engine`, the test oracle being
:func:`wavecheck.engine.check_machine`)."""
