"""Cross-check wavecheck's step decoding against sigrok-cli's ``counter`` and ``stepper_motor``.

Two independent decoders run on the same capture:

- ``counter`` (``data_edge`` = the active edge) counts STEP edges, the final step included;
- ``stepper_motor`` (rising edges only) writes one position line per step *except the last*:
  line k spans [edge k, edge k+1] in samples and shows the position after step k.

Both are compared with :func:`wavecheck.steps.decode.decode` on the same channels:
:mod:`wavecheck.crosscheck.sigrok` prepares sigrok-cli's input and runs it,
:mod:`wavecheck.crosscheck.comparison` compares (and explains sigrok's known differences).
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

from wavecheck.capture.edges import Capture
from wavecheck.capture.sigrokcli import find_sigrok_cli
from wavecheck.crosscheck.comparison import CrosscheckResult, compare
from wavecheck.crosscheck.sigrok import prepare_input, run_decoders
from wavecheck.drives.datasheet import ActiveEdge
from wavecheck.errors import CaptureError, UsageError
from wavecheck.steps.decode import decode as decode_steps
from wavecheck.steps.interface import build_interface

__all__ = ["crosscheck"]


def crosscheck(
    capture: Capture,
    mapping: dict[str, str],
    *,
    active_edge: ActiveEdge = "rising",
    forward_level: int = 0,
    downsample: int | None = None,
    input_format: str | None = None,
    workdir: str | os.PathLike[str] | None = None,
) -> CrosscheckResult:
    """Run sigrok-cli's decoders on ``capture`` and compare with wavecheck's decode.

    Raises:
        UsageError: no ``step`` role, unknown channel, unsupported edge.
        CaptureError: sigrok-cli is missing or fails on the file.
    """
    if "step" not in mapping:
        raise UsageError("crosscheck needs --map step=CHANNEL (and dir=CHANNEL for positions)")
    extra = set(mapping) - {"step", "dir"}
    if extra:
        raise UsageError(
            f"crosscheck compares step/dir only; drop --map {', '.join(sorted(extra))}"
        )
    if find_sigrok_cli() is None:
        raise CaptureError(
            capture.path, None, "crosscheck needs sigrok-cli (apt-get install sigrok-cli)"
        )
    iface = build_interface(capture, mapping)
    step_sig = iface.require("step")
    dir_sig = iface.get("dir")
    names = [step_sig.channel] + ([dir_sig.channel] if dir_sig else [])
    edges = [step_sig.edges] + ([dir_sig.edges] if dir_sig else [])
    # wavecheck's decode: on the active edge (counter), and on rising edges (stepper_motor)
    steps = decode_steps(iface, 0, active_edge=active_edge, forward_level=forward_level)
    rising = steps if active_edge == "rising" else decode_steps(iface, 0, active_edge="rising",
                                                          forward_level=forward_level)  # fmt: skip
    with tempfile.TemporaryDirectory(prefix="wavecheck-xc-", dir=workdir) as tmp:
        sr = prepare_input(
            capture, names, edges, Path(tmp), downsample=downsample, input_format=input_format
        )
        out = run_decoders(
            sr.path,
            sr.channels[0],
            sr.channels[1] if dir_sig else None,
            active_edge,
            capture.path,
            Path(tmp),
        )
    return compare(
        capture.path,
        step_sig,
        dir_sig,
        active_edge=active_edge,
        forward_level=forward_level,
        steps=steps,
        rising=rising,
        sigrok_input=sr,
        sigrok=out,
    )
