"""
wavecheck checks every STEP/DIR (or UP/DOWN, or phase) edge against a stepper
drive's datasheet timing: each pulse's high and low time, DIR setup and hold
around the active edge, the step rate, ENABLE setup, with the limits of
wavecheck's drive library ('wavecheck drives') or a rule file. Violations are
annotated where they happen (rule, measured, limit, margin: the words and ids
of 'wavecheck check'); a verdict the sample rate cannot decide is marked
indeterminate. Needs wavecheck itself: install this decoder with
'wavecheck sigrok install'.
"""

from .pd import Decoder

__all__ = ["Decoder"]
