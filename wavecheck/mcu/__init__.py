"""Real firmware on a simulated MCU: build it, run it on simavr with exact cycle timing (a separate
GPL-3.0-or-later program, ``wavecheck/mcu/simavr``), and record its pins to a VCD the engine checks.
"""
