"""Deterministic generators for the benchmark inputs (written to ``bench/data/``, git-ignored).

* :func:`gen_sr` — a long sigrok ``.sr`` of STEP/DIR for 3 axes plus ENABLE, at realistic rates
  (trapezoid moves up to ~20 kHz, 5 µs pulses, DIR changing between moves), written chunk by
  chunk: samples are built per 4 MiB member with ``np.repeat`` over the runs between edges and
  written as they come by wavecheck's .sr writer (:mod:`wavecheck.capture.srzip`), deflated at
  level 9 like libsigrok's srzip.
* :func:`gen_vcd` — a 10 M-change, 6-signal VCD like ``../shared/reference/vcd-perf.md``'s
  (3 axes ``step``/``dir``, 1 ns timescale, X 25.0 / Y 24.3 / Z 25.7 kHz with ±500 ns jitter,
  2 µs pulses, DIR reversing every ~4000 steps 5 µs before a rising edge), in the simulator
  layout (``#t`` then one change per line, scoped names) or sigrok's (changes on the timestamp
  line). Text is formatted with numpy, one block of events at a time.
* :func:`gen_edges` — 10 M edges (STEP and DIR) as arrays, for the check engine alone.
* :func:`gen_stepgen_vcd` — issue 25's capture: LinuxCNC's stepgen (the model, ``stepgen
  simulate``) at a 25 µs base period under ``uniform:11us`` latency, three 40-unit moves at
  the maximum step rate (20 k steps/s): 1.2 M edges, 31 MB of VCD; the truth is P and the worst
  lateness of the invocations that made an edge.
* :func:`gen_command` — a ``stepgen simulate --command`` CSV (a sine, a row a millisecond).
* :func:`gen_stepgen_sr` — a stepgen ``.sr`` of a sine-following axis (the cross-check's input).

Each generator also writes ``<file>.truth.json`` with the counts a reader must find. Run
``python bench/gen.py --help``; ``bench/run.py`` calls these when a file is missing.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np
import numpy.typing as npt

from wavecheck.capture.srzip import sr_metadata, write_sr

DATA = Path(__file__).resolve().parent / "data"
SR_MEMBER_BYTES = 4 << 20  # libsigrok's CHUNK_SIZE for VCD input; FX2 captures use 10 MiB


# ---------------------------------------------------------------------------------------------
# motion: step times of trapezoid moves


def _axis_steps(
    rng: np.random.Generator, duration_s: float, vmax_hz: float, accel: float
) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    """Step times (s) of a sequence of trapezoid moves with pauses, and DIR change times (s)."""
    dt = 1e-4  # velocity profile grid: 100 µs
    t_grid: list[npt.NDArray[np.float64]] = []
    v_grid: list[npt.NDArray[np.float64]] = []
    dir_changes: list[float] = []
    t = 0.01 + rng.uniform(0, 0.01)
    direction = 1
    while t < duration_s:
        v = rng.uniform(0.1, 1.0) * vmax_hz
        ramp = v / accel
        cruise = rng.uniform(0.02, 0.6)
        n = max(3, int((2 * ramp + cruise) / dt))
        tt = t + np.arange(n) * dt
        rel = tt - t
        vel = np.minimum.reduce(
            [rel / ramp * v, np.full(n, v), (2 * ramp + cruise - rel) / ramp * v]
        )
        vel = np.clip(vel, 0, None)
        t_grid.append(tt)
        v_grid.append(vel)
        t += n * dt
        pause = rng.uniform(0.002, 0.2)
        if rng.random() < 0.5:  # reverse between moves, mid-pause
            direction = -direction
            dir_changes.append(t + pause / 2)
        t += pause
    tg = np.concatenate(t_grid)
    vg = np.concatenate(v_grid)
    # position = integral of velocity over each grid cell; steps where it crosses an integer
    pos = np.concatenate([[0.0], np.cumsum(vg * dt)])
    tpos = np.concatenate([[tg[0]], tg + dt])
    k = np.arange(1, int(pos[-1]))
    steps = np.interp(k, pos, tpos)
    steps = steps[steps < duration_s]
    dirs = np.array([d for d in dir_changes if d < duration_s])
    return steps, dirs


# ---------------------------------------------------------------------------------------------
# .sr


def gen_sr(
    path: Path,
    *,
    nsamples: int = 1_000_000_000,
    samplerate: int = 20_000_000,
    seed: int = 7,
    level: int = 9,
) -> dict[str, object]:
    """Write a STEP/DIR ``.sr`` of ``nsamples`` samples (unitsize 1); return its truth."""
    rng = np.random.default_rng(seed)
    duration = nsamples / samplerate
    pulse = int(round(5e-6 * samplerate))  # 5 µs STEP pulses (grbl/LinuxCNC-like)
    names = ["EN", "X_STEP", "X_DIR", "Y_STEP", "Y_DIR", "Z_STEP", "Z_DIR", "SPINDLE"]
    ev_t: list[npt.NDArray[np.int64]] = []
    ev_m: list[npt.NDArray[np.uint8]] = []
    truth: dict[str, object] = {"nsamples": nsamples, "samplerate": samplerate, "axes": {}}
    en_on = int(0.005 * samplerate)
    ev_t.append(np.array([en_on], np.int64))
    ev_m.append(np.array([1], np.uint8))
    for axis, (vmax, bit) in enumerate(((20e3, 1), (15e3, 3), (8e3, 5))):
        steps_s, dirs_s = _axis_steps(rng, duration, vmax, accel=vmax * 4)
        rise = np.floor(steps_s * samplerate).astype(np.int64) + en_on
        rise = rise[rise + pulse < nsamples - 1]
        fall = rise + pulse
        dch = np.floor(dirs_s * samplerate).astype(np.int64) + en_on
        dch = dch[dch < nsamples - 1]
        ev_t += [rise, fall, dch]
        ev_m += [
            np.full(len(rise), 1 << bit, np.uint8),
            np.full(len(fall), 1 << bit, np.uint8),
            np.full(len(dch), 1 << (bit + 1), np.uint8),
        ]
        truth["axes"][names[bit][0]] = {  # type: ignore[index]
            "steps": int(len(rise)),
            "step_edges": int(2 * len(rise)),
            "dir_edges": int(len(dch)),
        }
        del axis
    t = np.concatenate(ev_t)
    m = np.concatenate(ev_m)
    order = np.argsort(t, kind="stable")
    t, m = t[order], m[order]
    # merge events at the same sample (XOR of their masks)
    first = np.ones(len(t), bool)
    first[1:] = t[1:] != t[:-1]
    starts = np.flatnonzero(first)
    t = t[starts]
    m = np.bitwise_xor.reduceat(m, starts)
    state = np.bitwise_xor.accumulate(m)  # level after each event (initial level 0)
    truth["edges_total"] = int(sum(np.count_nonzero(m & (1 << b)) for b in range(8)))

    def block(a: int, b: int) -> bytes:
        i0 = int(np.searchsorted(t, a, side="right"))
        i1 = int(np.searchsorted(t, b, side="left"))
        s0 = state[i0 - 1] if i0 > 0 else np.uint8(0)
        bounds = np.concatenate([[a], t[i0:i1], [b]])
        vals = np.concatenate([[s0], state[i0:i1]]).astype(np.uint8)
        return np.repeat(vals, np.diff(bounds)).tobytes()

    nmembers = -(-nsamples // SR_MEMBER_BYTES)
    members = (
        block(k * SR_MEMBER_BYTES, min(nsamples, (k + 1) * SR_MEMBER_BYTES))
        for k in range(nmembers)
    )
    meta = sr_metadata(names, samplerate=samplerate, unitsize=1)
    write_sr(path, members, metadata=meta, compresslevel=level)
    truth["members"] = nmembers
    path.with_suffix(".truth.json").write_text(json.dumps(truth, indent=1) + "\n")
    return truth


# ---------------------------------------------------------------------------------------------
# VCD


def _vcd_events(
    nchanges: int, seed: int
) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.int8], npt.NDArray[np.int8]]:
    """(time ns, signal 0..5, value) of ~``nchanges`` changes, time-ordered (signal order within a time)."""
    rng = np.random.default_rng(seed)
    rates = (25.0e3, 24.3e3, 25.7e3)
    share = np.array(rates) / sum(rates)
    ts: list[npt.NDArray[np.int64]] = []
    ss: list[npt.NDArray[np.int8]] = []
    vs: list[npt.NDArray[np.int8]] = []
    for axis, rate in enumerate(rates):
        nsteps = int(nchanges * share[axis] / (2 + 1 / 4000))
        period = 1e9 / rate
        rise = (25_000 + np.arange(nsteps) * period + rng.uniform(-500, 500, nsteps)).astype(
            np.int64
        )
        fall = rise + 2000
        rev = np.flatnonzero(rng.random(nsteps) < 1 / 4000)
        rev = rev[rev > 0]
        dch = rise[rev] - 5000
        dval = (np.arange(1, len(rev) + 1) & 1).astype(np.int8)
        ts += [rise, fall, dch]
        ss += [np.full(nsteps, 2 * axis, np.int8), np.full(nsteps, 2 * axis, np.int8),
               np.full(len(rev), 2 * axis + 1, np.int8)]  # fmt: skip
        vs += [np.ones(nsteps, np.int8), np.zeros(nsteps, np.int8), dval]
    t = np.concatenate(ts)
    s = np.concatenate(ss)
    v = np.concatenate(vs)
    order = np.lexsort((s, t))
    return t[order], s[order], v[order]


def _digits(t: npt.NDArray[np.int64]) -> npt.NDArray[np.int64]:
    nd = np.ones(len(t), np.int64)
    p = 10
    while True:
        more = t >= p
        if not more.any():
            return nd
        nd += more
        p *= 10


def _format_block(
    t: npt.NDArray[np.int64],
    s: npt.NDArray[np.int8],
    v: npt.NDArray[np.int8],
    ids: bytes,
    layout: str,
) -> bytes:
    """VCD body text of these changes (``t`` non-decreasing, a block starts a new timestamp).

    Simulator layout: ``#t\n`` then ``vI\n`` per change. sigrok layout: ``#t vI vI\n``.
    Each change is one record: the timestamp text if it is the first at its time, the change,
    and (sigrok) the newline if it is the last at its time.
    """
    n = len(t)
    newt = np.ones(n, bool)
    newt[1:] = t[1:] != t[:-1]
    tidx = np.flatnonzero(newt)
    tv = t[tidx]
    nd = _digits(tv)
    sim = layout == "sim"
    head = nd + (2 if sim else 1)  # "#digits\n" or "#digits"
    rec = np.full(n, 3, np.int64)
    rec[tidx] += head
    last = np.empty(n, bool)
    last[:-1] = newt[1:]
    last[-1] = True
    if not sim:
        rec[last] += 1
    end = np.cumsum(rec)
    start = end - rec
    buf = np.empty(int(end[-1]), np.uint8)
    ts = start[tidx]
    buf[ts] = ord("#")
    for col in range(int(nd.max())):
        m = nd > col
        buf[ts[m] + nd[m] - col] = 48 + (tv[m] // 10**col) % 10
    c = start.copy()
    c[tidx] += head
    idb = np.frombuffer(ids, np.uint8)
    if sim:
        buf[ts + nd + 1] = 10
        buf[c] = 48 + v
        buf[c + 1] = idb[s]
        buf[c + 2] = 10
    else:
        buf[c] = 32
        buf[c + 1] = 48 + v
        buf[c + 2] = idb[s]
        buf[c[last] + 3] = 10
    return buf.tobytes()


def gen_vcd(
    path: Path, *, nchanges: int = 10_000_000, layout: str = "sim", seed: int = 11
) -> dict[str, object]:
    """Write the 6-signal STEP/DIR VCD; ``layout`` is ``"sim"`` or ``"sigrok"``."""
    t, s, v = _vcd_events(nchanges - 6, seed)
    ids = b'!"#$%&'
    if layout == "sim":
        head = ["$date bench $end", "$version wavecheck bench/gen.py $end", "$timescale 1 ns $end",
                "$scope module top $end"]  # fmt: skip
        for axis in "xyz":
            head += [f"$scope module axis_{axis} $end"]
            k = "xyz".index(axis)
            head += [
                f"$var wire 1 {chr(ids[2 * k])} step $end",
                f"$var wire 1 {chr(ids[2 * k + 1])} dir $end",
            ]
            head += ["$upscope $end"]
        head += ["$upscope $end", "$enddefinitions $end", "#0", "$dumpvars"]
        head += [f"0{chr(c)}" for c in ids] + ["$end"]
    else:
        head = ["$date bench $end", "$version libsigrok 0.5.2 $end",
                "$comment\n  Acquisition with 6/6 channels at 1 GHz\n$end",
                "$timescale 1 ns $end", "$scope module libsigrok $end"]  # fmt: skip
        for k, name in enumerate(["X_STEP", "X_DIR", "Y_STEP", "Y_DIR", "Z_STEP", "Z_DIR"]):
            head.append(f"$var wire 1 {chr(ids[k])} {name} $end")
        head += [
            "$upscope $end",
            "$enddefinitions $end",
            "#0 " + " ".join(f"0{chr(c)}" for c in ids),
        ]
    tmp = path.with_suffix(".tmp")
    block = 1 << 20
    with open(tmp, "wb") as f:
        f.write(("\n".join(head) + "\n").encode())
        i = 0
        while i < len(t):  # blocks end where the time changes: no timestamp written twice
            j = min(len(t), i + block)
            if j < len(t):
                j = int(np.searchsorted(t, t[j], side="left")) or j
            f.write(_format_block(t[i:j], s[i:j], v[i:j], ids, layout))
            i = j
        f.write(f"#{int(t[-1]) + 1000}\n".encode())
    tmp.replace(path)
    edges = [int(np.count_nonzero(s == k)) for k in range(6)]
    truth = {
        "changes": int(len(t)) + 6,
        "edges_per_signal": edges,
        "edges": int(len(t)),
        "layout": layout,
    }
    path.with_suffix(".truth.json").write_text(json.dumps(truth, indent=1) + "\n")
    return truth


# ---------------------------------------------------------------------------------------------
# edge arrays


def gen_edges(path: Path, *, nedges: int = 10_000_000, seed: int = 3) -> dict[str, object]:
    """STEP/DIR edge arrays (ticks of 20 ns, a 50 MHz capture) with ``nedges`` edges in all.

    One axis stepping at 20–60 kHz with 5 µs pulses (falling edge active for a G202), DIR
    reversing every ~2000 steps; about 0.01 % of pulses are short and a few DIR changes come
    too soon after a step, so every rule has violations to report.
    """
    rng = np.random.default_rng(seed)
    nsteps = nedges // 2 - nedges // 4000
    period = rng.uniform(833, 2500, nsteps).astype(np.int64)  # 20–60 kHz at 50 MHz
    rise = 1000 + np.cumsum(period)
    width = np.full(nsteps, 250, np.int64)  # 5 µs
    short = rng.random(nsteps) < 1e-4
    width[short] = 10  # 200 ns: fails step_high 4.5 µs
    fall = rise + width
    step = np.empty(2 * nsteps, np.int64)
    step[0::2], step[1::2] = rise, fall
    ndir = nedges - len(step)
    at = np.sort(rng.choice(np.arange(1, nsteps - 1), ndir, replace=False))
    # DIR changes mid-gap, a few right after the falling (active) edge (dir_hold < 20 µs)
    dirt = (fall[at] + rise[at + 1]) // 2
    close = rng.random(ndir) < 0.02
    dirt[close] = fall[at[close]] + 100  # 2 µs after the active edge
    np.savez(path, step=step, dir=dirt, tick_hz=np.int64(50_000_000))
    truth = {
        "edges": int(len(step) + len(dirt)),
        "steps": int(nsteps),
        "short_pulses": int(short.sum()),
    }
    path.with_suffix(".truth.json").write_text(json.dumps(truth, indent=1) + "\n")
    return truth


def gen_command(path: Path, *, seconds: float = 20.0, amplitude: float = 10.0) -> dict[str, object]:
    """A ``stepgen simulate --command`` CSV: ``amplitude·sin(t)`` units, a row every 1 ms (as
    ``bench/stepgen_vcd.py``'s motion)."""
    t = np.arange(round(seconds * 1000) + 2) * 1e-3
    rows = [
        f"{a:.3f},{v!r}" for a, v in zip(t.tolist(), (amplitude * np.sin(t)).tolist(), strict=True)
    ]
    path.write_text("time_s,value\n" + "\n".join(rows) + "\n")
    truth = {"rows": len(rows), "seconds": seconds, "amplitude": amplitude}
    path.with_suffix(".truth.json").write_text(json.dumps(truth, indent=1) + "\n")
    return truth


def gen_stepgen_sr(path: Path, *, seconds: float) -> dict[str, object]:
    """A ``.sr`` from stepgen (25 µs base period, no latency: 40 kHz), position mode following
    15·sin(t) units at 1000 steps/unit, 20 kHz at most: ~9600 steps a second, DIR reversing every
    π s (the cross-check's input: ~575 k steps a minute)."""
    from stepgen.motion import Motion
    from stepgen.reference import StepgenConfig
    from stepgen.simulate import simulate
    from stepgen.vcdout import write_sr as write_trace_sr

    cfg = StepgenConfig(base_period_ns=25_000, servo_period_ns=1_000_000, position_scale=1000,
                        maxvel=20, maxaccel=200, thread_order="pulses-first")  # fmt: skip
    t = np.arange(round(seconds * 1000) + 2) * 1e-3
    trace = simulate(cfg, Motion("csv", csv_times=t, csv_values=15 * np.sin(t)),
                     n_periods=round(seconds * 40_000))  # fmt: skip
    write_trace_sr(trace, path)
    truth = {"steps": trace.steps, "seconds": seconds, "dir_edges": len(trace.edges["dir"])}
    path.with_suffix(".truth.json").write_text(json.dumps(truth, indent=1) + "\n")
    return truth


# ---------------------------------------------------------------------------------------------


def gen_stepgen_vcd(path: Path) -> dict[str, object]:
    """Issue 25's capture (module docstring) and its truth."""
    from stepgen.motion import Motion, parse_moves
    from stepgen.reference import StepgenConfig
    from stepgen.simulate import n_periods_for, simulate
    from stepgen.vcdout import write_vcd

    cfg = StepgenConfig(
        base_period_ns=25_000, position_scale=5000, maxvel=3.9, maxaccel=100,
        thread_order="pulses-first",  # as `stepgen simulate` runs two threads
    )  # fmt: skip
    motion = Motion("moves", segments=parse_moves("40, pause 100ms, 0, pause 100ms, 40", 3.9, 100))
    duration = int((motion.natural_duration_s or 1.0) * 1e9)
    trace = simulate(cfg, motion, "uniform:11us", n_periods=n_periods_for(cfg, duration), seed=1)
    write_vcd(trace, path)
    idx = np.unique(np.concatenate([trace.run.toggles[p] for p in trace.pins]))
    t = np.unique(np.concatenate([trace.edges[p] for p in trace.pins]))
    late = t - idx * cfg.base_period_ns
    truth = {
        "base_period_ns": cfg.base_period_ns,
        "max_lateness_ns": int(late.max() - late.min()),
        "edges": int(sum(len(e) for e in trace.edges.values())),
    }
    path.with_suffix(".truth.json").write_text(json.dumps(truth) + "\n")
    return truth


FILES = {
    "sr1g": ("stepdir_1G.sr", lambda p: gen_sr(p)),
    "sr100m": ("stepdir_100M.sr", lambda p: gen_sr(p, nsamples=100_000_000, seed=8)),
    # issue 14's bounded-memory rows: the same motion as sr1g, 8 and 16 G samples (400 / 800 s
    # at 20 MHz; 13 M / 26 M edges; 23 / 47 MB; ~1 / 2 min to make), and 2 G for --quick
    "sr2g": ("stepdir_2G.sr", lambda p: gen_sr(p, nsamples=2_000_000_000)),
    "sr8g": ("stepdir_8G.sr", lambda p: gen_sr(p, nsamples=8_000_000_000)),
    "sr16g": ("stepdir_16G.sr", lambda p: gen_sr(p, nsamples=16_000_000_000)),
    "vcd_sim": ("steps_10M_sim.vcd", lambda p: gen_vcd(p, layout="sim")),
    "vcd_sigrok": ("steps_10M_sigrok.vcd", lambda p: gen_vcd(p, layout="sigrok")),
    "vcd_sim_1m": ("steps_1M_sim.vcd", lambda p: gen_vcd(p, nchanges=1_000_000, layout="sim")),
    # issue 14: 50 M and 100 M changes (0.83 / 1.67 GB; ~15 / 30 s), and 2 M for --quick
    "vcd_sim_2m": ("steps_2M_sim.vcd", lambda p: gen_vcd(p, nchanges=2_000_000)),
    "vcd_sim_50m": ("steps_50M_sim.vcd", lambda p: gen_vcd(p, nchanges=50_000_000)),
    "vcd_sim_100m": ("steps_100M_sim.vcd", lambda p: gen_vcd(p, nchanges=100_000_000)),
    "edges": ("edges_10M.npz", lambda p: gen_edges(p)),
    "edges_1m": ("edges_1M.npz", lambda p: gen_edges(p, nedges=1_000_000)),
    "latency": ("stepgen_25us_uniform11us.vcd", lambda p: gen_stepgen_vcd(p)),
    # issue 29: stepgen's --command input (20 s), the cross-check's 575 k / 1.15 M steps
    "cmd20s": ("sine_20s.csv", lambda p: gen_command(p)),
    "cmd2s": ("sine_2s.csv", lambda p: gen_command(p, seconds=2.0)),
    # issue 38: the long trace (120 s) with a VCD out
    "cmd120s": ("sine_120s.csv", lambda p: gen_command(p, seconds=120.0)),
    "xc600k": ("stepgen_575k.sr", lambda p: gen_stepgen_sr(p, seconds=60)),
    "xc1200k": ("stepgen_1150k.sr", lambda p: gen_stepgen_sr(p, seconds=120)),
    "xc60k": ("stepgen_57k.sr", lambda p: gen_stepgen_sr(p, seconds=6)),
}


def ensure(key: str, *, force: bool = False, quiet: bool = False) -> Path:
    """Path of benchmark input ``key``, generating it first if missing."""
    name, make = FILES[key]
    path = DATA / name
    if force or not path.exists():
        DATA.mkdir(parents=True, exist_ok=True)
        t0 = time.perf_counter()
        make(path)
        if not quiet:
            size = path.stat().st_size
            print(
                f"  generated {path.name}: {size / 1e6:.1f} MB in {time.perf_counter() - t0:.1f} s"
            )
    return path


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument(
        "keys", nargs="*", default=list(FILES), help=f"inputs to make ({', '.join(FILES)})"
    )
    ap.add_argument("--force", action="store_true", help="regenerate even if present")
    args = ap.parse_args()
    for key in args.keys:
        ensure(key, force=args.force)


if __name__ == "__main__":
    main()
