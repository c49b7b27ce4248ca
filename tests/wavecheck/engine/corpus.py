"""The captures the block-size tests run on (the repository's golden traces with the drive and
step type each is checked against), and the engine run they share."""

from __future__ import annotations

from pathlib import Path

from wavecheck.capture.blocks import BlockSource
from wavecheck.engine.options import CheckOptions
from wavecheck.engine.outcome import MachineReport
from wavecheck.engine.run import check_source
from wavecheck.steps.mapping import AxisMap

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


def engine_check(
    source: BlockSource, axes: list[AxisMap], drives: dict, block: int, **kw: object
) -> MachineReport:
    """The engine on ``source``, a window each ``block`` edges, pictures kept; ``kw`` in the old
    engine's words (``step_types``, ``forward_levels``, ``invert`` per axis, ``active_edge``,
    ``pulse_level``, ``user_table``)."""
    invert = kw.get("invert") or {}
    options = CheckOptions(
        drive=drives,
        axes=tuple(axes),
        invert=tuple(
            f"{axis}.{r}" if axis else r
            for axis, roles in invert.items()  # type: ignore[attr-defined]
            for r in roles
        ),
        step_type=kw.get("step_types") or {},  # type: ignore[arg-type]
        forward_level=kw.get("forward_levels") or {},  # type: ignore[arg-type]
        active_edge=kw.get("active_edge"),  # type: ignore[arg-type]
        pulse_level=kw.get("pulse_level", 1),  # type: ignore[arg-type]
        user_table=kw.get("user_table"),  # type: ignore[arg-type]
        block_edges=block,
        pictures=True,
    )
    return check_source(source, options)
