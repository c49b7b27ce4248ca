"""What the validator knows of LinuxCNC's configuration (its step types 0–15 and their state
tables, the vocabulary of every step interface, are :mod:`wavecheck.steptypes`).

- :mod:`~wavecheck.linuxcnc.timing`: stepgen's n·P − J interval arithmetic;
- :mod:`~wavecheck.linuxcnc.files`: INI files, HAL words, halcmd's ``[SECTION]KEY`` references;
- :mod:`~wavecheck.linuxcnc.stepgen_config`: stepgen's settings from INI/HAL, the config/latency_safe rates;
- :mod:`~wavecheck.linuxcnc.pid_settings`: ``pid``'s settings from INI/HAL.
"""
