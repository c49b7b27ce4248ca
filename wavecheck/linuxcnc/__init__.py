"""What the validator knows of LinuxCNC's configuration (its step types 0–15 and their state
tables, the vocabulary of every step interface, are :mod:`wavecheck.steptypes`).

- :mod:`~wavecheck.linuxcnc.timing`: stepgen's n·P − J interval arithmetic;
- :mod:`~wavecheck.linuxcnc.files`: INI files, HAL words, halcmd's ``[SECTION]KEY`` references;
- :mod:`~wavecheck.linuxcnc.configuration`: a whole configuration as the ``linuxcnc`` script reads
  it (the INI, its HAL files, HAL library, a HAL file given alone) and what its commands say;
- :mod:`~wavecheck.linuxcnc.parport`: what a parallel-port pin (invert, reset) does to a stepgen output;
- :mod:`~wavecheck.linuxcnc.stepgen_config`: stepgen's settings from INI/HAL, the config/latency_safe rates;
- :mod:`~wavecheck.linuxcnc.pid_settings`: ``pid``'s settings from INI/HAL;
- :mod:`~wavecheck.linuxcnc.worstcase`: the edge that ends each rule's interval (worst-case latency).

The firmware-family readers built on them (:class:`~wavecheck.firmware.guarantee.GeneratorGuarantee`
per step generator) are :mod:`wavecheck.firmware.linuxcnc` (the family), with the software
stepgen in :mod:`wavecheck.firmware.linuxcnc_stepgen` and Mesa's in :mod:`wavecheck.firmware.hm2`.
"""
