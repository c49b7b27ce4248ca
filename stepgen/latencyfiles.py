"""Readers for latency measurements: cyclictest, latency-histogram, ``~/.latency``.

* :func:`read_latency_file` — the single worst figure (ns) from any of: LinuxCNC's one-number
  ``~/.latency`` file (ns, written by ``latency-test``), a cyclictest summary (``T: … Max: N``,
  µs unless ``-N`` was used), a cyclictest ``-h`` histogram (its ``# Max Latencies`` footer, else
  the highest non-empty bin), or ``latency-histogram --nox`` output (base thread
  max(|min|, max)).
* :func:`read_histogram` — a distribution to draw latencies from (``histogram:FILE`` model):
  cyclictest ``-h`` bins, or, for ``latency-histogram --nox`` (which prints no bins, only
  min/max/sdev), a half-normal with that sdev capped at the worst value.

Every problem is a :class:`~wavecheck.errors.ConfigError` naming the file and the line.

Files are read with a bound (:func:`read_text`): at most :data:`MAX_LATENCY_FILE_BYTES` (64 MiB)
and only from something that ends. No real output comes near the cap: a cyclictest ``-h``
histogram is one line of about 7 bytes per thread per 1-µs bin, so even 10,000 bins (10 ms, ten
times the latency at which LinuxCNC is unusable) for 128 threads is about 9 MB; a cyclictest
summary and ``~/.latency`` are a few lines; ``latency-histogram --nox`` writes one ~60-byte line
per thread per update, so 64 MiB is over a million updates. Character and block devices
(``/dev/zero``, ``/dev/urandom``) never end and are refused before any byte is read; a regular
file over the cap is refused from its size; a pipe is read up to the cap.
"""

from __future__ import annotations

import os
import re
import stat
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from wavecheck.errors import ConfigError, UnitError
from wavecheck.units import finite_float, parse_int

__all__ = [
    "MAX_LATENCY_FILE_BYTES",
    "LatencyHistogram",
    "check_latency_path",
    "read_histogram",
    "read_latency_file",
    "read_text",
]

#: Suffixes of logic-analyzer captures (read by ``stepgen plan --latency-from``).
CAPTURE_SUFFIXES = (".sr", ".vcd")

#: The most bytes a latency file may hold (see the module docstring for why 64 MiB).
MAX_LATENCY_FILE_BYTES = 64 << 20
_CAP_TEXT = "64 MiB"

_NOX = re.compile(
    r"^\s*(\d+)\s+s\s+(\S+)\s+min:\s*(-?[\d.]+)\s*us\s+max:\s*(-?[\d.]+)\s*us\s+sdev:\s*(-?[\d.]+)\s*us"
)
_CT_SUMMARY = re.compile(r"^\s*T:\s*(\d+).*?\bMax:\s*(-?\d+)")
_HIST_ROW = re.compile(r"^(\d+)((?:\s+\d+)+)\s*$")


@dataclass(frozen=True)
class LatencyHistogram:
    """A latency distribution: values in ns with weights, or a half-normal (sigma, cap)."""

    values_ns: np.ndarray
    weights: np.ndarray
    description: str
    half_normal: tuple[int, int] | None = None  # (sigma_ns, max_ns) for latency-histogram --nox


def _kind(mode: int) -> str | None:
    """What a non-regular file is, in words (None for a regular file)."""
    for test, words in (
        (stat.S_ISREG, None),
        (stat.S_ISDIR, "a directory"),
        (stat.S_ISCHR, "a character device"),
        (stat.S_ISBLK, "a block device"),
        (stat.S_ISFIFO, "a pipe"),
        (stat.S_ISSOCK, "a socket"),
    ):
        if test(mode):
            return words
    return "not a regular file"


def _refuse_mode(path: str | Path, mode: int) -> None:
    kind = _kind(mode)
    if kind in ("a directory", "a character device", "a block device"):
        what = "is a directory" if kind == "a directory" else f"is {kind}, which never ends"
        raise ConfigError(
            f"{path}: {what}; give a latency file (cyclictest or latency-histogram --nox output "
            "saved to a file, or ~/.latency)"
        )


def check_latency_path(path: str | Path) -> None:
    """Refuse a latency path that does not exist or cannot be read to its end (one line).

    Raises:
        ConfigError: missing, a directory, a character or block device.
    """
    try:
        st = os.stat(Path(path).expanduser())
    except OSError as err:
        if isinstance(err, FileNotFoundError):
            raise ConfigError(
                f"{path}: not found (cyclictest -h or latency-histogram --nox output)"
            ) from None
        raise ConfigError(f"{path}: cannot read latency file ({err.strerror})") from None
    _refuse_mode(path, st.st_mode)


def read_text(path: str | Path) -> str:
    """A latency file's text, read with a bound (see the module docstring).

    Raises:
        ConfigError: missing or unreadable, a device that never ends, a directory, or more than
            ``MAX_LATENCY_FILE_BYTES`` — one line naming the file.
    """
    too_big = (
        f"{path}: more than {_CAP_TEXT}, far beyond any cyclictest, latency-histogram or "
        "~/.latency output; give the tool's output (e.g. cyclictest -q -h 400 > FILE)"
    )
    check_latency_path(path)  # a device is refused before it is opened
    try:
        with open(Path(path).expanduser(), "rb") as fh:
            st = os.fstat(fh.fileno())
            _refuse_mode(path, st.st_mode)
            if stat.S_ISREG(st.st_mode) and st.st_size > MAX_LATENCY_FILE_BYTES:
                raise ConfigError(too_big)
            data = fh.read(MAX_LATENCY_FILE_BYTES + 1)
    except OSError as err:
        raise ConfigError(f"{path}: cannot read latency file ({err.strerror})") from None
    if len(data) > MAX_LATENCY_FILE_BYTES:
        raise ConfigError(too_big)
    return data.decode("utf-8", errors="replace")


_read = read_text

#: The largest latency a file may state: 1000 s (LinuxCNC is unusable beyond about 1 ms).
MAX_LATENCY_NS = 10**12
#: The largest count of one histogram bin (sums over bins and threads stay within int64).
MAX_COUNT = 10**15


def _int(text: str, path: str | Path, lineno: int, limit: int = MAX_LATENCY_NS) -> int:
    """A whole number of the file, at most ``limit`` (one line naming the file and line)."""
    try:
        return parse_int(text, f"{path}: line {lineno}:", limit=limit)
    except UnitError as err:
        raise ConfigError(str(err)) from None


def _us_to_ns(text: str, path: str | Path, lineno: int) -> int:
    try:
        us = finite_float(text, f"{path}: line {lineno}:", limit=MAX_LATENCY_NS // 1000)
    except UnitError as err:
        raise ConfigError(str(err)) from None
    return round(us * 1000)


def _nox(text: str, path: str | Path) -> tuple[int, int, int] | None:
    """(min_ns, max_ns, sdev_ns) of the base thread (or the only thread) in --nox output."""
    rows: dict[str, list[tuple[int, int, int]]] = {}
    for lineno, line in enumerate(text.splitlines(), 1):
        m = _NOX.match(line)
        if m:
            ns = [_us_to_ns(m.group(k), path, lineno) for k in (3, 4, 5)]
            rows.setdefault(m.group(2), []).append((ns[0], ns[1], ns[2]))
    if not rows:
        return None
    lines = rows.get("base") or next(iter(rows.values()))
    return min(r[0] for r in lines), max(r[1] for r in lines), lines[-1][2]


def _cyclictest_hist(text: str, path: str | Path) -> tuple[np.ndarray, np.ndarray, int, int | None]:
    """(bin values µs, counts summed over threads, overflows, max latency µs or None)."""
    bins: list[int] = []
    cols: list[list[int]] = []
    overflows = 0
    max_lat: int | None = None
    for lineno, line in enumerate(text.splitlines(), 1):
        m = _HIST_ROW.match(line)
        if m:
            bins.append(_int(m.group(1), path, lineno, MAX_LATENCY_NS // 1000))
            cols.append([_int(x, path, lineno, MAX_COUNT) for x in m.group(2).split()])
            continue
        if line.startswith("# Max Latencies:"):
            found = re.findall(r"\d+", line.split(":", 1)[1])
            nums = [_int(x, path, lineno, MAX_LATENCY_NS // 1000) for x in found]
            max_lat = max(nums) if nums else None
        elif line.startswith("# Histogram Overflows:"):
            found = re.findall(r"\d+", line.split(":", 1)[1])
            overflows = sum(_int(x, path, lineno, MAX_COUNT) for x in found)
        elif line.strip() and not line.startswith("#") and bins:
            raise ConfigError(
                f"{path}: line {lineno}: not a cyclictest histogram row: {line.strip()!r}"
            )
    if not bins:
        raise ConfigError(f"{path}: no histogram rows found (expected cyclictest -h output)")
    width = min(len(c) for c in cols)
    counts = np.array([c[:width] for c in cols], dtype=np.int64)
    # with -H the last column is the sum over all threads: drop it rather than count twice
    if width > 1 and np.array_equal(counts[:, -1], counts[:, :-1].sum(axis=1)):
        counts = counts[:, :-1]
    return np.array(bins, dtype=np.int64), counts.sum(axis=1), overflows, max_lat


def read_latency_file(path: str | Path, cyclictest_unit: str = "us") -> tuple[int, str]:
    """The worst latency in ``path`` in ns, and a one-line description of where it came from.

    ``cyclictest_unit`` is the unit of a cyclictest summary's numbers ("ns" if it ran with
    ``-N``); histograms are always in µs bins.

    Raises:
        ConfigError: unreadable file or no recognisable latency figure.
    """
    text = _read(path)
    stripped = text.strip()
    if re.fullmatch(r"\d+", stripped):
        line = next(n for n, li in enumerate(text.splitlines(), 1) if li.strip())
        ns = _int(stripped, path, line)
        return ns, f"{path}: LinuxCNC latency-test result (Max Jitter, ns)"
    nox = _nox(text, path)
    if nox is not None:
        lo, hi, _ = nox
        worst = max(abs(lo), hi)
        return worst, f"{path}: latency-histogram --nox, base thread max(|min|, max)"
    if "# Histogram" in text or any(_HIST_ROW.match(li) for li in text.splitlines()[:50]):
        bins, counts, overflows, max_lat = _cyclictest_hist(text, path)
        if max_lat is not None:
            return max_lat * 1000, f"{path}: cyclictest -h '# Max Latencies' (µs)"
        nonzero = np.flatnonzero(counts)
        if overflows:
            return (
                int(bins[-1]) + 1
            ) * 1000, f"{path}: cyclictest -h, overflows beyond the last bin (lower bound)"
        if len(nonzero):
            return (
                int(bins[nonzero[-1]]) + 1
            ) * 1000, f"{path}: cyclictest -h highest non-empty bin (upper edge)"
        raise ConfigError(f"{path}: cyclictest histogram is empty")
    maxes = [
        _int(m.group(2), path, n, MAX_LATENCY_NS)
        for n, li in enumerate(text.splitlines(), 1)
        if (m := _CT_SUMMARY.match(li))
    ]
    if maxes:
        factor = {"us": 1000, "ns": 1}.get(cyclictest_unit)
        if factor is None:
            raise ConfigError(f"cyclictest unit {cyclictest_unit!r} is not 'us' or 'ns'")
        return max(
            maxes
        ) * factor, f"{path}: cyclictest summary, worst 'Max:' over threads ({cyclictest_unit})"
    raise ConfigError(
        f"{path}: no latency figure found (expected ~/.latency, cyclictest output or latency-histogram --nox)"
    )


def read_histogram(path: str | Path) -> LatencyHistogram:
    """A latency distribution from cyclictest ``-h`` output or ``latency-histogram --nox``.

    cyclictest bins are whole µs (bin b holds latencies of b µs); a drawn value is b µs exactly.
    Overflows (≥ the histogram size) are drawn as the ``# Max Latencies`` value.
    """
    text = _read(path)
    nox = _nox(text, path)
    if nox is not None:
        lo, hi, sdev = nox
        worst = max(abs(lo), hi)
        return LatencyHistogram(
            np.zeros(0, np.int64),
            np.zeros(0),
            f"half-normal sdev {sdev} ns capped at {worst} ns from {path} (latency-histogram --nox)",
            half_normal=(sdev, worst),
        )
    bins, counts, overflows, max_lat = _cyclictest_hist(text, path)
    values = bins * 1000
    weights = counts.astype(float)
    if overflows:
        top = (max_lat if max_lat is not None else int(bins[-1]) + 1) * 1000
        values = np.append(values, top)
        weights = np.append(weights, float(overflows))
    if weights.sum() <= 0:
        raise ConfigError(f"{path}: cyclictest histogram is empty")
    return LatencyHistogram(values, weights / weights.sum(), f"cyclictest histogram {path}")
