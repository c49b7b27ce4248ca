"""Write a :class:`~stepgen.simulate.Trace` as VCD (the project's writer: numpy, byte-identical to
pyvcd) or sigrok ``.sr`` — atomically.

VCD: timescale 1 ns (every latency is a whole number of ns, so every edge is exact), scope
``stepgen``, one 1-bit wire per output pin named as LinuxCNC names it (``step``, ``dir``,
``up``, ``down``, ``phase-A`` …), plus ``counts`` (integer, 32 bits): accum>>28 after each
make-pulses. A final timestamp marks the end of the simulated span. No ``$date`` (output is
reproducible byte for byte) and no sample-rate comment (a simulated VCD is exact, T = 0).

``.sr`` (srzip, reference sigrok.md §5): ``version`` "2", ``metadata``, ``logic-1-N`` chunks of
4 MiB. The sample period is the largest exact one: g = gcd(every edge time, the end, 10^9) ns,
so the rate 10^9/g Hz is a whole number and every edge falls on a sample. Because the edges are
simulated, not sampled, the metadata also says so (``[wavecheck] edges=exact``, ignored by
libsigrok): a reader that took the file as sampled would give every interval ± one period g
(at 40 kHz base period that is ±25 µs: a 25 µs pulse against a 4.5 µs limit was
indeterminate), and no finer rate could help a pulse exactly at its limit. ``counts`` is not a
logic signal and is left out. Runs longer than ``max_samples`` at that rate are refused.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from stepgen.simulate import Trace
from wavecheck.capture.vcd.writer import VcdVector, VcdWire
from wavecheck.capture.vcd.writer import write_vcd as write_vcd_file
from wavecheck.errors import ConfigError

__all__ = ["DEFAULT_MAX_SAMPLES", "header_comment", "sr_sample_period_ns", "write_sr", "write_vcd"]

DEFAULT_MAX_SAMPLES = 200_000_000
#: How a stepgen .sr names the simulation its exact edges come from.
SR_SOURCE = "stepgen, a model of LinuxCNC's stepgen"


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


def write_vcd(trace: Trace, path: str | Path) -> int:
    """Write ``trace`` as a VCD at ``path`` (atomically); returns the number of value changes."""
    return write_vcd_file(
        path,
        [VcdWire(pin, 0, trace.edges[pin]) for pin in trace.pins],
        vectors=[VcdVector("counts", trace.counts_t, trace.counts_val, size=32)],
        timescale="1 ns",
        end=trace.end_ns,
        scope="stepgen",
        comment=header_comment(trace),
    )


def sr_sample_period_ns(trace: Trace) -> int:
    """g = gcd(all edge times, end, 10^9) ns: the coarsest exact sample period that divides 1 s."""
    g = math.gcd(trace.end_ns, 10**9)
    for pin in trace.pins:
        e = trace.edges[pin]
        if len(e):
            g = math.gcd(g, int(np.gcd.reduce(e)))
    return max(g, 1)


def write_sr(
    trace: Trace, path: str | Path, max_samples: int = DEFAULT_MAX_SAMPLES
) -> tuple[int, int]:
    """Write ``trace`` as a sigrok ``.sr`` (atomically); returns (samplerate Hz, samples).

    Raises:
        ConfigError: more than ``max_samples`` samples would be needed (nothing is written).
    """
    from wavecheck.capture.srzip import SR_CHUNK_BYTES, rate_text, write_sr_edges  # .sr only

    g = sr_sample_period_ns(trace)
    n_samples = trace.end_ns // g
    if n_samples > max_samples:
        raise ConfigError(
            f"{path}: a .sr of this run needs {n_samples} samples at {rate_text(10**9 // g)} "
            f"(edges on a {g} ns grid), more than {max_samples} (write a .vcd instead, or shorten the run)"
        )
    # an edge at the very end (sample n_samples) lies after the last sample
    edges = [trace.edges[pin] // g for pin in trace.pins]
    edges = [e[e < n_samples] for e in edges]
    write_sr_edges(
        path,
        list(trace.pins),
        edges,
        [0] * len(trace.pins),
        int(n_samples),
        samplerate=10**9 // g,
        chunk_bytes=SR_CHUNK_BYTES,
        exact_source=SR_SOURCE,
    )
    return 10**9 // g, int(n_samples)
