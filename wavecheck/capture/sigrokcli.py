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
from typing import BinaryIO

from wavecheck.capture.common import path_argument
from wavecheck.capture.edges import Capture
from wavecheck.errors import CaptureError, UnitError
from wavecheck.units import parse_frequency

__all__ = [
    "SAMPLERATE_OPTION_FORMATS",
    "CsvScan",
    "SigrokShow",
    "convert",
    "find_sigrok_cli",
    "read_with_sigrok",
    "run_sigrok",
    "scan_csv",
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
#: sigrok-cli options whose value is a file.
_FILE_OPTIONS = ("-i", "--input-file", "-o", "--output-file")
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
    stdout: BinaryIO | None = None,
) -> subprocess.CompletedProcess[str]:
    """Run ``sigrok-cli *args``; any failure (status, stderr pattern) is a CaptureError on ``path``.

    Stderr lines containing one of ``harmless`` are not failures. With ``stdout`` (a file open
    for writing), the output goes there instead of into the result (large outputs).
    """
    exe = find_sigrok_cli()
    if exe is None:
        raise CaptureError(
            path,
            None,
            "needs sigrok-cli to be read, and it is not installed (apt-get install sigrok-cli)",
        )
    # a file named like an option ("-fother.sr") is made a path ("./-fother.sr")
    args = [
        path_argument(a) if k and args[k - 1] in _FILE_OPTIONS else a for k, a in enumerate(args)
    ]
    try:
        proc = subprocess.run(
            [exe, *args],
            stdout=subprocess.PIPE if stdout is None else stdout,
            stderr=subprocess.PIPE,
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


_SCAN_BLOCK = 1 << 20
_MAX_COMMENTS = 64
_CSV_RATE_RE = re.compile(r"^;\s*Samplerate:\s*(.+?)\s*$")
_CSV_CHANNELS_RE = re.compile(r"^;\s*Channels \((\d+)/(\d+)\):\s*(.*?)\s*$")
#: csv options that do not change which lines are rows of samples
_CSV_PLAIN_OPTIONS = {"samplerate", "header"}


@dataclass
class CsvScan:
    """What a CSV file holds, read independently of sigrok-cli (to check its conversion).

    Attributes:
        nul_at: byte offset of the first NUL byte (sigrok-cli silently stops there), or None.
        rows: lines with text once ``;`` comments and blanks are removed (header included).
        first: the first such line (the header, or the first row of samples).
        samplerate: the ``; Samplerate: 12 MHz`` comment that sigrok-cli writes, as text.
        channels: the names in its ``; Channels (8/8): a, b, …`` comment.
    """

    nul_at: int | None
    rows: int
    first: str | None
    samplerate: str | None
    channels: list[str] | None


def scan_csv(path: str | os.PathLike[str]) -> CsvScan:
    """Count the rows of a CSV and read sigrok-cli's leading comments, in blocks (memory is one
    block plus one line cut to a block; time linear in the file). Scanning stops at a NUL byte.

    Raises:
        CaptureError: the file cannot be opened.
    """
    rows = 0
    first: str | None = None
    comments: list[str] = []
    nul_at: int | None = None
    carry = b""
    offset = 0

    def line(raw: bytes) -> None:
        nonlocal rows, first
        text = raw.split(b";", 1)[0].strip()
        if text:
            rows += 1
            if first is None:
                first = text[:200].decode("latin-1")
        elif rows == 0 and len(comments) < _MAX_COMMENTS and raw.lstrip().startswith(b";"):
            comments.append(raw[:4096].decode("utf-8", "replace").strip())

    try:
        with open(path, "rb") as f:
            while block := f.read(_SCAN_BLOCK):
                z = block.find(b"\0")
                if z >= 0:
                    nul_at, block = offset + z, block[:z]
                # "\r", "\n" and "\r\n" all end a line (the blank lines between are skipped)
                lines = (carry + block).replace(b"\r", b"\n").split(b"\n")
                carry = lines.pop()[:_SCAN_BLOCK]
                for raw in lines:
                    line(raw)
                offset += len(block)
                if nul_at is not None:
                    break
    except OSError as err:
        raise CaptureError(path, None, f"cannot open: {err.strerror or err}") from None
    if carry:
        line(carry)
    rate: str | None = None
    names: list[str] | None = None
    for text in comments:
        if (m := _CSV_RATE_RE.match(text)) and rate is None:
            rate = m.group(1)
        if (m := _CSV_CHANNELS_RE.match(text)) and names is None:
            listed = m.group(3).split(", ") if m.group(3) else []
            if len(listed) == int(m.group(1)):
                names = listed
    return CsvScan(nul_at, rows, first, rate, names)


def _options(spec: str) -> dict[str, str]:
    """``"csv:header=false:samplerate=5"`` → ``{"header": "false", "samplerate": "5"}``."""
    out: dict[str, str] = {}
    for part in spec.split(":")[1:]:
        key, _, value = part.partition("=")
        out[key.strip()] = value.strip()
    return out


def _looks_like_samples(text: str) -> bool:
    """A CSV line of 0/1 fields only (so not a header of channel names)."""
    return all(f.strip() in ("0", "1") for f in text.split(","))


def read_with_sigrok(
    path: str | os.PathLike[str],
    input_format: str,
    *,
    samplerate: Fraction | None = None,
    resolution_s: Fraction | None = None,
    require_time: bool = True,
) -> Capture:
    """Read ``path`` in any sigrok-cli input format: convert to a temporary ``.sr``, read that.

    A CSV is also read here, independently: a NUL byte (where sigrok-cli silently stops) is
    refused, the samples sigrok-cli produced must equal the file's rows (less the header line),
    and the ``; Samplerate:`` and ``; Channels (n/m):`` comments that sigrok-cli writes give the
    sample rate (unless one is given) and the channel names (its header row says ``logic``).

    Args:
        input_format: sigrok-cli ``-I`` value, with options if needed (``"binary:numchannels=4"``).
        samplerate: passed to formats that take a ``samplerate`` option, and to the ``.sr`` reader.
        require_time: with False, data without a sample rate is read untimed (counts only).
    """
    from wavecheck.capture.sr import read_sr

    name = input_format.split(":", 1)[0]
    spec = input_format
    notes: list[str] = []
    csv = scan_csv(path) if name == "csv" else None
    if csv is not None and csv.nul_at is not None:
        raise CaptureError(
            path,
            f"byte {csv.nul_at}",
            "is a NUL byte: sigrok-cli silently stops reading a CSV there, so the rest would be "
            "lost (a damaged or padded file?)",
        )
    if (
        csv is not None
        and samplerate is None
        and csv.samplerate is not None
        and "samplerate=" not in input_format
    ):
        try:
            stated = parse_frequency(csv.samplerate)
        except UnitError:
            stated = None
        if stated is not None and stated > 0 and stated.denominator == 1:
            samplerate = stated
            notes.append(f"sample rate {csv.samplerate} from the file's '; Samplerate' comment")
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
        if rate is None and not info.samplerate and require_time:
            raise CaptureError(
                path,
                None,
                f"the {name} data states no sample rate (give it, e.g. --samplerate 1MHz)",
            )
        try:
            cap = read_sr(
                out, samplerate=rate, resolution_s=resolution_s, require_rate=require_time
            )
        except CaptureError as err:
            raise CaptureError(path, err.where, err.msg) from None
    if cap.end != info.sample_count:
        raise CaptureError(
            path,
            "sigrok-cli",
            f"sample count mismatch: --show says {info.sample_count}, read {cap.end}",
        )
    if csv is not None:
        _check_csv(path, spec, csv, cap, notes)
    cap.path = str(path)
    cap.format = f"sigrok:{name}"
    cap.notes[:0] = [f"converted from {name} by sigrok-cli", *notes]
    return cap


def _check_csv(
    path: str | os.PathLike[str], spec: str, csv: CsvScan, cap: Capture, notes: list[str]
) -> None:
    """The conversion of a plain CSV is complete, and sigrok-cli's channel names are used.

    Raises:
        CaptureError: sigrok-cli produced fewer (or more) samples than the file has rows.
    """
    opts = _options(spec)
    header = opts.get("header", "true").lower() not in ("false", "0", "no", "off")
    if set(opts) - _CSV_PLAIN_OPTIONS:
        notes.append(
            "rows not counted against the samples (csv options other than samplerate/header)"
        )
    else:
        if header and csv.first is not None and _looks_like_samples(csv.first):
            raise CaptureError(
                path,
                None,
                f"its first line {csv.first[:40]!r} is a row of samples, but sigrok-cli takes it "
                "as channel names and drops it (give --input-format csv:header=false)",
            )
        expected = csv.rows - (1 if header and csv.rows else 0)
        if cap.end != expected:
            raise CaptureError(
                path,
                "sigrok-cli",
                f"converted {cap.end} samples, but the file has {expected} rows of samples: the "
                "conversion is incomplete (a malformed line?), so the capture is refused",
            )
    header_names = [f.strip() for f in (csv.first or "").split(",")] if header else []
    if (
        csv.channels is not None
        and len(csv.channels) == len(cap.channels)
        and (not header_names or len(set(header_names)) == 1)
    ):
        for ch, new in zip(cap.channels, csv.channels, strict=True):
            ch.name = new
        notes.append("channel names from the file's '; Channels' comment")
