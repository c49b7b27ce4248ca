"""`wavecheck compare` (placeholder until implemented)."""

from __future__ import annotations

import argparse
from typing import Any

from wavecheck.errors import UsageError


def register(sub: Any) -> None:
    p = sub.add_parser("compare", help="(not yet implemented)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    raise UsageError("wavecheck compare is not implemented yet")
