"""``wavecheck crosscheck CAPTURE --map step=CH[,dir=CH]``: sigrok-cli's decoders vs wavecheck's.

Exit codes: 0 the step counts and positions agree (after sigrok's known differences, which are
listed), 1 they disagree, 2 unusable input (or sigrok-cli missing / failing).
"""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING, Any

from wavecheck.cli._capture_args import add_capture_arguments, capture_from_args
from wavecheck.cli._formats import Formats, json_text
from wavecheck.errors import UsageError
from wavecheck.output import atomic_write, output_file
from wavecheck.steps.interface import parse_map
from wavecheck.verdict import EXIT_FAIL, EXIT_PASS

if TYPE_CHECKING:  # imported by run(): the sigrok-cli layer only when used
    from wavecheck.crosscheck import CrosscheckResult

__all__ = ["register", "run"]


def register(sub: Any) -> None:
    p = sub.add_parser(
        "crosscheck",
        description=(
            "Run sigrok-cli's counter and stepper_motor decoders on CAPTURE and compare step "
            "counts, step samples and positions with wavecheck's decode, accounting for sigrok's "
            "known differences (N-1 position lines, DIR read at the step sample, DIR high = +, "
            "rising edges only). Exit 0 agree, 1 disagree, 2 unusable."
        ),
    )
    p.add_argument(
        "capture", metavar="CAPTURE", help="the capture (.sr, .vcd, or a sigrok-cli format)"
    )
    p.add_argument(
        "--map", action="append", default=[], metavar="ROLE=CH",
        help="step=CH[,dir=CH]: channels by name or index (repeatable)",
    )  # fmt: skip
    p.add_argument(
        "--active-edge", choices=("rising", "falling"), default="rising",
        help="STEP edge that counts as a step (default rising, as stepper_motor counts)",
    )  # fmt: skip
    p.add_argument(
        "--dir-forward", choices=("low", "high"), default="low",
        help="DIR level wavecheck takes as forward (default low); sigrok's is always high",
    )  # fmt: skip
    p.add_argument(
        "--downsample", type=int, metavar="N",
        help="VCD only: ticks per sigrok sample (default: the shortest gap between STEP/DIR edges)",
    )  # fmt: skip
    FORMATS.add_argument(p)
    p.add_argument(  # output_file: checked before any work (wavecheck.output)
        "-o", "--output", type=output_file, metavar="FILE", help="write the result to FILE"
    )
    add_capture_arguments(p)
    p.set_defaults(func=run)


def _text(r: CrosscheckResult) -> str:
    lines = [
        f"crosscheck: {'AGREE' if r.agree else 'DISAGREE'}",
        f"capture:    {r.path} (sigrok-cli read {r.sigrok_input})",
        f"channels:   step={r.step_channel!r}"
        + (f", dir={r.dir_channel!r}" if r.dir_channel else ""),
        f"steps:      wavecheck {r.wavecheck_steps}, sigrok counter {r.sigrok_count} "
        f"({r.active_edge} edges)",
    ]
    if r.dir_channel is not None:
        lines.append(
            f"positions:  sigrok stepper_motor {r.sigrok_position_lines} lines for "
            f"{r.rising_steps} rising-edge steps; last shown {r.sigrok_last_position}, "
            f"expected {r.expected_last_position}; final (DIR high = +) {r.final_sigrok_polarity}"
        )
        lines.append(f"final position (wavecheck's polarity): {r.wavecheck_final_position}")
    lines += [f"disagree:   {d}" for d in r.disagreements]
    lines += [f"note:       {e}" for e in r.explanations]
    return "\n".join(lines) + "\n"


def _doc(r: CrosscheckResult) -> dict[str, Any]:
    keys = (
        "path", "step_channel", "dir_channel", "active_edge", "sigrok_input", "downsample",
        "wavecheck_steps", "sigrok_count", "rising_steps", "sigrok_position_lines",
        "sigrok_last_position", "expected_last_position", "wavecheck_final_position",
        "final_sigrok_polarity", "ambiguous", "disagreements", "explanations",
    )  # fmt: skip
    doc = {k: getattr(r, k) for k in keys}
    doc["agree"] = r.agree
    return doc


#: ``--format``: text or JSON.
FORMATS = Formats({"text": _text, "json": json_text(_doc)})


def run(args: argparse.Namespace) -> int:
    from wavecheck.crosscheck import crosscheck

    if args.downsample is not None and args.downsample < 1:
        raise UsageError(f"--downsample must be >= 1, got {args.downsample}")
    mapping = parse_map(args.map)
    capture = capture_from_args(args, args.capture)
    result = crosscheck(
        capture,
        mapping,
        active_edge=args.active_edge,
        forward_level=1 if args.dir_forward == "high" else 0,
        downsample=args.downsample,
        input_format=args.input_format,
    )
    text = FORMATS.render(args.format, result)
    if args.output:
        atomic_write(args.output, text)
    else:
        print(text, end="")
    return EXIT_PASS if result.agree else EXIT_FAIL
