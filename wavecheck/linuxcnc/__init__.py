"""What the validator knows of LinuxCNC.

- :mod:`~wavecheck.linuxcnc.steptypes`: step types 0–15 and their state tables;
- :mod:`~wavecheck.linuxcnc.timing`: stepgen's n·P − J interval arithmetic;
- :mod:`~wavecheck.linuxcnc.config`: INI/HAL files and the ``config``/``latency_safe`` rates.
"""
