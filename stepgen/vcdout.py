"""Write a :class:`~stepgen.simulate.Trace` as VCD (pyvcd) or sigrok ``.sr`` — atomically.

VCD: timescale 1 ns (every latency is a whole number of ns, so every edge is exact), scope
``stepgen``, one 1-bit wire per output pin named as LinuxCNC names it (``step``, ``dir``,
``up``, ``down``, ``phase-A`` …), plus ``counts`` (integer, 32 bits): accum>>28 after each
make-pulses. A final timestamp marks the end of the simulated span. No ``$date`` (output is
reproducible byte for byte) and no sample-rate comment (a simulated VCD is exact, T = 0).

``.sr`` (srzip, reference sigrok.md §5): ``version`` "2", ``metadata``, ``logic-1-N`` chunks of
4 MiB. The sample period is the largest exact one: g = gcd(every edge time, the end, 10^9) ns,
so the rate 10^9/g Hz is a whole number and every edge falls on a sample. ``counts`` is not a
logic signal and is left out. Runs longer than ``max_samples`` at that rate are refused.
"""

from __future__ import annotations

import math
import zipfile
from pathlib import Path

import numpy as np
from vcd import VCDWriter

from stepgen.simulate import Trace
from wavecheck.errors import ConfigError
from wavecheck.output import atomic_path
from wavecheck.progress import current

_REPORT_EVERY = 1 << 16  # value changes between two progress reports

__all__ = ["DEFAULT_MAX_SAMPLES", "header_comment", "sr_sample_period_ns", "write_sr", "write_vcd"]

DEFAULT_MAX_SAMPLES = 200_000_000
SR_CHUNK = 4 * 1024 * 1024


def header_comment(trace: Trace) -> str:
    """One line describing the run (config, latency, seed)."""
    c = trace.config
    parts = [
        f"stepgen model of LinuxCNC stepgen: type {c.step_type}",
        f"mode {c.mode}",
        f"base {c.base_period_ns} ns",
        f"servo {c.servo_ns} ns",
        f"scale {c.position_scale:g}",
        f"maxvel {c.maxvel:g}",
        f"maxaccel {c.maxaccel:g}",
        f"steplen {trace.run.final['steplen']} stepspace {trace.run.final['stepspace']}",
        f"dirsetup {trace.run.final['dirsetup']} dirhold/dirdelay {trace.run.final['dirhold']} (ns, rounded)",
        f"thread order {c.thread_order}",
        f"latency {trace.latency.text}" + (f" seed {trace.seed}" if trace.latency.random else ""),
        f"periods {trace.n_periods}",
    ]
    if c.user_step_type:
        parts.insert(1, f"user table {','.join(map(str, c.user_step_type))}")
    return "; ".join(parts)


def _events(trace: Trace) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """All value changes sorted by time: (time_ns, var index, value); counts is the last var."""
    ts, vs, vals = [], [], []
    for i, pin in enumerate(trace.pins):
        e = trace.edges[pin]
        ts.append(e)
        vs.append(np.full(len(e), i, dtype=np.int64))
        vals.append((np.arange(len(e)) + 1) & 1)
    n = len(trace.pins)
    ts.append(trace.counts_t)
    vs.append(np.full(len(trace.counts_t), n, dtype=np.int64))
    vals.append(trace.counts_val)
    t = np.concatenate(ts).astype(np.int64)
    v = np.concatenate(vs)
    x = np.concatenate(vals).astype(np.int64)
    order = np.lexsort((v, t))
    return t[order], v[order], x[order]


def write_vcd(trace: Trace, path: str | Path) -> int:
    """Write ``trace`` as a VCD at ``path`` (atomically); returns the number of value changes."""
    t, v, x = _events(trace)
    with atomic_path(path) as tmp, open(tmp, "w", encoding="ascii", newline="\n") as fh:
        writer = VCDWriter(fh, timescale="1 ns", date="", comment=header_comment(trace))
        variables = [
            writer.register_var("stepgen", pin, "wire", size=1, init=0) for pin in trace.pins
        ]
        variables.append(writer.register_var("stepgen", "counts", "integer", size=32, init=0))
        change = writer.change
        report = current()
        n = len(t)
        for a in range(0, n, _REPORT_EVERY):
            b = min(a + _REPORT_EVERY, n)
            for ti, vi, xi in zip(t[a:b].tolist(), v[a:b].tolist(), x[a:b].tolist(), strict=True):
                change(variables[vi], ti, xi)
            report(b, n)
        writer.close(trace.end_ns)
    return n


def sr_sample_period_ns(trace: Trace) -> int:
    """g = gcd(all edge times, end, 10^9) ns: the coarsest exact sample period that divides 1 s."""
    g = math.gcd(trace.end_ns, 10**9)
    for pin in trace.pins:
        e = trace.edges[pin]
        if len(e):
            g = math.gcd(g, int(np.gcd.reduce(e)))
    return max(g, 1)


def _rate_text(hz: int) -> str:
    for div, unit in ((10**9, "GHz"), (10**6, "MHz"), (10**3, "kHz")):
        if hz % div == 0:
            return f"{hz // div} {unit}"
    return f"{hz} Hz"


def write_sr(
    trace: Trace, path: str | Path, max_samples: int = DEFAULT_MAX_SAMPLES
) -> tuple[int, int]:
    """Write ``trace`` as a sigrok ``.sr`` (atomically); returns (samplerate Hz, samples).

    Raises:
        ConfigError: more than ``max_samples`` samples would be needed (nothing is written).
    """
    g = sr_sample_period_ns(trace)
    n_samples = trace.end_ns // g
    if n_samples > max_samples:
        raise ConfigError(
            f"{path}: a .sr of this run needs {n_samples} samples at {_rate_text(10**9 // g)} "
            f"(edges on a {g} ns grid), more than {max_samples} (write a .vcd instead, or shorten the run)"
        )
    n_pins = len(trace.pins)
    unitsize = max(1, (n_pins + 7) // 8)
    # merged changes: sample index → new byte value
    t, v, _ = _events(trace)
    logic = v < n_pins
    t, v = t[logic] // g, v[logic]
    bits = np.zeros(len(t), dtype=np.int64)
    if len(t):
        bits = np.bitwise_xor.accumulate(np.left_shift(1, v))
    # keep the last change per sample index
    keep = np.ones(len(t), dtype=bool)
    if len(t):
        keep[:-1] = t[1:] != t[:-1]
    t, bits = t[keep], bits[keep]
    starts = np.concatenate(([0], t))
    values = np.concatenate(([0], bits))
    lengths = np.diff(np.concatenate((starts, [n_samples])))
    good = lengths > 0
    samples = np.repeat(
        values[good].astype(f"<u{unitsize}" if unitsize in (1, 2, 4, 8) else "<u8"), lengths[good]
    )
    raw = samples.tobytes()
    meta = [
        "[global]",
        "sigrok version=0.5.2",
        "",
        "[device 1]",
        "capturefile=logic-1",
        f"total probes={n_pins}",
    ]
    meta += [f"samplerate={_rate_text(10**9 // g)}", "total analog=0"]
    meta += [f"probe{i + 1}={pin}" for i, pin in enumerate(trace.pins)]
    meta.append(f"unitsize={unitsize}")
    with atomic_path(path) as tmp, zipfile.ZipFile(tmp, "w") as z:
        z.writestr(zipfile.ZipInfo("version"), "2", compress_type=zipfile.ZIP_STORED)
        z.writestr("metadata", "\n".join(meta) + "\n", compress_type=zipfile.ZIP_DEFLATED)
        for i, off in enumerate(range(0, max(len(raw), 1), SR_CHUNK)):
            z.writestr(
                f"logic-1-{i + 1}", raw[off : off + SR_CHUNK], compress_type=zipfile.ZIP_DEFLATED
            )
    return 10**9 // g, int(n_samples)
