"""Cross-check wavecheck's step decoding against sigrok-cli's decoders.

:mod:`.run` (:func:`crosscheck`, the whole job), :mod:`.sigrok` (sigrok-cli's input, its run and
its output), :mod:`.model` (the result and the comparison). The CLI is
:mod:`wavecheck.cli.crosscheck`.
"""

from wavecheck.crosscheck.comparison import CrosscheckResult
from wavecheck.crosscheck.decoders import crosscheck
from wavecheck.crosscheck.sigrok import pick_downsample

__all__ = ["CrosscheckResult", "crosscheck", "pick_downsample"]
