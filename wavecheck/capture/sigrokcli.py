"""Other capture formats through ``sigrok-cli``, and sigrok-cli as an independent cross-check.

sigrok-cli is always run with an argument list (never a shell string). Its exit status is not
trusted (``../shared/reference/sigrok.md`` §7: truncated, empty or junk input and wrong channel
names all return 0): stderr is searched for failure patterns, the output file must exist, and
``--show`` must report a non-zero sample count. Failures become :class:`CaptureError`.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import tempfile
from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path

from wavecheck.capture.model import Capture
from wavecheck.errors import CaptureError

__all__ = [
    "SAMPLERATE_OPTION_FORMATS",
    "SigrokShow",
    "convert",
    "find_sigrok_cli",
    "read_with_sigrok",
    "run_sigrok",
    "show",
]

FAILURE_PATTERNS = (
    "Error",
    "error",
    "Failed",
    "failed",
    "Cannot",
    "cannot",
    "Unknown",
    "unknown",
    "Invalid",
    "No channel with name",
    "Required channel",
    "srd:",
    "Traceback",
    "unprocessed bytes",
    "not a multiple of the unit size",
    "Parsing timescale failed",
    "superfluous",
)
_TIMEOUT_S = 3600.0
#: sigrok-cli input formats that take a ``samplerate`` option (the others carry their own rate).
SAMPLERATE_OPTION_FORMATS = ("binary", "csv", "trace32_ad", "raw_analog")


def find_sigrok_cli() -> str | None:
    """Path of the sigrok-cli executable, or None when it is not installed."""
    return shutil.which("sigrok-cli")


def run_sigrok(
    args: list[str],
    *,
    path: str | os.PathLike[str],
    timeout: float = _TIMEOUT_S,
    harmless: tuple[str, ...] = (),
) -> subprocess.CompletedProcess[str]:
    """Run ``sigrok-cli *args``; any failure (status, stderr pattern) is a CaptureError on ``path``.

    Stderr lines containing one of ``harmless`` are not failures.
    """
    exe = find_sigrok_cli()
    if exe is None:
        raise CaptureError(
            path,
            None,
            "needs sigrok-cli to be read, and it is not installed (apt-get install sigrok-cli)",
        )
    try:
        proc = subprocess.run(
            [exe, *args],
            capture_output=True,
            text=True,
            errors="replace",
            timeout=timeout,
            check=False,
        )
    except subprocess.TimeoutExpired:
        raise CaptureError(path, "sigrok-cli", f"did not finish within {timeout:g} s") from None
    except OSError as err:
        raise CaptureError(path, "sigrok-cli", f"cannot be run: {err}") from None
    lines = [
        ln.strip()
        for ln in proc.stderr.splitlines()
        if ln.strip() and not any(h in ln for h in harmless)
    ]
    bad = [ln for ln in lines if any(p in ln for p in FAILURE_PATTERNS)]
    if proc.returncode != 0 or bad:
        detail = (bad or lines or [f"exit status {proc.returncode}"])[0]
        raise CaptureError(path, "sigrok-cli", f"failed: {detail[:200]}")
    return proc


@dataclass
class SigrokShow:
    """What ``sigrok-cli -i FILE --show`` reports."""

    samplerate: int | None
    channels: list[str]
    unitsize: int | None
    sample_count: int | None


def show(path: str | os.PathLike[str], input_format: str | None = None) -> SigrokShow:
    """Run ``--show`` on ``path`` (a cheap validity check) and parse its report."""
    args = ["-I", input_format] if input_format else []
    # a file without a sample rate makes sigrok-cli complain; --show still reports the rest
    out = run_sigrok(
        [*args, "-i", str(path), "--show"], path=path, harmless=("Cannot set 'samplerate' to 0",)
    ).stdout
    rate = re.search(r"^Samplerate:\s*(\d+)", out, re.M)
    unit = re.search(r"^Logic unitsize:\s*(\d+)", out, re.M)
    count = re.search(r"^Logic sample count:\s*(\d+)", out, re.M)
    chans = re.findall(r"^- (.*): logic$", out, re.M)
    return SigrokShow(
        int(rate.group(1)) if rate else None,
        chans,
        int(unit.group(1)) if unit else None,
        int(count.group(1)) if count else None,
    )


def convert(
    src: str | os.PathLike[str],
    dst: str | os.PathLike[str],
    *,
    input_format: str | None = None,
    output_format: str = "srzip",
) -> Path:
    """Convert ``src`` to ``dst`` with sigrok-cli (``-I input_format -O output_format``).

    Raises:
        CaptureError: sigrok-cli failed, or wrote no output.
    """
    args = ["-I", input_format] if input_format else []
    args += ["-i", str(src), "-O", output_format, "-o", str(dst)]
    run_sigrok(args, path=src)
    out = Path(dst)
    if not out.exists() or out.stat().st_size == 0:
        raise CaptureError(
            src,
            "sigrok-cli",
            "produced no output (the file is empty, cut off or not in this format)",
        )
    return out


def read_with_sigrok(
    path: str | os.PathLike[str],
    input_format: str,
    *,
    samplerate: Fraction | None = None,
    resolution_s: Fraction | None = None,
) -> Capture:
    """Read ``path`` in any sigrok-cli input format: convert to a temporary ``.sr``, read that.

    Args:
        input_format: sigrok-cli ``-I`` value, with options if needed (``"binary:numchannels=4"``).
        samplerate: passed to formats that take a ``samplerate`` option, and to the ``.sr`` reader.
    """
    from wavecheck.capture.sr import read_sr

    name = input_format.split(":", 1)[0]
    spec = input_format
    if (
        samplerate is not None
        and name in SAMPLERATE_OPTION_FORMATS
        and "samplerate=" not in input_format
    ):
        if samplerate.denominator != 1:
            raise CaptureError(
                path, None, f"sigrok-cli takes whole-hertz sample rates, not {samplerate} Hz"
            )
        spec = f"{input_format}:samplerate={int(samplerate)}"
    with tempfile.TemporaryDirectory(prefix="wavecheck-") as tmp:
        out = convert(path, Path(tmp) / "converted.sr", input_format=spec)
        try:
            info = show(out)
        except CaptureError as err:
            raise CaptureError(path, err.where, err.msg) from None
        if not info.sample_count:
            raise CaptureError(
                path,
                "sigrok-cli",
                f"read 0 samples as {name!r} (empty, cut off or another format?)",
            )
        rate = samplerate
        if rate is None and not info.samplerate:
            raise CaptureError(
                path,
                None,
                f"the {name} data states no sample rate (give it, e.g. --samplerate 1MHz)",
            )
        try:
            cap = read_sr(out, samplerate=rate, resolution_s=resolution_s)
        except CaptureError as err:
            raise CaptureError(path, err.where, err.msg) from None
    if cap.end != info.sample_count:
        raise CaptureError(
            path,
            "sigrok-cli",
            f"sample count mismatch: --show says {info.sample_count}, read {cap.end}",
        )
    cap.path = str(path)
    cap.format = f"sigrok:{name}"
    cap.notes.insert(0, f"converted from {name} by sigrok-cli")
    return cap
