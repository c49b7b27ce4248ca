"""Open any capture: pick the reader from ``--input-format``, the file's content, or its extension.

``.sr`` and VCD are read natively; every other format sigrok-cli knows (csv, binary,
chronovu-la8, logicport, …) is converted by sigrok-cli to a temporary ``.sr`` first.
"""

from __future__ import annotations

import os
from fractions import Fraction
from pathlib import Path

from wavecheck.capture.model import Capture
from wavecheck.errors import CaptureError, UsageError

__all__ = ["detect_format", "open_capture"]

_ALIASES = {"srzip": "sr", "sigrok": "sr"}
_BY_EXTENSION = {
    ".sr": "sr",
    ".vcd": "vcd",
    ".csv": "csv",
    ".kdt": "chronovu-la8",
    ".lpf": "logicport",
}
_ZIP_MAGIC = b"PK\x03\x04"


def detect_format(path: str | os.PathLike[str]) -> str:
    """The input format of ``path``: ``"sr"``, ``"vcd"`` or a sigrok-cli input format name.

    Raises:
        CaptureError: missing file, a folder, an empty file, or a format that cannot be told.
    """
    p = Path(path)
    if not p.exists():
        raise CaptureError(path, None, "no such file")
    if p.is_dir():
        raise CaptureError(path, None, "is a folder, not a capture file")
    try:
        with open(p, "rb") as f:
            head = f.read(4096)
    except OSError as err:
        raise CaptureError(path, None, f"cannot open: {err.strerror or err}") from None
    if not head.strip():
        raise CaptureError(path, None, "the file is empty")
    ext = p.suffix.lower()
    if head.startswith(_ZIP_MAGIC):
        return "sr"
    if head.lstrip().startswith(b"$"):
        return "vcd"
    if ext in ("", ".sr", ".vcd") or ext not in _BY_EXTENSION:
        kind = {".sr": "a sigrok .sr (zip) file", ".vcd": "a VCD file"}.get(ext)
        what = f"is not {kind}" if kind else "has a format that cannot be told from its content"
        raise CaptureError(
            path,
            None,
            f"{what} (give --input-format: sr, vcd, or a sigrok-cli format such as csv, "
            "binary, chronovu-la8, logicport)",
        )
    return _BY_EXTENSION[ext]


def open_capture(
    path: str | os.PathLike[str],
    *,
    samplerate: Fraction | None = None,
    resolution_s: Fraction | None = None,
    input_format: str | None = None,
    require_time: bool = True,
) -> Capture:
    """Read a capture file into a :class:`Capture`.

    Args:
        path: the capture.
        samplerate: sample rate in Hz, for files that lack one (a ``.sr`` without it, raw
            binary, csv) or to state a VCD's sampling; overrides the file's value with a note.
        resolution_s: the resolution (sample period) in seconds, overriding the derived one.
        input_format: ``"sr"``, ``"vcd"`` or a sigrok-cli input format (may carry options,
            ``"binary:numchannels=4"``); default: detected from content and extension. A VCD
            with options (``"vcd:downsample=10"``) is read through sigrok-cli, which has them.
        require_time: with False, a file that states no sample rate is read anyway, untimed
            (:attr:`Capture.time_known` False: counts in samples; for ``wavecheck info``).

    Raises:
        CaptureError: the file cannot be read (the message names the file and the place).
    """
    if samplerate is not None and samplerate <= 0:
        raise UsageError(f"--samplerate must be positive, got {samplerate} Hz")
    if resolution_s is not None and resolution_s < 0:
        raise UsageError(f"--resolution must not be negative, got {resolution_s} s")
    fmt = input_format.strip() if input_format else detect_format(path)
    name = _ALIASES.get(fmt.split(":", 1)[0].lower(), fmt.split(":", 1)[0].lower())
    if input_format:
        detect_path_exists(path)
    options = ":" in fmt
    if name == "sr" and options:
        raise UsageError(f"--input-format {fmt!r}: sr takes no options (give --input-format sr)")
    if name == "sr":
        from wavecheck.capture.sr import read_sr

        return read_sr(
            path, samplerate=samplerate, resolution_s=resolution_s, require_rate=require_time
        )
    if name == "vcd" and not options:  # with options: sigrok-cli's VCD input (below)
        from wavecheck.capture.vcd import read_vcd

        return read_vcd(path, samplerate=samplerate, resolution_s=resolution_s)
    from wavecheck.capture.sigrokcli import read_with_sigrok

    return read_with_sigrok(
        path, fmt, samplerate=samplerate, resolution_s=resolution_s, require_time=require_time
    )


def detect_path_exists(path: str | os.PathLike[str]) -> None:
    """Raise :class:`CaptureError` unless ``path`` is an existing, non-empty regular file."""
    p = Path(path)
    if not p.exists():
        raise CaptureError(path, None, "no such file")
    if p.is_dir():
        raise CaptureError(path, None, "is a folder, not a capture file")
    if p.stat().st_size == 0:
        raise CaptureError(path, None, "the file is empty")
