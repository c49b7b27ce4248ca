"""The firmware tests' guard against a hang (:func:`tests.bounds.bounded`): the reading itself
must be bounded by its input (issue 27), which the tests check by work counted or memory, not by
seconds (issue 37)."""

from __future__ import annotations

from tests.bounds import bounded

__all__ = ["bounded"]
