"""Development tools run from a source checkout (``python -m tools.story``, ``python -m
tools.golden``); not part of the installed package."""
