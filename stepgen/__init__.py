"""stepgen: a faithful model of LinuxCNC's software step generator, and its timing calculator.

It builds on :mod:`wavecheck` (errors, units, step-type tables, the n·P − J arithmetic); wavecheck
never imports stepgen.
"""

from wavecheck import __version__

__all__ = ["__version__"]
