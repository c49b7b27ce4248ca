"""stepgen: a faithful model of LinuxCNC's software step generator, and its timing calculator."""

# wavecheck's package imports stepgen.steptypes (the shared step tables); importing wavecheck
# first makes the order the same whichever package a program imports first.
import wavecheck as _wavecheck  # noqa: F401
