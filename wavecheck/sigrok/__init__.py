"""wavecheck's checks as a libsigrokdecode protocol decoder, for PulseView and sigrok-cli (issue 28).

- :mod:`wavecheck.sigrok.decoder` — the decoder itself (``pd.py``, API version 3), copied where
  libsigrokdecode looks by ``wavecheck sigrok install`` (:mod:`wavecheck.sigrok.install`);
- :mod:`wavecheck.sigrok.adapter` — everything the decoder asks of the engine (drive, rule table,
  limits, the block engine's summary): the one module to re-point when the engine changes;
- :mod:`wavecheck.sigrok.judge` — each interval judged at the edge that decides it (PulseView
  never tells a decoder that the capture has ended), held equal to the engine by the tests;
- :mod:`wavecheck.sigrok.regions` — runs of violations merged into regions a whole-capture view
  shows (issue 36);
- :mod:`wavecheck.sigrok.session` — PulseView session files with the decoder stacked
  (``wavecheck check --pulseview FILE``).
"""
