"""A side door of the engine: the parts of a report beyond its rules.

:class:`~wavecheck.engine.outcome.Report` (through the front door) carries them: its steps
(:class:`StepCounts`), its thinned step trace (:class:`StepTrace`, which a measurement also feeds
as a step sink) and each rule's interval histogram (:class:`Histogram`, from
``RuleResult.histogram``). Renderers and ``wavecheck measure`` that read them import them here.
"""

from __future__ import annotations

from wavecheck.engine.judge import Histogram
from wavecheck.engine.results import StepCounts
from wavecheck.engine.trace import StepTrace

__all__ = ["Histogram", "StepCounts", "StepTrace"]
