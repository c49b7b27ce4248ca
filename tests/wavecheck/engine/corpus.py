"""The captures the streamed-check tests run on: the repository's golden traces with the drive and
step type each is checked against."""

from __future__ import annotations

from pathlib import Path

ROOT = Path(__file__).resolve().parents[3]
GOLDEN = ROOT / "captures" / "golden"
SHARED = ROOT.parent / "shared" / "captures"

#: (file in captures/golden, drive id, step type or None for the default)
GOLDEN_CASES = [
    ("g202-p20-worst-dirhold.vcd", "gecko-g202", None),
    ("g202-p16-dirhold2-worst.vcd", "gecko-g202", None),
    ("stepgen0.vcd", "gecko-g202", None),
    ("a4988-spike.vcd", "a4988", None),
    ("xylotex-dirsetup-zero.vcd", "gecko-g202", None),
    ("updown-uniform.vcd", "gecko-g202", 1),
    ("stepgen1-quadrature.vcd", "gecko-g202", 2),
]
