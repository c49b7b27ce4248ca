"""`stepgen plan` (placeholder until implemented)."""

from __future__ import annotations

import argparse
from typing import Any

from wavecheck.errors import UsageError


def register(sub: Any) -> None:
    p = sub.add_parser("plan", help="(not yet implemented)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    raise UsageError("stepgen plan is not implemented yet")
