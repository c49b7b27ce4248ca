"""The fast engine: the same stepgen, servo period by servo period, with numpy for the pulses.

Between two update-freq calls the base thread's behaviour is deterministic. In the common case
(no DDS hold, no sign change of ``addval``, ``curr_dir`` already agreeing with the sign of
``addval``, |addval| ≤ 2^28) it has a closed form:

* addval in the i-th period of the chunk is ``a0 + sgn·min(i·deltalim, |target − a0|)``
  (a jump straight to the target when deltalim is 0), so the accumulator at the chunk's end is
  an arithmetic series (pass 1, pure Python integers, O(1) per servo period);
* ``accum`` is a cumulative sum, a step is a change of bit 28 (the same XOR test as the C),
  STEP is high for ceil(steplen/P) periods from each step (timer1), DIR is constant, and the
  phase state is a running sum of ±1 per step (pass 2, numpy over ~1 M periods at a time).

Every other servo period ("exact chunk": a reversal, a hold, a timer interaction at the start,
the first steps) is run through the reference make-pulses of :mod:`stepgen.model`, one period
at a time, with the timers made concrete first. The timers of the fast chunks are kept lazily:
only the last step's invocation is needed, and only when an exact chunk follows.

``tests/stepgen/test_fast.py`` checks with hypothesis that this engine and
:func:`stepgen.model.run_reference` give identical toggles, counts and final state.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from stepgen.model import (
    ONE_STEP,
    PICKOFF,
    Channel,
    Component,
    InvocationRun,
    StepgenConfig,
    final_state,
    follow_position,
    follow_velocity,
    make_pulses_channel,
    update_schedule,
)
from wavecheck.progress import current

__all__ = ["run_fast"]

BLOCK_PERIODS = 1 << 20  #: pass 2 works on about this many base periods at a time


@dataclass
class _Pending:
    """A fast chunk that stepped: where its last step is can be computed when needed."""

    k0: int
    m: int
    accum0: int
    a0: int
    sgn: int
    d_eff: int
    span: int
    count_end: int
    loads: tuple[int, int, int]


def _series(i: int, a0: int, sgn: int, d_eff: int, span: int) -> int:
    """Sum of addval over the first ``i`` periods of a ramp chunk (see module docstring)."""
    if d_eff == 0:
        return i * a0
    full = span // d_eff  # periods with a whole deltalim step; afterwards addval == target
    j = i if i < full else full
    total = i * a0 + sgn * d_eff * (j * (j + 1) // 2)
    if i > full:
        total += sgn * span * (i - full)
    return total


def _last_step(p: _Pending) -> int:
    """Invocation index of the last step of a pending fast chunk (binary search, O(log m))."""
    lo, hi = 1, p.m  # first i with count(i) == count_end; exists because the count changed
    while lo < hi:
        mid = (lo + hi) // 2
        if (p.accum0 + _series(mid, p.a0, p.sgn, p.d_eff, p.span)) >> PICKOFF == p.count_end:
            hi = mid
        else:
            lo = mid + 1
    return p.k0 + lo - 1


def _steady(comp: Component, ch: Channel, base: int, servo: int) -> bool:
    """True once update-freq has nothing left to re-round or rescale (periods and params settled)."""
    return (
        comp.periodns == base
        and comp.old_periodns == base
        and comp.old_dtns == servo
        and ch.old_scale == ch.pos_scale
        and ch.step_len == ch.old_step_len
        and ch.step_space == ch.old_step_space
        and ch.dir_setup == ch.old_dir_setup
        and ch.dir_hold_dly == ch.old_dir_hold_dly
        and ch.enable
    )


def run_fast(
    config: StepgenConfig,
    commands: Sequence[float] | np.ndarray,
    n_periods: int,
    block_periods: int = BLOCK_PERIODS,
) -> InvocationRun:
    """Same contract and result as :func:`stepgen.model.run_reference`, much faster.

    Pass 1 keeps the channel state in local variables. Until update-freq has settled (the first
    one or two calls re-round the timing params, §3) it calls the reference update-freq; after
    that it runs the same code inlined (steps 5–9 of §4 with nothing left to re-round).
    """
    config.validate()
    kind = config.kind()
    comp = Component([config])
    ch = comp.channels[0]
    base = config.base_period_ns
    servo = config.servo_ns
    cmds = np.asarray(commands, dtype=float)
    n_cmd = len(cmds)
    cmd_list = cmds.tolist()
    schedule = update_schedule(config, n_periods)
    bounds = ([0] if (not schedule or schedule[0] != 0) else []) + schedule + [n_periods]
    first_update_at = 0 if schedule and schedule[0] == 0 else 1

    # per-chunk descriptors for pass 2: (k0, m, a0, sgn, d_eff, span, dir, step_len, accum0, state0)
    desc: list[tuple[int, int, int, int, int, int, int, int, int, int]] = []
    exact: dict[int, tuple[np.ndarray, np.ndarray]] = {}

    # lazy timers: values after invocation t_ref, or a pending fast chunk
    t_ref = -1
    t_vals = (0, 0, 0)
    pending: _Pending | None = None
    steps_total = 0
    u = 0
    pos_mode = ch.pos_mode
    cycle = max(kind.cycle, 1)
    phased = kind.kind == "phases"
    append = desc.append
    steady = False

    # the channel state, as locals (synced with ``ch`` around reference calls)
    accum = ch.accum
    addval = ch.addval
    target = ch.target_addval
    deltalim = ch.deltalim
    freq = ch.freq
    old_pos_cmd = ch.old_pos_cmd
    curr_dir = ch.curr_dir
    state = ch.state
    maxvel = ch.maxvel
    maxaccel = ch.maxaccel
    # constants once steady
    abs_scale = pos_scale = min_step_period = 0.0
    dt = recip_dt = freqscale = accelscale = 0.0

    def to_ch() -> None:
        ch.accum, ch.addval, ch.target_addval, ch.deltalim = accum, addval, target, deltalim
        ch.freq, ch.old_pos_cmd, ch.curr_dir, ch.state = freq, old_pos_cmd, curr_dir, state
        ch.maxvel, ch.maxaccel = maxvel, maxaccel
        ch.rawcount = accum >> PICKOFF

    report = current()
    for ci in range(len(bounds) - 1):
        k0, k1 = bounds[ci], bounds[ci + 1]
        if not ci & 1023:
            report(k0, n_periods)
        if k1 <= k0:
            continue
        if ci >= first_update_at:
            value = cmd_list[u if u < n_cmd else n_cmd - 1] if n_cmd else 0.0
            u += 1
            if steady:
                # ---- update-freq, steps 5-9 of §4, inlined (same operations as the model) ----
                max_freq = 1.0 / (min_step_period * 0.000000001)
                if maxvel <= 0.0:
                    maxvel = 0.0
                else:
                    desired_freq = maxvel * abs_scale
                    if desired_freq > max_freq:
                        if not ch.printed_error:
                            to_ch()
                            ch.pos_cmd = ch.vel_cmd = value
                            comp.update_freq(servo)  # the model prints its warning
                            raise AssertionError("unreachable: maxvel clamp after settling")
                        maxvel = max_freq / abs_scale
                    else:
                        max_freq = desired_freq
                max_ac = max_freq * recip_dt
                if maxaccel <= 0.0:
                    maxaccel = 0.0
                elif maxaccel * abs_scale > max_ac:
                    maxaccel = max_ac / abs_scale
                else:
                    max_ac = maxaccel * abs_scale
                if pos_mode:
                    pos_cmd = value * pos_scale
                    new_vel = follow_position(
                        pos_cmd, old_pos_cmd, accum, freq, max_freq, max_ac, dt, recip_dt
                    )
                    old_pos_cmd = pos_cmd
                else:
                    new_vel = follow_velocity(value * pos_scale, freq, max_freq, max_ac, dt)
                freq = new_vel
                target = int(freq * freqscale)
                deltalim = int(max_ac * accelscale)
            else:
                to_ch()
                if pos_mode:
                    ch.pos_cmd = value
                else:
                    ch.vel_cmd = value
                if k0 > 0:
                    comp.periodns = base
                comp.update_freq(servo)
                freq, old_pos_cmd = ch.freq, ch.old_pos_cmd
                target, deltalim, addval = ch.target_addval, ch.deltalim, ch.addval
                maxvel, maxaccel = ch.maxvel, ch.maxaccel
                steady = _steady(comp, ch, base, servo)
                if steady:
                    pos_scale = ch.pos_scale
                    abs_scale = abs(pos_scale)
                    min_step_period = float(ch.step_len + ch.step_space)
                    dt, recip_dt = comp.dt, comp.recip_dt
                    freqscale, accelscale = comp.freqscale, comp.accelscale
        m = k1 - k0
        a0 = addval
        if target >= a0:
            sgn = 1
            span = target - a0
        else:
            sgn = -1
            span = a0 - target
        d_eff = deltalim if deltalim != 0 else span
        # the chunk's closed form: addval_i = a0 + sgn*min(i*d_eff, span), i = 1..m
        if d_eff == 0:
            a_end = a0
            total = m * a0
        else:
            full = span // d_eff
            if m <= full:
                a_end = a0 + sgn * m * d_eff
                total = m * a0 + sgn * d_eff * (m * (m + 1) // 2)
            else:
                a_end = target
                total = m * a0 + sgn * (d_eff * (full * (full + 1) // 2) + span * (m - full))
        cls = a0 >= 0
        if (
            not ch.hold_dds
            and ch.enable
            and (a_end >= 0) == cls
            and -ONE_STEP <= a0 <= ONE_STEP
            and -ONE_STEP <= a_end <= ONE_STEP
            and (curr_dir == (1 if cls else -1) or (a0 == 0 and a_end == 0))
        ):
            step_len = ch.step_len
            append((k0, m, a0, sgn, d_eff, span, curr_dir, step_len, accum, state))
            accum1 = accum + total
            count1 = accum1 >> PICKOFF
            delta = count1 - (accum >> PICKOFF)
            if delta:
                steps_total += delta if delta > 0 else -delta
                hold = step_len + ch.dir_hold_dly
                pending = _Pending(
                    k0,
                    m,
                    accum,
                    a0,
                    sgn,
                    d_eff,
                    span,
                    count1,
                    (step_len, hold, hold + ch.dir_setup),
                )
                if phased:
                    state = (state + delta) % cycle
            accum = accum1
            addval = a_end
            continue
        # exact chunk: make the timers concrete, then run the reference make-pulses
        append((k0, m, a0, sgn, d_eff, span, curr_dir, ch.step_len, accum, state))
        if pending is not None:
            t_ref = _last_step(pending)
            t_vals = pending.loads
            pending = None
        elapsed = (k0 - 1 - t_ref) * base
        ch.timer1 = max(t_vals[0] - elapsed, 0)
        ch.timer2 = max(t_vals[1] - elapsed, 0)
        ch.timer3 = max(t_vals[2] - elapsed, 0)
        to_ch()
        inc = np.empty(m, dtype=np.int64)
        dirs = np.empty(m, dtype=np.int64)
        comp.periodns = base
        for i in range(m):
            before = ch.accum
            if make_pulses_channel(ch, base):
                steps_total += 1
            inc[i] = ch.accum - before
            dirs[i] = ch.curr_dir
        exact[len(desc) - 1] = (inc, dirs)
        accum, addval, curr_dir, state = ch.accum, ch.addval, ch.curr_dir, ch.state
        # timers after this chunk, relative to its last invocation
        t_vals = (ch.timer1, ch.timer2, ch.timer3)
        t_ref = k1 - 1

    to_ch()
    toggles, counts_at, counts_val = _pass2(
        kind.number, kind.outputs, kind.states, cycle, base, block_periods, desc, exact
    )
    run = InvocationRun(
        config=config,
        n_periods=n_periods,
        pins=kind.outputs,
        toggles=toggles,
        counts_at=counts_at,
        counts_val=counts_val,
        steps=steps_total,
        fast_chunks=len(desc) - len(exact),
        exact_chunks=len(exact),
    )
    run.final = final_state(comp)
    run.warnings = list(ch.warnings)
    return run


def _pass2(
    step_type: int,
    pins: tuple[str, ...],
    lut: tuple[int, ...],
    cycle: int,
    base: int,
    block_periods: int,
    desc: list[tuple[int, int, int, int, int, int, int, int, int, int]],
    exact: dict[int, tuple[np.ndarray, np.ndarray]],
) -> tuple[dict[str, np.ndarray], np.ndarray, np.ndarray]:
    """Per-period outputs from the chunk descriptors, a block of chunks at a time."""
    cols = np.array(desc, dtype=np.int64).reshape(-1, 10).T if desc else np.zeros((10, 0), np.int64)
    k0, m, a0, sgn, dd, span, dirs_c, lens, accum0s, state0s = cols
    c_m = m.tolist()
    nper_c = -(-lens // base)  # ceil(step_len / P): timer1 periods
    lut_arr = np.asarray(lut if lut else (0,), dtype=np.int64)

    tog_parts: dict[str, list[np.ndarray]] = {p: [] for p in pins}
    cnt_at_parts: list[np.ndarray] = []
    cnt_val_parts: list[np.ndarray] = []
    prev_out = 0
    prev_count = 0
    last_step = -(1 << 62)  # global index of the most recent step
    last_nper = 0
    n_chunks = len(desc)
    ci = 0
    while ci < n_chunks:
        cj = ci
        total = 0
        while cj < n_chunks and (total == 0 or total + c_m[cj] <= block_periods):
            total += c_m[cj]
            cj += 1
        sl = slice(ci, cj)
        mm = m[sl]
        start = int(k0[ci])
        offs = np.concatenate(([0], np.cumsum(mm)[:-1]))
        rep = np.repeat(np.arange(cj - ci), mm)
        i1 = np.arange(total, dtype=np.int64) - offs[rep] + 1
        inc = a0[sl][rep] + sgn[sl][rep] * np.minimum(i1 * dd[sl][rep], span[sl][rep])
        dirs = dirs_c[sl][rep]
        for c in range(ci, cj):
            if c in exact:
                e_inc, e_dir = exact[c]
                o = int(offs[c - ci])
                inc[o : o + len(e_inc)] = e_inc
                dirs[o : o + len(e_dir)] = e_dir
        accum0 = int(accum0s[ci])
        accum = np.cumsum(inc) + accum0
        prev = np.empty_like(accum)
        prev[0] = accum0
        prev[1:] = accum[:-1]
        step = ((accum ^ prev) & ONE_STEP) != 0
        idx = np.arange(start, start + total, dtype=np.int64)
        nper = nper_c[sl][rep]
        outbits: np.ndarray
        if step_type <= 1:
            ls = np.maximum.accumulate(np.where(step, idx, -(1 << 62)))
            has = ls > -(1 << 62)
            ls_local = np.where(has, ls - start, 0)
            np_at = np.where(has, nper[ls_local], last_nper)
            ls = np.where(has, ls, last_step)
            high = (idx - ls) < np_at
            if step.any():
                last_pos = int(np.flatnonzero(step)[-1])
                last_step = start + last_pos
                last_nper = int(nper[last_pos])
            if step_type == 0:
                outbits = high.astype(np.int64) | ((dirs < 0).astype(np.int64) << 1)
            else:
                neg = dirs < 0
                outbits = (high & ~neg).astype(np.int64) | ((high & neg).astype(np.int64) << 1)
        else:
            state0 = int(state0s[ci])
            state = (state0 + np.cumsum(np.where(step, dirs, 0))) % cycle
            outbits = lut_arr[state]
        oprev = np.empty_like(outbits)
        oprev[0] = prev_out
        oprev[1:] = outbits[:-1]
        changed = outbits ^ oprev
        for bit, pin in enumerate(pins):
            tog_parts[pin].append(np.flatnonzero((changed >> bit) & 1) + start)
        counts = accum >> PICKOFF
        cprev = np.empty_like(counts)
        cprev[0] = prev_count
        cprev[1:] = counts[:-1]
        at = np.flatnonzero(counts != cprev)
        cnt_at_parts.append(at + start)
        cnt_val_parts.append(counts[at])
        prev_out = int(outbits[-1])
        prev_count = int(counts[-1])
        ci = cj
    toggles = {
        p: (np.concatenate(v).astype(np.int64) if v else np.zeros(0, np.int64))
        for p, v in tog_parts.items()
    }
    counts_at = (
        np.concatenate(cnt_at_parts).astype(np.int64) if cnt_at_parts else np.zeros(0, np.int64)
    )
    counts_val = (
        np.concatenate(cnt_val_parts).astype(np.int64) if cnt_val_parts else np.zeros(0, np.int64)
    )
    return toggles, counts_at, counts_val
